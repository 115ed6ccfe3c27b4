// What the passes of one frame share (render.cpp runs them in order): the frame's
// inputs (FrameContext), its per-pixel buffers (FrameBuffers), the per-pixel
// result of a solve (PixelHit), the neighbourhood walk, row-parallel loops with
// progress and cancellation.
#pragma once

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <atomic>
#include <cstdint>
#include <functional>
#include <cmath>
#include <limits>
#include <memory>
#include <new>
#include <type_traits>
#include <mutex>
#include <type_traits>
#include <utility>
#include <vector>

#include "renderer/camera.h"
#include "core/process/heap_tuning.h"
#include "renderer/frame/face_cameras.h"
#include "renderer/map/preliminary_map.h"
#include "renderer/solve/prepared_data.h"
#include "renderer/render.h"
#include "core/scene/scene.h"

namespace nurbsrt {

// RenderOptions::cancel: blocks of rows are skipped once it is set, and the pass
// then ends with Error(canceled) (a partial pass is never used).
inline bool canceled(const RenderOptions& o) { return o.cancel && o.cancel->load(std::memory_order_relaxed); }
void throw_if_canceled(const RenderOptions& o);

// Per-pixel solve result of a pass.
struct PixelHit {
    uint32_t face = 0;  // 0: no hit
    float u = 0, v = 0;
    // Unit shading normal (oriented by the face) from the solve's last partials;
    // (0, 0, 0) where they were degenerate: shading then takes surface_normal's limits.
    float nx = 0, ny = 0, nz = 0;
    double t = std::numeric_limits<double>::infinity();
    uint8_t iterations = 0;
};

// How one solve of a pixel ended (FrameBuffers::outcome for the primary solve):
// the Newton status, or converged outside the trim (kTrimmed), or outside it but
// within the face's trim-tolerance band (kNearTrim, rescue only).
enum Outcome : uint8_t { kNone, kConverged, kDiverged, kSingular, kMaxIter, kLeftDomain, kBehind, kTrimmed, kNearTrim };

// Newton found no point of the surface (as opposed to one behind the eye or
// outside the trim): another start may still find one.
inline bool newton_failed(Outcome o) { return o == kDiverged || o == kSingular || o == kMaxIter || o == kLeftDomain; }

// Which rescue gave a pixel its hit (RenderStats::rescue_*).
enum RescueKind : uint8_t { kNoRescue, kRescueNeighbour, kRescueSilhouette, kRescueGeneral, kRescueTrimTol };

// Fraction-done reporting for RenderOptions::progress: rows are counted with one
// relaxed atomic add; a thread that crosses the next ~2% mark reports, serialized
// by a mutex it only try-locks (a busy reporter just skips one report).
class Progress {
public:
    Progress(const std::function<void(double)>& fn, int64_t total)
        : fn_(fn), total_(std::max<int64_t>(total, 1)), step_(std::max<int64_t>(total_ / 50, 1)), next_(step_) {}
    void add(int64_t n);
    void finish();

private:
    void report(double f);
    const std::function<void(double)>& fn_;
    const int64_t total_, step_;
    std::atomic<int64_t> done_{0}, next_;
    std::mutex m_;
    double last_ = 0;
};

// The inputs of one frame, shared read-only by its passes.
struct FrameContext {
    const PreparedScene& prepared;
    const Scene& scene;
    const Camera& camera;
    // Per face, the camera its solves and mesh projections use: `camera` itself
    // but where RenderOptions::face_offsets moves the face (face_cameras.h).
    const FaceCameras& face_cameras;
    const PreliminaryMap& map;
    const RenderOptions& options;
    tbb::task_arena& arena;
    Progress& progress;
    int width, height;
    uint32_t nfaces;
    // The box of the faces where the frame shows them (moved by the offsets).
    BBox bbox;
    // 2 / height, once: pixel_footprint runs per pixel pair in several passes,
    // where a division per call (the compiler may not turn x / h into a product)
    // costs far more. A power-of-two height keeps every product exact.
    double two_over_height = 2.0 / height;

