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
#include <mutex>
#include <type_traits>
#include <utility>
#include <vector>

#include "renderer/camera.h"
#include "renderer/preliminary_map.h"
#include "renderer/prepared_scene.h"
#include "renderer/render.h"
#include "renderer/scene.h"

namespace nurbsrt {

// Per-pixel solve result of a pass.
struct PixelHit {
    uint32_t face = 0;       // 0: no hit
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

// Which rescue gave a pixel its hit (RenderStats::rescue_*).
enum RescueKind : uint8_t { kNoRescue, kRescueNeighbour, kRescueSilhouette, kRescueGeneral, kRescueTrimTol };

// The frame's per-pixel arrays, row-major like the map (PreliminaryMap::index).
struct FrameBuffers {
    explicit FrameBuffers(size_t npx) : first(npx), outcome(npx, kNone), rescued(npx, kNoRescue) {}
    std::vector<PixelHit> first;    // the primary solve's hit (face 0: none)
    std::vector<uint8_t> outcome;   // Outcome of the primary solve; kNone where the map has no face
    std::vector<PixelHit> hits;     // the final hit: `first`, then the rescue and nearer-sheet passes
    std::vector<uint8_t> rescued;   // RescueKind of the pixel's hit
};

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

// RenderOptions::cancel: blocks of rows are skipped once it is set, and the pass
// then ends with Error(canceled) (a partial pass is never used).
inline bool canceled(const RenderOptions& o) { return o.cancel && o.cancel->load(std::memory_order_relaxed); }
void throw_if_canceled(const RenderOptions& o);

// The inputs of one frame, shared read-only by its passes.
struct FrameContext {
    const PreparedScene& prepared;
    const Scene& scene;
    const Camera& camera;
    const PreliminaryMap& map;
    const RenderOptions& options;
    tbb::task_arena& arena;
    Progress& progress;
    int width, height;
    uint32_t nfaces;

    bool in_frame(int i, int j) const { return i >= 0 && j >= 0 && i < width && j < height; }
    size_t pixels() const { return static_cast<size_t>(width) * height; }
};

// Starts (u, v) for a face that no pixel near this one shows: the point of the
// face's mesh nearest to the pixel on screen, its (u, v) interpolated in that
// triangle (Newton then starts within the mesh's deflection of the root). A
// face narrower than a pixel (a fillet or a blend seen edge-on) has mesh vertices
// many pixels apart along its length; the nearest vertex would start Newton that
// far away, across a thin trimmed strip, and miss. Each face's vertices are
// projected once per face and frame on first use, not once per pixel: the scan is
// O(triangles) and a face of the ducks has ~8000 (`nurbsrt bench`). Same
// arithmetic as projecting in place (X/D, Y/D of Camera::project_h); NaN marks a
// vertex behind the eye. Thread-safe.
class MeshScreenPoints {
public:
    explicit MeshScreenPoints(const FrameContext& c) : c_(c), faces_(new Entry[c.nfaces]) {}
    // Starts of face id for screen point sp, written to out: the (u, v) of the
    // face's mesh point nearest to sp (among triangles that contain sp, the
    // nearest to the eye), then of its nearest mesh vertex if that differs (near
    // a trim loop, a start interpolated across a triangle can lie where Newton
    // runs off the trimmed face, and the vertex, on the face, does not). Only
    // points in front of the eye count; returns how many starts (0 to 2).
    int nearest_starts(uint32_t id, ScreenPoint sp, Vec2 out[2], double* screen_d2 = nullptr) const;

    // A face that no pixel near sp shows, with its nearest_starts.
    struct FarFace {
        uint32_t id = 0;
        int nstarts = 0;
        Vec2 starts[2];
        double d2 = 0;  // squared screen distance of its mesh from sp
    };
    // The faces adjacent (PreparedFace::adjacent) to near[0..nn) that are not
    // among them, the max_out nearest to sp on screen first (a thin face between
    // the near faces lies at the pixel; a face with many neighbours, a hub or a
    // base plate, would otherwise fill the list with faces far away). Returns the
    // number written to out.
    // Faces whose mesh lies farther than sqrt(max_d2) from sp (screen units) are
    // left out, most of them by their screen box alone, without a scan.
    int adjacent_far_faces(const uint32_t* near, int nn, ScreenPoint sp, FarFace* out, int max_out,
                           double max_d2 = HUGE_VAL) const;

private:
    struct Projected {
        Vec2 s;        // screen position (NaN behind the eye)
        double depth;  // along the view direction
    };
    struct Entry {
        std::once_flag once;
        std::vector<Projected> pts;
        Vec2 lo{HUGE_VAL, HUGE_VAL}, hi{-HUGE_VAL, -HUGE_VAL};  // screen box of the points in front of the eye
    };
    const Entry& projected(uint32_t id) const;
    const FrameContext& c_;
    const std::unique_ptr<Entry[]> faces_;
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
