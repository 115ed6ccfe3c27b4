#include "core/process/heap_tuning.h"

#include <cstdlib>  // defines __GLIBC__ (through <features.h>) on glibc

#include <cstdint>

#if defined(__GLIBC__)
#include <malloc.h>
#endif
#if defined(__linux__)
#include <sys/mman.h>
#include <unistd.h>
#endif

namespace nurbsrt {

bool tune_heap_for_frames() {
#if defined(__GLIBC__)
    // glibc refuses thresholds above half its 64 MiB heap size (mallopt returns 0).
    constexpr int kMmapThreshold = 32 << 20;
    constexpr int kTrimThreshold = 256 << 20;
    return mallopt(M_MMAP_THRESHOLD, kMmapThreshold) == 1 && mallopt(M_TRIM_THRESHOLD, kTrimThreshold) == 1;
#else
    return false;
#endif
}

bool populate_pages(void* data, size_t bytes) {
#if defined(__linux__)
    // The value of the Linux UAPI (include/uapi/asm-generic/mman-common.h), for
    // C library headers older than the kernel.
#ifndef MADV_POPULATE_WRITE
    constexpr int MADV_POPULATE_WRITE = 23;
#endif
    static const uintptr_t page = static_cast<uintptr_t>(sysconf(_SC_PAGESIZE));
    const uintptr_t begin = (reinterpret_cast<uintptr_t>(data) + page - 1) & ~(page - 1);
    const uintptr_t end = (reinterpret_cast<uintptr_t>(data) + bytes) & ~(page - 1);
    if (end <= begin) return true;
    return madvise(reinterpret_cast<void*>(begin), end - begin, MADV_POPULATE_WRITE) == 0;
#else
    (void)data;
    (void)bytes;
    return false;
#endif
}

}  // namespace nurbsrt
