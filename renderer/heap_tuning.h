// Process-wide allocator settings for rendering many frames in one process (the
// CLI's bench, the service). Call once from main, before any thread starts.
#pragma once

namespace nurbsrt {

// A 512x512 frame allocates and frees ~40 MB of per-pixel buffers (hits, AOVs,
// image). glibc serves blocks above its mmap threshold (128 KiB, raised
// dynamically up to 32 MiB) with fresh mmap()s and trims the heap top above 2x
// that threshold, so every frame page-faulted its buffers in again: ~20 % of a
// 512x512 frame of the mobile-phone scene (`nurbsrt_bench`, 95 ms -> 77 ms with
// the settings of this function). Keeps blocks up to 32 MiB (glibc's upper limit
// for the threshold; a 512x512 frame's largest buffer has 10 MB, and frames from
// about 900x900 on go back to mmap for their largest) in the heap, and the heap
// from shrinking while its free top is under 256 MiB, which later frames reuse.
// Returns false where the C library refused (not glibc).
bool tune_heap_for_frames();

}  // namespace nurbsrt
