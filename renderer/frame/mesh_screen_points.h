// Starts (u, v) for a face that no pixel near a rescued one shows, or for a
// sheet of a pixel's own face in front of its hit, from the face's map mesh
// projected on screen (the rescue and nearer-sheet passes).
#pragma once

#include <atomic>
#include <cmath>
#include <cstdint>
#include <memory>
#include <mutex>
#include <vector>

#include "renderer/frame/frame.h"
#include "renderer/frame/screen_geometry.h"

namespace nurbsrt {

// How far a search for faces near a pixel on screen goes (adjacent_far_faces,
// faces_near): at most max_faces faces, the nearest first, and only those whose
// mesh comes within reach_pixels of the pixel (pixels of the frame the
// MeshScreenPoints was made for). Each caller says why its bounds.
struct NearFaceBound {
    int max_faces;
    double reach_pixels;
};

// The point of the face's mesh nearest to the pixel on screen, its (u, v)
// interpolated in that triangle (Newton then starts within the mesh's deflection
// of the root). A face narrower than a pixel (a fillet or a blend seen edge-on)
// has mesh vertices many pixels apart along its length; the nearest vertex would
// start Newton that far away, across a thin trimmed strip, and miss.
// Each face's vertices are projected once per frame on first use, and bucketed
// in a screen grid when first searched, so that a query visits the triangles
// near the pixel instead of all of a face's thousands. Same arithmetic as
// projecting in place (X/D, Y/D of Camera::project_h); NaN marks a vertex
// behind the eye. Thread-safe.
class MeshScreenPoints {
public:
    explicit MeshScreenPoints(const FrameContext& c) : c_(c), faces_(new Entry[c.nfaces]) {}
    // Starts of face id for screen point sp, written to out: the (u, v) of the
    // face's mesh point nearest to sp (among triangles that contain sp, the
    // nearest to the eye), then of its nearest mesh vertex if that differs (near
    // a trim loop, a start interpolated across a triangle can lie where Newton
    // runs off the trimmed face, and the vertex, on the face, does not). Only
    // points in front of the eye count; returns how many starts (0 to 2). Exact
    // ties (equal distance and depth) go to the lowest triangle or vertex index,
    // so the answer does not depend on the grid.
    // max_d2: only a mesh within sqrt(max_d2) of sp (screen units) counts: 0
    // starts where it lies farther, and the search skips what lies beyond.
    int nearest_starts(uint32_t id, ScreenPoint sp, Vec2 out[2], double* screen_d2 = nullptr,
                       double max_d2 = HUGE_VAL) const;

    // The (u, v) of the face's mesh point nearest to the eye (least depth along
    // the view direction) among those within sqrt(max_d2) of sp on screen (max_d2
    // finite), and its depth; false if there is none. Exact for the mesh's
    // piecewise linear depth: a sheet in front of another of the same face (a
    // fold, whose near sheet's mesh may stop short of a pixel its surface covers).
    bool frontmost_point(uint32_t id, ScreenPoint sp, double max_d2, Vec2& uv, double& depth) const;

    // A pixel near a face's mesh: the (u, v) and depth of the mesh point nearest
    // to its centre on screen (of the triangles within reach, the one nearest to
    // the eye there).
    struct MeshPixel {
        size_t k;
        Vec2 uv;
        double depth;
    };
    // The pixels showing another face (`hits`: neither the background nor face
    // id) whose centre lies within `pixels` of the face's projected mesh on
    // screen, one each, ascending, appended to out; false (out as it was) where
    // that takes testing more than max_tested pixel centres (a face covering
    // much of the frame: the map shows it anyway).
    // `hit_t`: the frame's hit distances (+inf: none); a triangle behind the hit
    // at its centroid's pixel by more than `gap_footprints` pixel footprints
    // there is hidden and skipped (a face mostly behind others).
    bool pixels_near(uint32_t id, double pixels, size_t max_tested, const PixelArray<PixelHit>& hits,
                     const PixelArray<double>& hit_t, double gap_footprints, std::vector<MeshPixel>& out) const;

    // Starts on the part of the face's mesh nearer to the eye than max_depth
    // (the mesh clipped at that depth): the (u, v) of each of its sheets that
    // covers sp, nearest to the eye first (at most max_out), or where none does,
    // of its point nearest to sp on screen within sqrt(max_d2). Returns how many.
    int starts_in_front(uint32_t id, ScreenPoint sp, double max_d2, double max_depth, Vec2* out, int max_out) const;

    // A face that no pixel near sp shows, with its nearest_starts.
    struct FarFace {
        uint32_t id = 0;
        int nstarts = 0;
        Vec2 starts[2];
        double d2 = 0;  // squared screen distance of its mesh from sp
    };
    // The faces adjacent (PreparedFace::adjacent) to near[0..nn) that are not
    // among them, the bound.max_faces nearest to sp on screen first (a thin face between
    // the near faces lies at the pixel; a face with many neighbours, a hub or a
    // base plate, would otherwise fill the list with faces far away). Returns the
    // number written to out.
    // Faces whose mesh lies farther than bound.reach_pixels from sp are left
    // out, most of them by their screen box alone, without a scan.
    int adjacent_far_faces(const uint32_t* near, int nn, ScreenPoint sp, FarFace* out, NearFaceBound bound) const;

