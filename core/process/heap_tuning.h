// Memory for frames: process-wide allocator settings for rendering many frames
// in one process (the CLI's bench, the service; call tune_heap_for_frames once
// from main, before any thread starts), and faulting in a large buffer's pages
// from several threads.
#pragma once

#include <cstddef>

namespace nurbsrt {

// A 512x512 frame allocates and frees ~40 MB of per-pixel buffers (hits, AOVs,
// image). glibc serves blocks above its mmap threshold (128 KiB, raised
// dynamically up to 32 MiB) with fresh mmap()s and trims the heap top above 2x
// that threshold, so every frame page-faulted its buffers in again (~20 % of a
// small frame's time). Keeps blocks up to 32 MiB (glibc's upper limit for the
// threshold; a 512x512 frame's largest buffer has 10 MB, and frames from about
// 900x900 on go back to mmap for their largest) in the heap, and the heap from
// shrinking while its free top is under 256 MiB, which later frames reuse.
// Returns false where the C library refused (not glibc).
bool tune_heap_for_frames();

// Faults in the whole pages inside [data, data + bytes) for writing (Linux 5.14+
// madvise(MADV_POPULATE_WRITE)), on the calling thread: the kernel zeroes fresh
// pages as it maps them, and threads that populate parts of one buffer zero it
// in parallel, where its first write would zero it page by page on one thread.
// The memory's contents are unchanged (fresh pages read as zero either way).
// Returns false where the kernel cannot (nothing done).
bool populate_pages(void* data, size_t bytes);

}  // namespace nurbsrt
