// Point-in-trim-region test of a face in (u,v): even-odd rule over all of the
// face's trim loops (scene.h: loop orientation does not matter), accelerated by
// a uniform grid so that a query touches only the few edges near the point.
//
// Structure (built once per face): a uniform grid over the loops' (u,v) box;
// every cell lists the loop edges that overlap it (compressed rows), and stores
// whether its centre is inside (computed per grid row by one scanline through
// the cell centres). A query in cell c counts the crossings of the segment from
// c's centre to the point with c's edges: inside = centre_inside XOR odd count.
// Only edges overlapping the cell can cross that segment, since both ends lie
// in the (convex) cell. A cell whose centre lies (nearly) on an edge uses another
// reference point of the cell instead. Vertices lying exactly on the segment's line are
// classified by a half-open side rule, so shared vertices are counted once.
// Points outside the grid are outside every loop.
#pragma once

#include <cmath>
#include <cstdint>
#include <vector>

#include "core/scene/scene.h"

namespace nurbsrt {

class TrimTester {
public:
    TrimTester() = default;  // untrimmed: everything inside
    explicit TrimTester(const std::vector<TrimLoop>& loops, int max_cells_per_side = 256);

    bool trimmed() const { return !edges_.empty(); }
    bool inside(Vec2 p) const;
    // Distance from p to the nearest loop edge when it is <= max_d, else +inf
    // (looks only at the grid cells within max_d of p). Untrimmed: +inf.
    double boundary_distance(Vec2 p, double max_d) const;

    int cells_u() const { return nu_; }
    int cells_v() const { return nv_; }
    size_t edge_count() const { return edges_.size(); }
    // Heap memory of the grid and edges (for caches that bound their size).
    size_t memory_bytes() const {
        return edges_.capacity() * sizeof(Edge) + (cell_start_.capacity() + cell_edges_.capacity()) * sizeof(uint32_t) +
               centre_inside_.capacity() + ref_.capacity() * sizeof(Vec2);
    }

private:
    struct Edge {
        double ax, ay, bx, by;
    };
    struct Bounds {
        double lo_x = HUGE_VAL, lo_y = HUGE_VAL, hi_x = -HUGE_VAL, hi_y = -HUGE_VAL;
    };
    // The constructor's stages, in order: the loops' edges (zero-length ones
    // dropped); a grid of about 2 cells per edge over their box; each edge into
    // the cells it overlaps; the cell centres' inside state by scanlines; and
    // the reference points that lie (nearly) on an edge moved off it.
    Bounds collect_edges(const std::vector<TrimLoop>& loops);  // returns the edges' box
    void size_grid(const Bounds& box, int max_cells_per_side);
    void bin_edges();
    void classify_cell_centres();
    void settle_reference_points(const std::vector<TrimLoop>& loops);
    std::vector<Edge> edges_;
    double u0_ = 0, v0_ = 0, du_ = 1, dv_ = 1;  // grid origin and cell size
    int nu_ = 0, nv_ = 0;
    std::vector<uint32_t> cell_start_;  // nu*nv + 1 offsets into cell_edges_
    std::vector<uint32_t> cell_edges_;
    std::vector<uint8_t> centre_inside_;  // inside state of each cell's reference point
    std::vector<Vec2> ref_;  // the cell centre, or another point of the cell if an edge passes too near the centre
};

// Reference: even-odd crossing count over every edge of every loop (slow).
bool inside_even_odd_bruteforce(const std::vector<TrimLoop>& loops, Vec2 p);

}  // namespace nurbsrt