    // Any faces, not in exclude[0..ne), whose mesh lies within bound.reach_pixels of
    // sp on screen, nearest first (at most bound.max_faces; of the kMaxBoxCandidates
    // whose mesh box reaches sp nearest to the eye): a face seen through a gap
    // between faces that do not touch it, which neither the map nor adjacency
    // offers. Only faces whose mesh box comes nearer to the eye than max_depth
    // (the depth of frontmost_point) are considered. Returns the number written to out.
    int faces_near(ScreenPoint sp, const uint32_t* exclude, int ne, FarFace* out, NearFaceBound bound,
                   double max_depth = HUGE_VAL) const;

private:
    // A face's mesh box on screen (its 8 corners projected) and its least depth;
    // `around` where a corner lies behind the eye (the box may cover any point).
    struct ScreenBox {
        Vec2 lo{HUGE_VAL, HUGE_VAL}, hi{-HUGE_VAL, -HUGE_VAL};
        double near = HUGE_VAL;
        bool around = false, empty = true;
    };
    const std::vector<ScreenBox>& screen_boxes() const;
    mutable std::once_flag boxes_once_;
    mutable std::vector<ScreenBox> boxes_;
    // The screen boxes binned on a coarse uniform grid over the frame, for
    // faces_near: per cell the faces whose box overlaps it (clamped to the
    // frame's cells), as index ranges into one array (compressed rows); apart,
    // the faces whose box may cover any point (`around`). A box within reach
    // of a point overlaps a cell of the square around the point, so only those
    // cells' faces need the exact box test, not every face's.
    struct BoxGrid {
        int n = 0;  // cells per side
        double x0 = 0, y0 = 0, inv_cw = 1, inv_ch = 1;
        std::vector<uint32_t> begin, ids, around;
        int cell_x(double x) const;
        int cell_y(double y) const;
    };
    const BoxGrid& box_grid() const;
    mutable std::once_flag box_grid_once_;
    mutable BoxGrid box_grid_;
    struct Projected {
        Vec2 s;        // screen position (NaN behind the eye)
        double depth;  // along the view direction
    };
    // A uniform grid over the screen box of a face's projected mesh: per cell the
    // triangles whose screen box overlaps it and the vertices inside it, as
    // index ranges into one array each (compressed rows), ascending.
    struct Grid {
        int nx = 0, ny = 0;
        double x0 = 0, y0 = 0, cw = 1, ch = 1;
        std::vector<uint32_t> tri_begin, tris, vtx_begin, vtxs;
        int cell_x(double x) const;
        int cell_y(double y) const;
    };
    // std::call_once's work without its cost here: glibc's pthread_once ends
    // every first call with a futex wake system call, waiters or not, and a
    // frame makes hundreds of first uses. The flag is read with acquire order;
    // only a first use takes the entry's mutex (uncontended: no system call).
    // As with call_once, an init that throws leaves it undone.
    class Once {
    public:
        template <class F>
        void call(std::mutex& m, F&& init) {
            if (done_.load(std::memory_order_acquire)) return;
            const std::lock_guard<std::mutex> lock(m);
            if (done_.load(std::memory_order_relaxed)) return;
            init();
            done_.store(true, std::memory_order_release);
        }

    private:
        std::atomic<bool> done_{false};
    };
    // Built on first use, in two steps: the projection (and screen box) for any
    // face asked about, the grid for faces searched (adjacent_far_faces rejects
    // most candidates by their box alone).
    struct Entry {
        std::mutex m;
        Once once, grid_once;
        std::vector<Projected> pts;
        Vec2 lo{HUGE_VAL, HUGE_VAL}, hi{-HUGE_VAL, -HUGE_VAL};  // screen box of the points in front of the eye
        Grid grid;
    };
    const Entry& projected(uint32_t id) const;
    // The face's grid (no cells where no point is in front of the eye).
    const Grid& grid(uint32_t id) const;
    static bool usable_triangle(const FaceMesh& mesh, const std::vector<Projected>& pts, size_t t);
    // fn(t) for the usable triangles of face id that may lie within
    // sqrt(bound()) of p: those of its grid's cells near p (bound() is read
    // again as fn tightens it).
    template <class Bound, class Fn>
    void for_triangles_near(uint32_t id, Vec2 p, Bound&& bound, Fn&& fn) const {
        const Grid& g = grid(id);
        if (g.nx == 0) return;  // no usable triangle: nothing in front of the eye
        screen::for_near_cells(g, p, bound, [&](size_t cell) {
            for (uint32_t q = g.tri_begin[cell]; q < g.tri_begin[cell + 1]; ++q) fn(g.tris[q]);
        });
    }
    void build_grid(uint32_t id, Entry& e) const;
    const FrameContext& c_;
    const std::unique_ptr<Entry[]> faces_;
};

}  // namespace nurbsrt
