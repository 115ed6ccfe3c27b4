// The mesh starts of faces no nearby pixel shows (see mesh_screen_points.h).
#include "renderer/mesh_screen_points.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace nurbsrt {

namespace {

// Triangles per grid cell aimed at: a query then tests a few cells' worth of
// triangles instead of the face's thousands, and the grid stays small.
constexpr double kTrianglesPerCell = 4.0;
// Cells per axis at the most: bounds a grid's memory where a face has very many
// triangles or a very long screen box (a face crossing the eye plane).
constexpr int kMaxCellsPerAxis = 128;
// A face's first queries scan all its triangles; from this query on, the grid
// (built once, O(triangles) with a larger constant than one scan) answers. A
// face asked about once or twice (most candidates of the nearer-sheet pass)
// never pays for a grid; one along a long silhouette does after a few pixels.
constexpr uint32_t kQueriesBeforeGrid = 4;
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
double segment_distance2(Vec2 p, Vec2 a, Vec2 b, double& t) {
    const double ex = b.x - a.x, ey = b.y - a.y, len2 = ex * ex + ey * ey;
    t = len2 > 0 ? std::clamp(((p.x - a.x) * ex + (p.y - a.y) * ey) / len2, 0.0, 1.0) : 0.0;
    const double dx = a.x + t * ex - p.x, dy = a.y + t * ey - p.y;
    return dx * dx + dy * dy;
}

// The parameters [s0, s1] of the part of segment ab within sqrt(r2) of p;
// false if none: |a + s (b - a) - p|^2 <= r2, a quadratic in s, clipped to [0, 1].
bool segment_in_disk(Vec2 a, Vec2 b, Vec2 p, double r2, double& s0, double& s1) {
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

Vec2 lerp(Vec2 a, Vec2 b, double t) { return {a.x + t * (b.x - a.x), a.y + t * (b.y - a.y)}; }

// Barycentric coordinates l of p in the screen triangle ABC; false if p lies
// outside it or the triangle is degenerate.
bool inside_triangle(Vec2 p, Vec2 A, Vec2 B, Vec2 C, double l[3]) {
    const double det = (B.y - C.y) * (A.x - C.x) + (C.x - B.x) * (A.y - C.y);
    if (det == 0) return false;
    l[0] = ((B.y - C.y) * (p.x - C.x) + (C.x - B.x) * (p.y - C.y)) / det;
    l[1] = ((C.y - A.y) * (p.x - C.x) + (A.x - C.x) * (p.y - C.y)) / det;
    l[2] = 1.0 - l[0] - l[1];
    return l[0] >= 0 && l[1] >= 0 && l[2] >= 0;
}

// The depth and the (u, v) at barycentric coordinates l of a mesh triangle.
double interpolated_depth(const double l[3], const double z[3]) { return l[0] * z[0] + l[1] * z[1] + l[2] * z[2]; }
Vec2 interpolated_uv(const double l[3], const FaceMesh& mesh, const uint32_t* idx) {
    const Vec2 &a = mesh.uv[idx[0]], &b = mesh.uv[idx[1]], &c = mesh.uv[idx[2]];
    return {l[0] * a.x + l[1] * b.x + l[2] * c.x, l[0] * a.y + l[1] * b.y + l[2] * c.y};
}

// Squared distance from p to the box [x0, x1] x [y0, y1] (0 inside).
double box_distance2(Vec2 p, double x0, double x1, double y0, double y1) {
    const double bx = std::max({x0 - p.x, 0.0, p.x - x1}), by = std::max({y0 - p.y, 0.0, p.y - y1});
    return bx * bx + by * by;
}

}  // namespace

// A triangle counts when its three vertices exist and lie in front of the eye.
bool MeshScreenPoints::usable_triangle(const FaceMesh& mesh, const std::vector<Projected>& pts, size_t t) {
    const uint32_t* idx = &mesh.triangles[3 * t];
    for (int q = 0; q < 3; ++q)
        if (idx[q] >= pts.size() || std::isnan(pts[idx[q]].s.x)) return false;
    return true;
}

int MeshScreenPoints::Grid::cell_x(double x) const {
    return std::clamp(static_cast<int>(std::floor((x - x0) / cw)), 0, nx - 1);
}
int MeshScreenPoints::Grid::cell_y(double y) const {
    return std::clamp(static_cast<int>(std::floor((y - y0) / ch)), 0, ny - 1);
}

namespace {

// Calls fn(cell) for the cells of g in square rings around p's cell (p clamped
// into the grid), each cell whose box lies within sqrt(bound()) of p, and stops
// at the first ring that lies wholly farther: every cell of ring r is at least
// r - 1 cells from p along one axis. bound() is read again as fn tightens it.
template <class Grid, class Bound, class Fn>
void for_near_cells(const Grid& g, Vec2 p, Bound&& bound, Fn&& fn) {
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

}  // namespace

const MeshScreenPoints::Entry& MeshScreenPoints::projected(uint32_t id) const {
    Entry& e = faces_[id - 1];
    std::call_once(e.once, [&] {
        const FaceMesh& mesh = c_.scene.faces[id - 1].mesh;
        const size_t n = std::min(mesh.xyz.size(), mesh.uv.size());
        e.pts.resize(n);
        for (size_t m = 0; m < n; ++m) {
            const Vec4 ph = c_.camera.project_h(Vec4{mesh.xyz[m].x, mesh.xyz[m].y, mesh.xyz[m].z, 1.0});
            const double depth = c_.camera.depth(ph);
            if (!(depth > 0)) {
                e.pts[m] = {Vec2{NAN, NAN}, depth};
                continue;
            }
            const Vec2 s{ph.x / ph.z, ph.y / ph.z};
            e.pts[m] = {s, depth};
            e.lo = {std::min(e.lo.x, s.x), std::min(e.lo.y, s.y)};
            e.hi = {std::max(e.hi.x, s.x), std::max(e.hi.y, s.y)};
        }
    });
    return e;
}

const MeshScreenPoints::Grid* MeshScreenPoints::grid(uint32_t id) const {
    Entry& e = faces_[id - 1];  // projected(id) has run: nearest_starts asks for it first
    if (e.queries.fetch_add(1, std::memory_order_relaxed) + 1 < kQueriesBeforeGrid) return nullptr;
    std::call_once(e.grid_once, [&] { build_grid(id, e); });
    return &e.grid;
}

void MeshScreenPoints::build_grid(uint32_t id, Entry& e) const {
    if (!(e.lo.x <= e.hi.x)) return;  // nothing in front of the eye: nx stays 0
    const FaceMesh& mesh = c_.scene.faces[id - 1].mesh;
    const std::vector<Projected>& pts = e.pts;
    const size_t ntri = mesh.triangles.size() / 3;
    // Each usable triangle's screen box, once: sizes the grid, then gives the cells.
    struct Box {
        uint32_t t;
        double x0, x1, y0, y1;
    };
    std::vector<Box> boxes;
    boxes.reserve(ntri);
    for (size_t t = 0; t < ntri; ++t) {
        if (!usable_triangle(mesh, pts, t)) continue;
        const uint32_t* idx = &mesh.triangles[3 * t];
        const Vec2 a = pts[idx[0]].s, b = pts[idx[1]].s, c = pts[idx[2]].s;
        boxes.push_back({static_cast<uint32_t>(t), std::min({a.x, b.x, c.x}), std::max({a.x, b.x, c.x}),
                         std::min({a.y, b.y, c.y}), std::max({a.y, b.y, c.y})});
    }
    Grid& g = e.grid;
    const double w = e.hi.x - e.lo.x, h = e.hi.y - e.lo.y;
    const double cells = std::max(1.0, static_cast<double>(boxes.size()) / kTrianglesPerCell);
    const double side = w > 0 && h > 0 ? std::sqrt(w * h / cells) : std::max(w, h) / cells;
    auto axis_cells = [&](double extent) {
        return side > 0 ? std::clamp(static_cast<int>(std::ceil(extent / side)), 1, kMaxCellsPerAxis) : 1;
    };
    g.nx = axis_cells(w);
    g.ny = axis_cells(h);
    g.x0 = e.lo.x;
    g.y0 = e.lo.y;
    // A zero extent (all points on one screen line) keeps a cell of positive
    // size: every point then falls in cell 0 of that axis.
    g.cw = w > 0 ? w / g.nx : 1.0;
    g.ch = h > 0 ? h / g.ny : 1.0;
    const size_t ncells = static_cast<size_t>(g.nx) * g.ny;

    // Compressed rows in two passes (count, then fill), entries ascending per cell.
    auto fill = [&](std::vector<uint32_t>& begin, std::vector<uint32_t>& items, size_t count, auto&& cells_of) {
        begin.assign(ncells + 1, 0);
        for (size_t q = 0; q < count; ++q) cells_of(q, [&](size_t cell, uint32_t) { ++begin[cell + 1]; });
        for (size_t cell = 0; cell < ncells; ++cell) begin[cell + 1] += begin[cell];
        items.resize(begin[ncells]);
        std::vector<uint32_t> next(begin.begin(), begin.end() - 1);
        for (size_t q = 0; q < count; ++q) cells_of(q, [&](size_t cell, uint32_t item) { items[next[cell]++] = item; });
    };
    fill(g.tri_begin, g.tris, boxes.size(), [&](size_t q, auto&& add) {
        const Box& b = boxes[q];
        const int x0 = g.cell_x(b.x0), x1 = g.cell_x(b.x1), y0 = g.cell_y(b.y0), y1 = g.cell_y(b.y1);
        for (int y = y0; y <= y1; ++y)
            for (int x = x0; x <= x1; ++x) add(static_cast<size_t>(y) * g.nx + x, b.t);
    });
    fill(g.vtx_begin, g.vtxs, pts.size(), [&](size_t m, auto&& add) {
        if (!std::isnan(pts[m].s.x))
            add(static_cast<size_t>(g.cell_y(pts[m].s.y)) * g.nx + g.cell_x(pts[m].s.x), static_cast<uint32_t>(m));
    });
}

int MeshScreenPoints::nearest_starts(uint32_t id, ScreenPoint sp, Vec2 out[2], double* screen_d2,
                                      double max_d2) const {
    const Entry& e = projected(id);
    const std::vector<Projected>& pts = e.pts;
    const Grid* g = grid(id);
    const FaceMesh& mesh = c_.scene.faces[id - 1].mesh;
    const Vec2 p{sp.sx, sp.sy};
    NearestPoint best, vertex;
    auto none = [&] {
        if (screen_d2) *screen_d2 = HUGE_VAL;
        return 0;
    };
    if (!(e.lo.x <= e.hi.x)) return none();  // no point in front of the eye
    // Bounded: points at the bound still count (offer takes strictly nearer ones).
    const bool bounded = max_d2 < HUGE_VAL;
    if (bounded) best.d2 = std::nextafter(max_d2, HUGE_VAL);
    bool any_triangle = false;
    // Triangles: a point inside one is at distance 0 (its depth decides between
    // several); else the nearest point of its edges.
    auto test_triangle = [&](uint32_t t) {
        const uint32_t* idx = &mesh.triangles[3 * t];
        const Projected* q[3] = {&pts[idx[0]], &pts[idx[1]], &pts[idx[2]]};
        const Vec2 A = q[0]->s, B = q[1]->s, C = q[2]->s;
        // Cull by the triangle's screen box: most triangles of a cell are farther than the best.
        if (box_distance2(p, std::min({A.x, B.x, C.x}), std::max({A.x, B.x, C.x}), std::min({A.y, B.y, C.y}),
                          std::max({A.y, B.y, C.y})) > best.d2)
            return;
        double l[3];
        const double z3[3] = {q[0]->depth, q[1]->depth, q[2]->depth};
        if (inside_triangle(p, A, B, C, l)) {
            best.offer(0.0, interpolated_depth(l, z3), interpolated_uv(l, mesh, idx), 3 * uint64_t(t));
            return;
        }
        for (int k = 0; k < 3; ++k) {
            const uint32_t a = idx[k], b = idx[(k + 1) % 3];
            double s = 0;
            const double d2 = segment_distance2(p, pts[a].s, pts[b].s, s);
            best.offer(d2, pts[a].depth + s * (pts[b].depth - pts[a].depth), lerp(mesh.uv[a], mesh.uv[b], s),
                       3 * uint64_t(t) + k);
        }
    };
    auto test_vertex = [&](uint32_t m) {
        const double dx = pts[m].s.x - p.x, dy = pts[m].s.y - p.y;
        vertex.offer(dx * dx + dy * dy, pts[m].depth, mesh.uv[m], m);
    };
    if (g) {
        for_near_cells(*g, p, [&] { return best.d2; }, [&](size_t cell) {
            for (uint32_t q = g->tri_begin[cell]; q < g->tri_begin[cell + 1]; ++q) test_triangle(g->tris[q]);
        });
        any_triangle = !g->tris.empty();
    } else {
        const size_t ntri = mesh.triangles.size() / 3;
        for (size_t t = 0; t < ntri; ++t)
            if (usable_triangle(mesh, pts, t)) {
                any_triangle = true;
                test_triangle(static_cast<uint32_t>(t));
            }
    }
    if (bounded && !best.found) {
        // The mesh lies farther than the bound (its vertices belong to its
        // triangles); only a mesh without usable triangles falls back on the
        // vertices within the bound.
        if (any_triangle) return none();
        vertex.d2 = best.d2;
    }
    if (g) {
        for_near_cells(*g, p, [&] { return vertex.d2; }, [&](size_t cell) {
            for (uint32_t q = g->vtx_begin[cell]; q < g->vtx_begin[cell + 1]; ++q) test_vertex(g->vtxs[q]);
        });
    } else {
        for (size_t m = 0; m < pts.size(); ++m)
            if (!std::isnan(pts[m].s.x)) test_vertex(static_cast<uint32_t>(m));
    }
    int n = 0;
    for (const NearestPoint* q : {&best, &vertex})
        if (q->found && (n == 0 || out[0].x != q->uv.x || out[0].y != q->uv.y)) out[n++] = q->uv;
    if (n == 0) return none();
    if (screen_d2) *screen_d2 = best.found ? best.d2 : vertex.d2;
    return n;
}

bool MeshScreenPoints::frontmost_point(uint32_t id, ScreenPoint sp, double max_d2, Vec2& uv, double& depth) const {
    const Entry& e = projected(id);
    const std::vector<Projected>& pts = e.pts;
    const Vec2 p{sp.sx, sp.sy};
    if (!(box_distance2(p, e.lo.x, e.hi.x, e.lo.y, e.hi.y) <= max_d2)) return false;
    const FaceMesh& mesh = c_.scene.faces[id - 1].mesh;
    NearestPoint front;  // ordered by depth: offer(depth, 0, ...)
    // Per triangle within reach: depth is linear over it, so its minimum over the
    // triangle's part inside the disk of reach around p lies on that part's
    // border: at an end of an edge's part inside the disk, or on the disk's rim
    // at the point against the depth gradient, where that lies in the triangle.
    const double r = std::sqrt(max_d2);
    auto test_triangle = [&](uint32_t t) {
        const uint32_t* idx = &mesh.triangles[3 * t];
        const Projected* q[3] = {&pts[idx[0]], &pts[idx[1]], &pts[idx[2]]};
        const Vec2 A = q[0]->s, B = q[1]->s, C = q[2]->s;
        if (box_distance2(p, std::min({A.x, B.x, C.x}), std::max({A.x, B.x, C.x}), std::min({A.y, B.y, C.y}),
                          std::max({A.y, B.y, C.y})) > max_d2)
            return;
        for (int k = 0; k < 3; ++k) {
            const uint32_t a = idx[k], b = idx[(k + 1) % 3];
            double s0 = 0, s1 = 0;
            if (!segment_in_disk(pts[a].s, pts[b].s, p, max_d2, s0, s1)) continue;
            for (const double s : {s0, s1})
                front.offer(pts[a].depth + s * (pts[b].depth - pts[a].depth), 0, lerp(mesh.uv[a], mesh.uv[b], s),
                            4 * uint64_t(t) + k);
        }
        // The screen gradient g of depth: z(x) = z(A) + g . (x - A) at B and C.
        const double bx = B.x - A.x, by = B.y - A.y, cx = C.x - A.x, cy = C.y - A.y, det = bx * cy - by * cx;
        if (det == 0) return;
        const double zb = q[1]->depth - q[0]->depth, zc = q[2]->depth - q[0]->depth;
        const double gx = (zb * cy - zc * by) / det, gy = (zc * bx - zb * cx) / det, g = std::hypot(gx, gy);
        const Vec2 rim = g > 0 ? Vec2{p.x - r * gx / g, p.y - r * gy / g} : p;
        double l[3];
        const double z3[3] = {q[0]->depth, q[1]->depth, q[2]->depth};
        if (inside_triangle(rim, A, B, C, l))
            front.offer(interpolated_depth(l, z3), 0, interpolated_uv(l, mesh, idx), 4 * uint64_t(t) + 3);
    };
    if (const Grid* g = grid(id)) {
        for_near_cells(*g, p, [&] { return max_d2; }, [&](size_t cell) {
            for (uint32_t q = g->tri_begin[cell]; q < g->tri_begin[cell + 1]; ++q) test_triangle(g->tris[q]);
        });
    } else {
        const size_t ntri = mesh.triangles.size() / 3;
        for (size_t t = 0; t < ntri; ++t)
            if (usable_triangle(mesh, pts, t)) test_triangle(static_cast<uint32_t>(t));
    }
    if (!front.found) return false;
    uv = front.uv;
    depth = front.d2;
    return true;
}

int MeshScreenPoints::starts_in_front(uint32_t id, ScreenPoint sp, double max_d2, double max_depth, Vec2* out,
                                      int max_out) const {
    const Entry& e = projected(id);
    const std::vector<Projected>& pts = e.pts;
    const Vec2 p{sp.sx, sp.sy};
    if (!(box_distance2(p, e.lo.x, e.hi.x, e.lo.y, e.hi.y) <= max_d2) || max_out <= 0) return 0;
    const FaceMesh& mesh = c_.scene.faces[id - 1].mesh;
    NearestPoint best;
    best.d2 = std::nextafter(max_d2, HUGE_VAL);  // points at the bound still count
    // The sheets covering sp: (depth, key, uv) of each triangle part that contains it.
    struct Cover {
        double z;
        uint64_t key;
        Vec2 uv;
    };
    std::vector<Cover> covers;
    // A polygon vertex: screen position, depth, (u, v).
    struct Corner {
        Vec2 s;
        double z;
        Vec2 uv;
    };
    auto test_triangle = [&](uint32_t t) {
        const uint32_t* idx = &mesh.triangles[3 * t];
        const Vec2 A = pts[idx[0]].s, B = pts[idx[1]].s, C = pts[idx[2]].s;
        if (box_distance2(p, std::min({A.x, B.x, C.x}), std::max({A.x, B.x, C.x}), std::min({A.y, B.y, C.y}),
                          std::max({A.y, B.y, C.y})) > best.d2)
            return;
        // The triangle clipped to depth < max_depth (Sutherland & Hodgman 1974,
        // one plane): depth is linear over it, so the part is a convex polygon.
        Corner poly[4];
        int n = 0;
        for (int k = 0; k < 3; ++k) {
            const Projected &a = pts[idx[k]], &b = pts[idx[(k + 1) % 3]];
            const Vec2 &ua = mesh.uv[idx[k]], &ub = mesh.uv[idx[(k + 1) % 3]];
            if (a.depth < max_depth) poly[n++] = {a.s, a.depth, ua};
            if ((a.depth < max_depth) != (b.depth < max_depth)) {
                const double w = (max_depth - a.depth) / (b.depth - a.depth);
                poly[n++] = {lerp(a.s, b.s, w), max_depth, lerp(ua, ub, w)};
            }
        }
        if (n == 0) return;
        // p inside the polygon: the nearest point is p itself (a fan of triangles).
        for (int k = 1; k + 1 < n; ++k) {
            double l[3];
            if (!inside_triangle(p, poly[0].s, poly[k].s, poly[k + 1].s, l)) continue;
            const double z3[3] = {poly[0].z, poly[k].z, poly[k + 1].z};
            const Vec2 uv3 = {l[0] * poly[0].uv.x + l[1] * poly[k].uv.x + l[2] * poly[k + 1].uv.x,
                              l[0] * poly[0].uv.y + l[1] * poly[k].uv.y + l[2] * poly[k + 1].uv.y};
            covers.push_back({interpolated_depth(l, z3), 4 * uint64_t(t), uv3});
            best.offer(0.0, covers.back().z, uv3, 4 * uint64_t(t));
            return;
        }
        for (int k = 0; k < n; ++k) {
            const Corner &a = poly[k], &b = poly[(k + 1) % n];
            double w = 0;
            const double d2 = segment_distance2(p, a.s, b.s, w);
            best.offer(d2, a.z + w * (b.z - a.z), lerp(a.uv, b.uv, w), 4 * uint64_t(t) + k);
        }
    };
    if (const Grid* g = grid(id)) {
        for_near_cells(*g, p, [&] { return best.d2; }, [&](size_t cell) {
            for (uint32_t q = g->tri_begin[cell]; q < g->tri_begin[cell + 1]; ++q) test_triangle(g->tris[q]);
        });
    } else {
        const size_t ntri = mesh.triangles.size() / 3;
        for (size_t t = 0; t < ntri; ++t)
            if (usable_triangle(mesh, pts, t)) test_triangle(static_cast<uint32_t>(t));
    }
    if (!best.found) return 0;
    if (covers.empty()) {
        out[0] = best.uv;
        return 1;
    }
    std::sort(covers.begin(), covers.end(),
              [](const Cover& x, const Cover& y) { return x.z < y.z || (x.z == y.z && x.key < y.key); });
    const int n = std::min(static_cast<int>(covers.size()), max_out);
    for (int k = 0; k < n; ++k) out[k] = covers[k].uv;
    return n;
}

int MeshScreenPoints::adjacent_far_faces(const uint32_t* near, int nn, ScreenPoint sp, FarFace* out, int max_out,
                                         double max_d2) const {
    // Candidates whose distance is measured (an O(triangles) scan each): bounds
    // the cost where a near face has very many neighbours; the near faces' own
    // lists are in face order, so which ones are cut off is still deterministic.
    constexpr size_t kMaxCandidates = 64;
    std::vector<FarFace> all;
    for (int q = 0; q < nn && all.size() < kMaxCandidates; ++q)
        for (const uint32_t id : c_.prepared.faces()[near[q] - 1].adjacent) {
            if (all.size() == kMaxCandidates) break;
            if (std::find(near, near + nn, id) != near + nn ||
                std::any_of(all.begin(), all.end(), [&](const FarFace& f) { return f.id == id; }))
                continue;
            const Entry& e = projected(id);
            // Also drops a face wholly behind the eye (empty box: infinite distance).
            if (!(box_distance2({sp.sx, sp.sy}, e.lo.x, e.hi.x, e.lo.y, e.hi.y) <= max_d2)) continue;
            FarFace f;
            f.id = id;
            f.nstarts = nearest_starts(id, sp, f.starts, &f.d2, max_d2);
            if (f.nstarts && f.d2 <= max_d2) all.push_back(f);
        }
    const size_t n = std::min(all.size(), static_cast<size_t>(std::max(max_out, 0)));
    std::partial_sort(all.begin(), all.begin() + n, all.end(),
                      [](const FarFace& a, const FarFace& b) { return a.d2 < b.d2 || (a.d2 == b.d2 && a.id < b.id); });
    std::copy(all.begin(), all.begin() + n, out);
    return static_cast<int>(n);
}

}  // namespace nurbsrt
