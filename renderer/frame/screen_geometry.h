// Screen-space geometry shared by MeshScreenPoints' queries
// (mesh_screen_points.cpp, mesh_screen_sheets.cpp): distances to points,
// segments, triangles and boxes on screen, and the walk over a grid's cells
// near a point. Internal to the renderer.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

#include "core/scene/scene.h"
#include "core/vec.h"

namespace nurbsrt::screen {

// Slack on cell bounds, relative to the cell size: a point's cell comes from a
// rounded division, so the cell's recomputed box may miss it by an ulp; the
// slack keeps such a cell in the search (visiting one more cell costs nothing).
constexpr double kCellSlack = 1e-9;

// The nearest point to p found so far, with its depth and (u, v).
struct NearestPoint {
    double d2 = HUGE_VAL, depth = HUGE_VAL;
    Vec2 uv;
    uint64_t key = std::numeric_limits<uint64_t>::max();
    bool found = false;
    // Nearer on screen wins; at equal distance (p inside several triangles: a
    // face folding over itself) the nearer to the eye, the sheet a ray meets
    // first; at equal depth too, the lower key (the triangle or vertex order),
    // whatever order the grid offers them in.
    void offer(double dist2, double z, Vec2 at, uint64_t k) {
        if (dist2 < d2 || (dist2 == d2 && (z < depth || (z == depth && k < key))))
            d2 = dist2, depth = z, uv = at, key = k, found = true;
    }
};

// Squared distance from p to segment ab, and the parameter t in [0, 1] of the nearest point.
inline double segment_distance2(Vec2 p, Vec2 a, Vec2 b, double& t) {
    const double ex = b.x - a.x, ey = b.y - a.y, len2 = ex * ex + ey * ey;
    t = len2 > 0 ? std::clamp(((p.x - a.x) * ex + (p.y - a.y) * ey) / len2, 0.0, 1.0) : 0.0;
    const double dx = a.x + t * ex - p.x, dy = a.y + t * ey - p.y;
    return dx * dx + dy * dy;
}

// The parameters [s0, s1] of the part of segment ab within sqrt(r2) of p;
// false if none: |a + s (b - a) - p|^2 <= r2, a quadratic in s, clipped to [0, 1].
inline bool segment_in_disk(Vec2 a, Vec2 b, Vec2 p, double r2, double& s0, double& s1) {
    const double ex = b.x - a.x, ey = b.y - a.y, fx = a.x - p.x, fy = a.y - p.y;
    const double A = ex * ex + ey * ey, B = fx * ex + fy * ey, C = fx * fx + fy * fy - r2;
    if (A == 0) {
        s0 = s1 = 0;
        return C <= 0;
    }
    const double disc = B * B - A * C;
    if (disc < 0) return false;
    const double root = std::sqrt(disc);
    s0 = std::max((-B - root) / A, 0.0);
    s1 = std::min((-B + root) / A, 1.0);
    return s0 <= s1;
}

inline Vec2 lerp(Vec2 a, Vec2 b, double t) { return {a.x + t * (b.x - a.x), a.y + t * (b.y - a.y)}; }

// Barycentric coordinates l of p in the screen triangle ABC; false if p lies
// outside it or the triangle is degenerate.
inline bool inside_triangle(Vec2 p, Vec2 A, Vec2 B, Vec2 C, double l[3]) {
    const double det = (B.y - C.y) * (A.x - C.x) + (C.x - B.x) * (A.y - C.y);
    if (det == 0) return false;
    l[0] = ((B.y - C.y) * (p.x - C.x) + (C.x - B.x) * (p.y - C.y)) / det;
    l[1] = ((C.y - A.y) * (p.x - C.x) + (A.x - C.x) * (p.y - C.y)) / det;
    l[2] = 1.0 - l[0] - l[1];
    return l[0] >= 0 && l[1] >= 0 && l[2] >= 0;
}

// The depth and the (u, v) at barycentric coordinates l of a mesh triangle.
inline double interpolated_depth(const double l[3], const double z[3]) {
    return l[0] * z[0] + l[1] * z[1] + l[2] * z[2];
}
inline Vec2 interpolated_uv(const double l[3], const FaceMesh& mesh, const uint32_t* idx) {
    const Vec2 &a = mesh.uv[idx[0]], &b = mesh.uv[idx[1]], &c = mesh.uv[idx[2]];
    return {l[0] * a.x + l[1] * b.x + l[2] * c.x, l[0] * a.y + l[1] * b.y + l[2] * c.y};
}

// Squared distance from p to the box [x0, x1] x [y0, y1] (0 inside).
inline double box_distance2(Vec2 p, double x0, double x1, double y0, double y1) {
    const double bx = std::max({x0 - p.x, 0.0, p.x - x1}), by = std::max({y0 - p.y, 0.0, p.y - y1});
    return bx * bx + by * by;
}

// Calls fn(cell) for the cells of g in square rings around p's cell (p clamped
// into the grid), each cell whose box lies within sqrt(bound()) of p, and stops
// at the first ring that lies wholly farther: every cell of ring r is at least
// r - 1 cells from p along one axis. bound() is read again as fn tightens it.
template <class Grid, class Bound, class Fn>
inline void for_near_cells(const Grid& g, Vec2 p, Bound&& bound, Fn&& fn) {
    const int cx = g.cell_x(p.x), cy = g.cell_y(p.y);
    const int reach_x = std::max(cx, g.nx - 1 - cx), reach_y = std::max(cy, g.ny - 1 - cy);
    const double slack = kCellSlack * (g.cw + g.ch);
    for (int r = 0; r <= std::max(reach_x, reach_y); ++r) {
        if (r > 1) {
            // Ring r reaches r cells away only along the axes the grid extends that far.
            const double step = std::min(r <= reach_x ? g.cw : HUGE_VAL, r <= reach_y ? g.ch : HUGE_VAL);
            const double gap = std::max((r - 1) * step - slack, 0.0);
            if (gap * gap > bound()) return;
        }
        for (int y = std::max(cy - r, 0); y <= std::min(cy + r, g.ny - 1); ++y) {
            const bool full_row = y == cy - r || y == cy + r;
            for (int x = cx - r; x <= cx + r; x += full_row ? 1 : 2 * r) {
                if (x < 0 || x >= g.nx) continue;
                const double x0 = g.x0 + x * g.cw, y0 = g.y0 + y * g.ch;
                if (box_distance2(p, x0 - slack, x0 + g.cw + slack, y0 - slack, y0 + g.ch + slack) > bound()) continue;
                fn(y * g.nx + x);
            }
        }
    }
}

}  // namespace nurbsrt::screen
