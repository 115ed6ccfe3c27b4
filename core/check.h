// Invariant checks in the manner of pbrt-v4's CHECK and DCHECK. A broken
// invariant is a bug of ours, never bad input (input is refused at the edge with
// its own error codes). NURBSRT_CHECK is always on and throws Error(internal)
// naming the condition and the place: pbrt aborts, but a service must answer the
// one request 500 and keep serving the others. NURBSRT_DCHECK is the same in
// debug builds and compiles to nothing in release builds, for per-pixel loops.
#pragma once

namespace nurbsrt {

// Throws Error(internal): "invariant broken: COND (FILE:LINE)".
[[noreturn]] void check_failed(const char* condition, const char* file, int line);

}  // namespace nurbsrt

#define NURBSRT_CHECK(cond) ((cond) ? (void)0 : ::nurbsrt::check_failed(#cond, __FILE__, __LINE__))
#ifdef NDEBUG
#define NURBSRT_DCHECK(cond) ((void)0)
#else
#define NURBSRT_DCHECK(cond) NURBSRT_CHECK(cond)
#endif
