#include "renderer/heap_tuning.h"

#include <cstdlib>  // defines __GLIBC__ (through <features.h>) on glibc

#if defined(__GLIBC__)
#include <malloc.h>
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

}  // namespace nurbsrt