    const Camera& camera_of(uint32_t id) const { return face_cameras.of(id); }
    bool in_frame(int i, int j) const { return i >= 0 && j >= 0 && i < width && j < height; }
    size_t pixels() const { return static_cast<size_t>(width) * height; }
    // The size of one pixel in model units at hit distance t (screen units span
    // 2 over the height; depth along the view direction for orthographic views,
    // where it does not matter).
    double pixel_footprint(double t) const { return camera.image_to_model_scale(t) * two_over_height; }
    // A distance of `pixels` in screen units (ScreenPoint), which span 2 over the height.
    double screen_distance(double pixels) const { return 2.0 * pixels / height; }
    // The depth along the view direction (the map mesh's measure) `footprints`
    // pixel footprints behind a hit at distance t on the ray through sp.
    double depth_behind(double t, double footprints, ScreenPoint sp) const {
        return (t + footprints * pixel_footprint(t)) / camera.hit_distance_from_depth(1.0, sp);
    }
};

// Frame-sized buffers are filled in blocks of this many bytes with a cancel check
// between blocks: filling fresh pages (above glibc's mmap threshold) is mostly the
// kernel zeroing them, ~0.8 s per GiB on one thread of a 2-core machine, and a
// 25-Mpixel frame has over 3 GiB that a canceled render must not go on filling.
inline constexpr size_t kCancelBlockBytes = size_t(64) << 20;
// From this size on a buffer's storage is fresh pages (glibc's mmap threshold as
// tune_heap_for_frames sets it), and the frame's threads fault them in together
// (populate_pages) before the fill: ~2x faster on 2 cores.
inline constexpr size_t kPopulateMinBytes = size_t(32) << 20;

// Faults in the pages of v's storage for n elements, in blocks spread over the
// frame's threads; nothing for small buffers or where the kernel cannot.
template <class T>
void populate_storage(std::vector<T>& v, size_t n, const FrameContext& c) {
    v.reserve(n);
    const size_t bytes = n * sizeof(T);
    if (bytes < kPopulateMinBytes) return;
    char* data = reinterpret_cast<char*>(v.data());
    const size_t blocks = (bytes + kCancelBlockBytes - 1) / kCancelBlockBytes;
    c.arena.execute([&] {
        tbb::parallel_for(size_t(0), blocks, [&](size_t b) {
            if (canceled(c.options)) return;
            const size_t begin = b * kCancelBlockBytes;
            populate_pages(data + begin, std::min(kCancelBlockBytes, bytes - begin));
        });
    });
}

// Grows v from empty to n elements in blocks of kCancelBlockBytes, append(end)
// growing it to `end`; throws Error(canceled) between blocks.
template <class T, class Append>
void grow_cancelable(std::vector<T>& v, size_t n, const FrameContext& c, Append&& append) {
    v.clear();
    populate_storage(v, n, c);
    const size_t block = std::max<size_t>(kCancelBlockBytes / sizeof(T), 1);
    while (v.size() < n) {
        throw_if_canceled(c.options);
        append(std::min(n, v.size() + block));
    }
}

// v = n copies of value, in blocks (grow_cancelable).
template <class T>
void assign_cancelable(std::vector<T>& v, size_t n, const T& value, const FrameContext& c) {
    grow_cancelable(v, n, c, [&](size_t end) { v.resize(end, value); });
}

// Per-pixel storage that the frame's first pass writes in full before anything
// reads it, allocated without an initial fill: std::vector's serial fill of a
// 512x512 frame's 10.5 MB of hits took milliseconds, while the primary pass
// writes each element once, in parallel, next to its solve. The elements are
// aggregates of scalars (implicit-lifetime types: C++20 [intro.object]), so the
// raw storage holds them once written.
template <class T>
class PixelArray {
    static_assert(std::is_trivially_copyable_v<T> && std::is_trivially_destructible_v<T>);

public:
    explicit PixelArray(size_t n)
        : n_(n),
          data_(static_cast<T*>(::operator new(std::max<size_t>(n, 1) * sizeof(T), std::align_val_t(alignof(T))))) {}
    ~PixelArray() { ::operator delete(data_, std::align_val_t(alignof(T))); }
    PixelArray(const PixelArray&) = delete;
    PixelArray& operator=(const PixelArray&) = delete;
    T& operator[](size_t k) { return data_[k]; }
    const T& operator[](size_t k) const { return data_[k]; }
    T* data() { return data_; }
    const T* data() const { return data_; }
    size_t size() const { return n_; }

private:
    size_t n_;
    T* data_;
};

// The frame's per-pixel arrays, row-major like the map (PreliminaryMap::index).
struct FrameBuffers {
    explicit FrameBuffers(const FrameContext& c) : hits(c.pixels()), depth(c.pixels()) {
        assign_cancelable(outcome, c.pixels(), uint8_t(kNone), c);
        assign_cancelable(iterations, c.pixels(), uint8_t(0), c);
        assign_cancelable(rescued, c.pixels(), uint8_t(kNoRescue), c);
    }
    // The hit: the primary solve's (written for every pixel, PixelHit{} where
    // the map shows no face), then the rescue and nearer-sheet passes' (face 0:
    // none). Each of these passes reads the previous state and applies its
    // changes after it (a handful of pixels), so no second frame-sized copy.
    PixelArray<PixelHit> hits;
    // hits[k].t where hits[k] is a hit, +inf elsewhere: the depths alone (8
    // bytes a pixel instead of the hits' 40), for the tests that read every
    // pixel's neighbourhood (the nearer-sheet pass's spikes). Written with the
    // hits (set, update_depth).
    PixelArray<double> depth;
    void set(size_t k, const PixelHit& h) {
        hits[k] = h;
        update_depth(k);
    }
    void update_depth(size_t k) { depth[k] = hits[k].face ? hits[k].t : std::numeric_limits<double>::infinity(); }
    std::vector<uint8_t> outcome;     // Outcome of the primary solve; kNone where the map has no face
    std::vector<uint8_t> iterations;  // Newton steps of the primary solve (its statistics)
    std::vector<uint8_t> rescued;     // RescueKind of the pixel's hit
};

// Calls fn(ni, nj) for every pixel of the (2 radius + 1)^2 square around (i, j)
// inside the width x height frame, the pixel itself included, rows top to bottom, each left to
// right (the order decides which start is tried first, so it is fixed). A fn that
// returns bool stops the walk by returning false.
template <class F>
void for_each_neighbour(int width, int height, int i, int j, int radius, F&& fn) {
    const int j1 = std::min(j + radius, height - 1), i1 = std::min(i + radius, width - 1);
    for (int nj = std::max(j - radius, 0); nj <= j1; ++nj)
        for (int ni = std::max(i - radius, 0); ni <= i1; ++ni) {
            if constexpr (std::is_same_v<std::invoke_result_t<F&, int, int>, bool>) {
                if (!fn(ni, nj)) return;
            } else {
                fn(ni, nj);
            }
        }
}

template <class F>
void for_each_neighbour(const FrameContext& c, int i, int j, int radius, F&& fn) {
    for_each_neighbour(c.width, c.height, i, j, radius, std::forward<F>(fn));
}

// Rows of the frame in parallel, in blocks of kRowGrain rows (a block is the unit
// of cancellation and progress), fn(j) per row.
template <class F>
void parallel_rows(const FrameContext& c, bool report_progress, F&& fn) {
    // Small blocks balance the uneven cost of rows (rows across silhouettes and
    // cracks need the rescue) between threads, and bound the work done after a cancel.
    constexpr int kRowGrain = 4;
    c.arena.execute([&] {
        tbb::parallel_for(tbb::blocked_range<int>(0, c.height, kRowGrain), [&](const tbb::blocked_range<int>& r) {
            if (canceled(c.options)) return;
            for (int j = r.begin(); j < r.end(); ++j) fn(j);
            if (report_progress) c.progress.add(r.end() - r.begin());
        });
    });
}

}  // namespace nurbsrt
