// Grid-accelerated even-odd trim test (see trim.h).
#include "core/scene/trim.h"

#include <algorithm>
#include <cmath>

namespace nurbsrt {

namespace {

inline double orient(double ax, double ay, double bx, double by, double cx, double cy) {
    return (bx - ax) * (cy - ay) - (by - ay) * (cx - ax);
}

// Does the closed segment a-b overlap the closed box [x0,x1] x [y0,y1]?
// (separating axes: the box's two axes and the segment's normal)
inline bool segment_overlaps_box(double ax, double ay, double bx, double by, double x0, double y0, double x1,
                                 double y1) {
    if (std::max(ax, bx) < x0 || std::min(ax, bx) > x1 || std::max(ay, by) < y0 || std::min(ay, by) > y1) return false;
    const double s0 = orient(ax, ay, bx, by, x0, y0), s1 = orient(ax, ay, bx, by, x1, y0);
    const double s2 = orient(ax, ay, bx, by, x0, y1), s3 = orient(ax, ay, bx, by, x1, y1);
    return !((s0 > 0 && s1 > 0 && s2 > 0 && s3 > 0) || (s0 < 0 && s1 < 0 && s2 < 0 && s3 < 0));
}

// Squared distance from p to the closed segment a-b (to a where a = b). Squared:
// the callers compare it with a squared tolerance, or take one root at the end
// (std::hypot per edge was a libm call each).
inline double segment_distance2(double ax, double ay, double bx, double by, Vec2 p) {
    const double ex = bx - ax, ey = by - ay, len2 = ex * ex + ey * ey;
    const double s = len2 > 0 ? std::clamp(((p.x - ax) * ex + (p.y - ay) * ey) / len2, 0.0, 1.0) : 0.0;
    const double dx = ax + s * ex - p.x, dy = ay + s * ey - p.y;
    return dx * dx + dy * dy;
}

}  // namespace

bool inside_even_odd_bruteforce(const std::vector<TrimLoop>& loops, Vec2 p) {
    bool in = false;
    for (const TrimLoop& loop : loops) {
        const size_t n = loop.points.size();
        for (size_t k = 0, l = n - 1; k < n; l = k++) {
            const Vec2 a = loop.points[l], b = loop.points[k];
            if ((a.y > p.y) != (b.y > p.y) && p.x < a.x + (p.y - a.y) * (b.x - a.x) / (b.y - a.y)) in = !in;
        }
    }
    return in;
}

TrimTester::TrimTester(const std::vector<TrimLoop>& loops, int max_cells_per_side) {
    const Bounds box = collect_edges(loops);
    if (edges_.empty()) return;
    size_grid(box, max_cells_per_side);
    bin_edges();
    classify_cell_centres();
    settle_reference_points(loops);
}

TrimTester::Bounds TrimTester::collect_edges(const std::vector<TrimLoop>& loops) {
    Bounds b;
    size_t points = 0;
    for (const TrimLoop& loop : loops) points += loop.points.size();
    edges_.reserve(points);  // at most one edge a point (loops are sampled finely: thousands)
    for (const TrimLoop& loop : loops) {
        const size_t n = loop.points.size();
        if (n < 2) continue;
        for (size_t k = 0, l = n - 1; k < n; l = k++) {
            const Vec2 p = loop.points[l], q = loop.points[k];
            if (p.x == q.x && p.y == q.y) continue;
            edges_.push_back({p.x, p.y, q.x, q.y});
            b.lo_x = std::min({b.lo_x, p.x, q.x});
            b.hi_x = std::max({b.hi_x, p.x, q.x});
            b.lo_y = std::min({b.lo_y, p.y, q.y});
            b.hi_y = std::max({b.hi_y, p.y, q.y});
        }
    }
    return b;
}

void TrimTester::size_grid(const Bounds& b, int max_cells_per_side) {
    const double lo_x = b.lo_x, lo_y = b.lo_y, hi_x = b.hi_x, hi_y = b.hi_y;
    // About 2 cells per edge, as square as the box allows. The box is grown by an
    // odd fraction so that cell centres rarely coincide with exact CAD coordinates.
    const double w0 = std::max(hi_x - lo_x, 1e-12), h0 = std::max(hi_y - lo_y, 1e-12);
    // (Asymmetric, so the middle cell's centre is not the box's midpoint either.)
    const double gx = 0.0123457 * w0 + 1e-12, gy = 0.0123457 * h0 + 1e-12;
    u0_ = lo_x - gx;
    v0_ = lo_y - 1.7071 * gy;
    const double w = w0 + 2.4142 * gx, h = h0 + 2.7071 * gy;
    const double cells = std::clamp(2.0 * edges_.size(), 1.0, double(max_cells_per_side) * max_cells_per_side);
    nu_ = std::clamp(static_cast<int>(std::ceil(std::sqrt(cells * w / h))), 1, max_cells_per_side);
    nv_ = std::clamp(static_cast<int>(std::ceil(cells / nu_)), 1, max_cells_per_side);
    du_ = w / nu_;
    dv_ = h / nv_;
}

// Each edge into the cells it overlaps (two passes: count, then fill).
void TrimTester::bin_edges() {
    // The grid in locals: the stores into the uint32_t / uint8_t arrays below
    // may alias the members as far as the compiler knows, which made it reload
    // them in the inner loops.
    const double u0 = u0_, v0 = v0_, du = du_, dv = dv_;
    const int nu = nu_, nv = nv_;
    const size_t ncell = static_cast<size_t>(nu) * nv;
    cell_start_.assign(ncell + 1, 0);
    auto for_cells = [&](const Edge& e, auto&& fn) {
        const int i0 = std::clamp(static_cast<int>((std::min(e.ax, e.bx) - u0) / du), 0, nu - 1);
        const int i1 = std::clamp(static_cast<int>((std::max(e.ax, e.bx) - u0) / du), 0, nu - 1);
        const int j0 = std::clamp(static_cast<int>((std::min(e.ay, e.by) - v0) / dv), 0, nv - 1);
        const int j1 = std::clamp(static_cast<int>((std::max(e.ay, e.by) - v0) / dv), 0, nv - 1);
        for (int j = j0; j <= j1; ++j)
            for (int i = i0; i <= i1; ++i) {
                const double x0 = u0 + i * du, y0 = v0 + j * dv;
                // Slightly enlarged cell: floating-point cell assignment of the query never misses an edge.
                const double ex = 1e-9 * du, ey = 1e-9 * dv;
                if (segment_overlaps_box(e.ax, e.ay, e.bx, e.by, x0 - ex, y0 - ey, x0 + du + ex, y0 + dv + ey))
                    fn(static_cast<size_t>(j) * nu + i);
            }
    };
    for (const Edge& e : edges_) for_cells(e, [&](size_t c) { ++cell_start_[c + 1]; });
    for (size_t c = 0; c < ncell; ++c) cell_start_[c + 1] += cell_start_[c];
    cell_edges_.resize(cell_start_[ncell]);
    std::vector<uint32_t> fill(cell_start_.begin(), cell_start_.end() - 1);
    for (uint32_t k = 0; k < edges_.size(); ++k) for_cells(edges_[k], [&](size_t c) { cell_edges_[fill[c]++] = k; });
}

// Inside state of the cell centres: one scanline per grid row (even-odd with
// the same half-open rule as the brute-force test).
void TrimTester::classify_cell_centres() {
    const double u0 = u0_, v0 = v0_, du = du_, dv = dv_;  // locals, as in bin_edges
    const int nu = nu_, nv = nv_;
    const size_t ncell = static_cast<size_t>(nu) * nv;
    centre_inside_.assign(ncell, 0);
    ref_.resize(ncell);
    for (int j = 0; j < nv; ++j)
        for (int i = 0; i < nu; ++i) ref_[static_cast<size_t>(j) * nu + i] = {u0 + (i + 0.5) * du, v0 + (j + 0.5) * dv};
    // The crossings of each row's centre line, bucketed by row (two passes:
    // count, then fill): an edge crosses only the rows between its end points,
    // and testing every edge on every row dominated prepare() on finely sampled
    // loops. rows_of gives a range at least one row wider each way (by
    // truncation: the edges lie above v0, and std::floor is a library call on
    // the baseline target); the test itself decides, as it did per row.
    // decides, as it did per row.
    auto row_y = [&](int j) { return v0 + (j + 0.5) * dv; };
    auto crosses = [](const Edge& e, double y) { return (e.ay > y) != (e.by > y); };
    auto rows_of = [&](const Edge& e, int& j0, int& j1) {
        j0 = std::clamp(static_cast<int>((std::min(e.ay, e.by) - v0) / dv) - 1, 0, nv - 1);
        j1 = std::clamp(static_cast<int>((std::max(e.ay, e.by) - v0) / dv) + 1, 0, nv - 1);
    };
    std::vector<uint32_t> row_start(static_cast<size_t>(nv) + 1, 0);
    for (const Edge& e : edges_) {
        int j0, j1;
        rows_of(e, j0, j1);
        for (int j = j0; j <= j1; ++j) row_start[j + 1] += crosses(e, row_y(j));
    }
    for (int j = 0; j < nv; ++j) row_start[j + 1] += row_start[j];
    std::vector<double> xs(row_start[nv]);
    std::vector<uint32_t> next(row_start.begin(), row_start.end() - 1);
    for (const Edge& e : edges_) {
        int j0, j1;
        rows_of(e, j0, j1);
        for (int j = j0; j <= j1; ++j) {
            const double y = row_y(j);
            if (crosses(e, y)) xs[next[j]++] = e.ax + (y - e.ay) * (e.bx - e.ax) / (e.by - e.ay);
        }
    }
    for (int j = 0; j < nv; ++j) {
        double* const row = xs.data() + row_start[j];
        const size_t n = row_start[j + 1] - row_start[j];
        std::sort(row, row + n);
        size_t k = 0;
        for (int i = 0; i < nu; ++i) {
            const double x = u0 + (i + 0.5) * du;
            while (k < n && row[k] <= x) ++k;
            // crossings strictly right of x: n - k
            centre_inside_[static_cast<size_t>(j) * nu + i] = (n - k) & 1;
        }
    }
}

// A reference point (nearly) on an edge of its cell would make the query's
// crossing count ambiguous: move it to another point of the cell, away from
// every edge, and classify it by brute force (rare: exact CAD coordinates).
// (Squared distances: std::hypot is a libm call per edge of every cell.)
void TrimTester::settle_reference_points(const std::vector<TrimLoop>& loops) {
    const double u0 = u0_, v0 = v0_, du = du_, dv = dv_;  // locals, as in bin_edges
    const int nu = nu_, nv = nv_;
    const double tol = 1e-6 * std::min(du, dv), tol2 = tol * tol;
    auto near_edge = [&](size_t c, Vec2 q) {
        for (uint32_t k = cell_start_[c]; k < cell_start_[c + 1]; ++k) {
            const Edge& e = edges_[cell_edges_[k]];
            if (segment_distance2(e.ax, e.ay, e.bx, e.by, q) <= tol2) return true;
        }
        return false;
    };
    static const double kAlt[][2] = {{0.3137, 0.6911}, {0.7219, 0.2683}, {0.1871, 0.1429},
                                     {0.8377, 0.8621}, {0.4423, 0.3089}, {0.6047, 0.5813}};
    for (int j = 0; j < nv; ++j)
        for (int i = 0; i < nu; ++i) {
            const size_t c = static_cast<size_t>(j) * nu + i;
            if (!near_edge(c, ref_[c])) continue;
            for (const auto& a : kAlt) {
                const Vec2 q{u0 + (i + a[0]) * du, v0 + (j + a[1]) * dv};
                if (near_edge(c, q)) continue;
                ref_[c] = q;
                centre_inside_[c] = inside_even_odd_bruteforce(loops, q);
                break;
            }
        }
}

bool TrimTester::inside(Vec2 p) const {
    if (edges_.empty()) return true;
    const double fx = (p.x - u0_) / du_, fy = (p.y - v0_) / dv_;
    if (!(fx >= 0 && fy >= 0 && fx < nu_ && fy < nv_)) return false;  // also NaN
    const int i = static_cast<int>(fx), j = static_cast<int>(fy);
    const size_t c = static_cast<size_t>(j) * nu_ + i;
    const double cx = ref_[c].x, cy = ref_[c].y;
    bool in = centre_inside_[c];
    for (uint32_t k = cell_start_[c]; k < cell_start_[c + 1]; ++k) {
        const Edge& e = edges_[cell_edges_[k]];
        // Edge endpoints on opposite sides of the line centre->p (half-open: > 0 vs <= 0) ...
        const bool sa = orient(cx, cy, p.x, p.y, e.ax, e.ay) > 0, sb = orient(cx, cy, p.x, p.y, e.bx, e.by) > 0;
        if (sa == sb) continue;
        // ... and centre and p on opposite sides of the edge's line.
        const bool sc = orient(e.ax, e.ay, e.bx, e.by, cx, cy) > 0, sp = orient(e.ax, e.ay, e.bx, e.by, p.x, p.y) > 0;
        if (sc != sp) in = !in;
    }
    return in;
}

double TrimTester::boundary_distance(Vec2 p, double max_d) const {
    if (edges_.empty() || !(max_d >= 0)) return HUGE_VAL;
    const double fx0 = (p.x - max_d - u0_) / du_, fx1 = (p.x + max_d - u0_) / du_;
    const double fy0 = (p.y - max_d - v0_) / dv_, fy1 = (p.y + max_d - v0_) / dv_;
    if (!(fx1 >= 0 && fy1 >= 0 && fx0 < nu_ && fy0 < nv_)) return HUGE_VAL;  // also NaN
    // At most 8 x 8 cells: the callers' tolerances are far below a cell; larger
    // windows are clipped around p (a miss only makes the caller stricter).
    const int ci = std::clamp(static_cast<int>((p.x - u0_) / du_), 0, nu_ - 1);
    const int cj = std::clamp(static_cast<int>((p.y - v0_) / dv_), 0, nv_ - 1);
    const int i0 = std::max({0, static_cast<int>(std::max(fx0, 0.0)), ci - 4});
    const int i1 = std::min({nu_ - 1, static_cast<int>(std::min(fx1, double(nu_ - 1))), ci + 4});
    const int j0 = std::max({0, static_cast<int>(std::max(fy0, 0.0)), cj - 4});
    const int j1 = std::min({nv_ - 1, static_cast<int>(std::min(fy1, double(nv_ - 1))), cj + 4});
    double best2 = HUGE_VAL;
    for (int j = j0; j <= j1; ++j)
        for (int i = i0; i <= i1; ++i) {
            const size_t c = static_cast<size_t>(j) * nu_ + i;
            for (uint32_t k = cell_start_[c]; k < cell_start_[c + 1]; ++k) {
                const Edge& e = edges_[cell_edges_[k]];
                best2 = std::min(best2, segment_distance2(e.ax, e.ay, e.bx, e.by, p));
            }
        }
    // One root at the end (this is the near-trim test of every solve converged
    // outside a loop).
    const double best = std::sqrt(best2);
    return best <= max_d ? best : HUGE_VAL;
}

}  // namespace nurbsrt
