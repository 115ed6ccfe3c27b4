// The mesh starts of faces no nearby pixel shows (see mesh_screen_points.h).
#include "renderer/frame/mesh_screen_points.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace nurbsrt {

using namespace screen;

namespace {

// Triangles per grid cell aimed at: a query then tests a few cells' worth of
// triangles instead of the face's thousands, and the grid stays small. A
// triangle is listed in every cell its screen box overlaps (~5 at 4 per cell),
// so small cells make the grids costly to build; 16 balances building against
// querying (docs/BENCHMARKS.md).
constexpr double kTrianglesPerCell = 16.0;
// Cells per axis at the most: bounds a grid's memory where a face has very many
// triangles or a very long screen box (a face crossing the eye plane).
constexpr int kMaxCellsPerAxis = 128;

}  // namespace

// A triangle counts when its three vertices exist and lie in front of the eye.
bool MeshScreenPoints::usable_triangle(const FaceMesh& mesh, const std::vector<Projected>& pts, size_t t) {
    const uint32_t* idx = &mesh.triangles[3 * t];
    for (int q = 0; q < 3; ++q)
        if (idx[q] >= pts.size() || std::isnan(pts[idx[q]].s.x)) return false;
    return true;
}

namespace {
// floor(f) clamped to [0, n - 1] (0 for NaN): truncation where f is positive.
// std::floor is a libm call on the baseline x86-64 target, and a grid's making
// takes four per triangle.
int clamped_cell(double f, int n) { return !(f > 0) ? 0 : f < n ? static_cast<int>(f) : n - 1; }

// A grid's compressed rows in two passes (count, then fill): begin[cell] ..
// begin[cell + 1] index the cell's items in `items`, in the order offered
// (ascending where the items come ascending). cells_of(q, add) calls
// add(cell, item) for each cell item q of `count` lies in.
template <class CellsOf>
void compressed_rows(size_t ncells, size_t count, CellsOf&& cells_of, std::vector<uint32_t>& begin,
                     std::vector<uint32_t>& items) {
    begin.assign(ncells + 1, 0);
    for (size_t q = 0; q < count; ++q) cells_of(q, [&](size_t cell, uint32_t) { ++begin[cell + 1]; });
    for (size_t cell = 0; cell < ncells; ++cell) begin[cell + 1] += begin[cell];
    items.resize(begin[ncells]);
    std::vector<uint32_t> next(begin.begin(), begin.end() - 1);
    for (size_t q = 0; q < count; ++q) cells_of(q, [&](size_t cell, uint32_t item) { items[next[cell]++] = item; });
}
}  // namespace

int MeshScreenPoints::Grid::cell_x(double x) const { return clamped_cell((x - x0) / cw, nx); }
int MeshScreenPoints::Grid::cell_y(double y) const { return clamped_cell((y - y0) / ch, ny); }

const MeshScreenPoints::Entry& MeshScreenPoints::projected(uint32_t id) const {
    Entry& e = faces_[id - 1];
    e.once.call(e.m, [&] {
        const FaceMesh& mesh = c_.scene.faces[id - 1].mesh;
        const Camera& camera = c_.camera_of(id);  // the mesh in place, where the frame shows it
        const size_t n = std::min(mesh.xyz.size(), mesh.uv.size());
        e.pts.resize(n);
        for (size_t m = 0; m < n; ++m) {
            const Vec4 ph = camera.project_h(Vec4{mesh.xyz[m].x, mesh.xyz[m].y, mesh.xyz[m].z, 1.0});
            const double depth = camera.depth(ph);
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

// A face's grid is built at its first query, although one scan of its
// triangles is cheaper than a grid's making: the scans of faces asked about a
// few times cost more in total than their grids.
const MeshScreenPoints::Grid& MeshScreenPoints::grid(uint32_t id) const {
    Entry& e = faces_[id - 1];  // projected(id) has run: its callers ask for it first
    e.grid_once.call(e.m, [&] { build_grid(id, e); });
    return e.grid;
}

void MeshScreenPoints::build_grid(uint32_t id, Entry& e) const {
    if (!(e.lo.x <= e.hi.x)) return;  // nothing in front of the eye: nx stays 0
    const FaceMesh& mesh = c_.scene.faces[id - 1].mesh;
    const std::vector<Projected>& pts = e.pts;
    const size_t ntri = mesh.triangles.size() / 3;
    Grid& g = e.grid;
    // Sized by all the triangles (the usable ones are not counted first: the
    // answers do not depend on the grid, only the time).
    const double w = e.hi.x - e.lo.x, h = e.hi.y - e.lo.y;
    const double cells = std::max(1.0, static_cast<double>(ntri) / kTrianglesPerCell);
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

    // Each usable triangle's range of cells (its screen box's), computed once
    // for both passes below; kMaxCellsPerAxis fits a byte.
    static_assert(kMaxCellsPerAxis <= 256);
    struct Cells {
        uint32_t t;
        uint8_t x0, x1, y0, y1;
    };
    std::vector<Cells> ranges;
    ranges.reserve(ntri);
    for (size_t t = 0; t < ntri; ++t) {
        if (!usable_triangle(mesh, pts, t)) continue;
        const uint32_t* idx = &mesh.triangles[3 * t];
        const Vec2 a = pts[idx[0]].s, b = pts[idx[1]].s, c = pts[idx[2]].s;
        ranges.push_back({static_cast<uint32_t>(t), static_cast<uint8_t>(g.cell_x(std::min({a.x, b.x, c.x}))),
                          static_cast<uint8_t>(g.cell_x(std::max({a.x, b.x, c.x}))),
                          static_cast<uint8_t>(g.cell_y(std::min({a.y, b.y, c.y}))),
                          static_cast<uint8_t>(g.cell_y(std::max({a.y, b.y, c.y})))});
    }

    // Entries ascending per cell.
    compressed_rows(
        ncells, ranges.size(),
        [&](size_t q, auto&& add) {
            const Cells& r = ranges[q];
            for (int y = r.y0; y <= r.y1; ++y)
                for (int x = r.x0; x <= r.x1; ++x) add(static_cast<size_t>(y) * g.nx + x, r.t);
        },
        g.tri_begin, g.tris);
    compressed_rows(
        ncells, pts.size(),
        [&](size_t m, auto&& add) {
            if (!std::isnan(pts[m].s.x))
                add(static_cast<size_t>(g.cell_y(pts[m].s.y)) * g.nx + g.cell_x(pts[m].s.x), static_cast<uint32_t>(m));
        },
        g.vtx_begin, g.vtxs);
}

int MeshScreenPoints::nearest_starts(uint32_t id, ScreenPoint sp, Vec2 out[2], double* screen_d2, double max_d2) const {
    const Entry& e = projected(id);
    const std::vector<Projected>& pts = e.pts;
    const FaceMesh& mesh = c_.scene.faces[id - 1].mesh;
    const Vec2 p{sp.sx, sp.sy};
    NearestPoint best, vertex;
    auto none = [&] {
        if (screen_d2) *screen_d2 = HUGE_VAL;
        return 0;
    };
    if (!(e.lo.x <= e.hi.x)) return none();  // no point in front of the eye
    const Grid& g = grid(id);
    // Bounded: points at the bound still count (offer takes strictly nearer ones).
    const bool bounded = max_d2 < HUGE_VAL;
    if (bounded) best.d2 = std::nextafter(max_d2, HUGE_VAL);
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
    for_near_cells(
        g, p, [&] { return best.d2; },
        [&](size_t cell) {
            for (uint32_t q = g.tri_begin[cell]; q < g.tri_begin[cell + 1]; ++q) test_triangle(g.tris[q]);
        });
    const bool any_triangle = !g.tris.empty();
    if (bounded && !best.found) {
        // The mesh lies farther than the bound (its vertices belong to its
        // triangles); only a mesh without usable triangles falls back on the
        // vertices within the bound.
        if (any_triangle) return none();
        vertex.d2 = best.d2;
    }
    for_near_cells(
        g, p, [&] { return vertex.d2; },
        [&](size_t cell) {
            for (uint32_t q = g.vtx_begin[cell]; q < g.vtx_begin[cell + 1]; ++q) test_vertex(g.vtxs[q]);
        });
    int n = 0;
    for (const NearestPoint* q : {&best, &vertex})
        if (q->found && (n == 0 || out[0].x != q->uv.x || out[0].y != q->uv.y)) out[n++] = q->uv;
    if (n == 0) return none();
    if (screen_d2) *screen_d2 = best.found ? best.d2 : vertex.d2;
    return n;
}

namespace {

// The max_out faces of `all` nearest on screen, written to out in that order
// (ties by id, so the answer does not depend on the candidates' order); returns how many.
int nearest_first(std::vector<MeshScreenPoints::FarFace>& all, MeshScreenPoints::FarFace* out, int max_out) {
    using FarFace = MeshScreenPoints::FarFace;
    const size_t n = std::min(all.size(), static_cast<size_t>(std::max(max_out, 0)));
    std::partial_sort(all.begin(), all.begin() + n, all.end(),
                      [](const FarFace& a, const FarFace& b) { return a.d2 < b.d2 || (a.d2 == b.d2 && a.id < b.id); });
    std::copy(all.begin(), all.begin() + n, out);
    return static_cast<int>(n);
}

}  // namespace

const std::vector<MeshScreenPoints::ScreenBox>& MeshScreenPoints::screen_boxes() const {
    std::call_once(boxes_once_, [&] {
        boxes_.resize(c_.nfaces);
        for (uint32_t id = 1; id <= c_.nfaces; ++id) {
            const BBox& b = c_.prepared.faces()[id - 1].mesh_box;
            const Camera& camera = c_.camera_of(id);
            ScreenBox& sb = boxes_[id - 1];
            if (b.empty()) continue;
            sb.empty = false;
            for (int k = 0; k < 8; ++k) {
                const Vec3 P{k & 1 ? b.hi.x : b.lo.x, k & 2 ? b.hi.y : b.lo.y, k & 4 ? b.hi.z : b.lo.z};
                const Vec4 ph = camera.project_h(Vec4{P.x, P.y, P.z, 1.0});
                const double depth = camera.depth(ph);
                if (!(depth > 0)) {
                    sb.around = true;
                    sb.near = 0;
                    continue;
                }
                const Vec2 s{ph.x / ph.z, ph.y / ph.z};
                sb.lo = {std::min(sb.lo.x, s.x), std::min(sb.lo.y, s.y)};
                sb.hi = {std::max(sb.hi.x, s.x), std::max(sb.hi.y, s.y)};
                sb.near = std::min(sb.near, depth);
            }
        }
    });
    return boxes_;
}

namespace {

// Cells per side of the box grid: 16 pixels a cell on a 512-pixel frame, so a
// point's search square (faces_near's reach is a few pixels) spans 1 to 4
// cells, while a face's box spans few of the 1024.
constexpr int kBoxGridCells = 32;

}  // namespace

// As the face grids' cells (clamped_cell): a box corner just in front of the
// eye plane projects to a huge or infinite coordinate, which must not reach the
// integer conversion.
int MeshScreenPoints::BoxGrid::cell_x(double x) const { return clamped_cell((x - x0) * inv_cw, n); }

int MeshScreenPoints::BoxGrid::cell_y(double y) const { return clamped_cell((y - y0) * inv_ch, n); }

const MeshScreenPoints::BoxGrid& MeshScreenPoints::box_grid() const {
    std::call_once(box_grid_once_, [&] {
        const std::vector<ScreenBox>& boxes = screen_boxes();
        BoxGrid& g = box_grid_;
        g.n = kBoxGridCells;
        // The frame's screen extent: x in [-aspect, aspect], y in [-1, 1].
        const double a = c_.camera.aspect();
        g.x0 = -a, g.y0 = -1;
        g.inv_cw = g.n / (2 * a), g.inv_ch = g.n / 2.0;
        // Face ids ascending per cell; those around the eye apart.
        compressed_rows(
            static_cast<size_t>(g.n) * g.n, boxes.size(),
            [&](size_t q, auto&& add) {
                const ScreenBox& b = boxes[q];
                if (b.empty || b.around) return;
                for (int y = g.cell_y(b.lo.y); y <= g.cell_y(b.hi.y); ++y)
                    for (int x = g.cell_x(b.lo.x); x <= g.cell_x(b.hi.x); ++x)
                        add(static_cast<size_t>(y) * g.n + x, static_cast<uint32_t>(q + 1));
            },
            g.begin, g.ids);
        for (uint32_t id = 1; id <= c_.nfaces; ++id)
            if (!boxes[id - 1].empty && boxes[id - 1].around) g.around.push_back(id);
    });
    return box_grid_;
}

int MeshScreenPoints::faces_near(ScreenPoint sp, const uint32_t* exclude, int ne, FarFace* out, NearFaceBound bound,
                                 double max_depth) const {
    const double reach = c_.screen_distance(bound.reach_pixels), max_d2 = reach * reach;
    // Faces whose box reaches sp, front first; only so many have their mesh
    // searched (an O(triangles) scan or a grid each): bounds the cost where a
    // point lies in the boxes of hundreds of faces of a large assembly.
    constexpr size_t kMaxBoxCandidates = 16;
    const std::vector<ScreenBox>& boxes = screen_boxes();
    const BoxGrid& g = box_grid();
    const Vec2 p{sp.sx, sp.sy};
    // The faces binned in the cells of the square of half-side reach around p,
    // and those around the eye; ascending, each once.
    std::vector<uint32_t> ids(g.around);
    for (int y = g.cell_y(p.y - reach); y <= g.cell_y(p.y + reach); ++y)
        for (int x = g.cell_x(p.x - reach); x <= g.cell_x(p.x + reach); ++x) {
            const size_t cell = static_cast<size_t>(y) * g.n + x;
            ids.insert(ids.end(), g.ids.begin() + g.begin[cell], g.ids.begin() + g.begin[cell + 1]);
        }
    std::sort(ids.begin(), ids.end());
    ids.erase(std::unique(ids.begin(), ids.end()), ids.end());
    std::vector<std::pair<double, uint32_t>> cand;
    for (const uint32_t id : ids) {
        const ScreenBox& b = boxes[id - 1];
        if (b.empty || !(b.near < max_depth) || std::find(exclude, exclude + ne, id) != exclude + ne) continue;
        if (!b.around && !(box_distance2(p, b.lo.x, b.hi.x, b.lo.y, b.hi.y) <= max_d2)) continue;
        cand.push_back({b.near, id});
    }
    const size_t nc = std::min(cand.size(), kMaxBoxCandidates);
    std::partial_sort(cand.begin(), cand.begin() + nc, cand.end());
    std::vector<FarFace> all;
    for (size_t q = 0; q < nc; ++q) {
        FarFace f;
        f.id = cand[q].second;
        f.nstarts = nearest_starts(f.id, sp, f.starts, &f.d2, max_d2);
        if (f.nstarts && f.d2 <= max_d2) all.push_back(f);
    }
    return nearest_first(all, out, bound.max_faces);
}

int MeshScreenPoints::adjacent_far_faces(const uint32_t* near, int nn, ScreenPoint sp, FarFace* out,
                                         NearFaceBound bound) const {
    const double reach = c_.screen_distance(bound.reach_pixels), max_d2 = reach * reach;
    // Candidates whose distance is measured (an O(triangles) scan each): bounds
    // the cost where a near face has very many neighbours; the near faces' own
    // lists are in face order, so which ones are cut off is still deterministic.
    constexpr size_t kMaxCandidates = 64;
    const std::vector<ScreenBox>& boxes = screen_boxes();
    const Vec2 p{sp.sx, sp.sy};
    std::vector<FarFace> all;
    for (int q = 0; q < nn && all.size() < kMaxCandidates; ++q)
        for (const uint32_t id : c_.prepared.faces()[near[q] - 1].adjacent) {
            if (all.size() == kMaxCandidates) break;
            if (std::find(near, near + nn, id) != near + nn ||
                std::any_of(all.begin(), all.end(), [&](const FarFace& f) { return f.id == id; }))
                continue;
            // The mesh box's corners on screen bound its points' (all in front
            // of the eye when the corners are): most adjacent faces lie farther
            // and are left without projecting their mesh.
            const ScreenBox& sb = boxes[id - 1];
            if (sb.empty || (!sb.around && !(box_distance2(p, sb.lo.x, sb.hi.x, sb.lo.y, sb.hi.y) <= max_d2))) continue;
            const Entry& e = projected(id);
            // Also drops a face wholly behind the eye (empty box: infinite distance).
            if (!(box_distance2(p, e.lo.x, e.hi.x, e.lo.y, e.hi.y) <= max_d2)) continue;
            FarFace f;
            f.id = id;
            f.nstarts = nearest_starts(id, sp, f.starts, &f.d2, max_d2);
            if (f.nstarts && f.d2 <= max_d2) all.push_back(f);
        }
    return nearest_first(all, out, bound.max_faces);
}

bool MeshScreenPoints::pixels_near(uint32_t id, double pixels, size_t max_tested, const PixelArray<PixelHit>& hits,
                                   const PixelArray<double>& hit_t, double gap_footprints,
                                   std::vector<MeshPixel>& out) const {
    const Entry& e = projected(id);
    if (!(e.lo.x <= e.hi.x)) return true;  // nothing in front of the eye
    const FaceMesh& mesh = c_.scene.faces[id - 1].mesh;
    const std::vector<Projected>& pts = e.pts;
    const int W = c_.width, H = c_.height;
    // Screen to pixel coordinates, in which pixel i's centre is at i.
    auto px = [&](double sx) { return c_.camera.pixel_x(sx) - 0.5; };
    auto py = [&](double sy) { return c_.camera.pixel_y(sy) - 0.5; };
    const double r = c_.screen_distance(pixels), r2 = r * r;
    const size_t first = out.size();
    size_t tested = 0;
    const size_t ntri = mesh.triangles.size() / 3;
    for (size_t t = 0; t < ntri; ++t) {
        if (!usable_triangle(mesh, pts, t)) continue;
        const uint32_t* idx = &mesh.triangles[3 * t];
        const Vec2 A = pts[idx[0]].s, B = pts[idx[1]].s, C = pts[idx[2]].s;
        const int i0 = std::max(0, static_cast<int>(std::ceil(px(std::min({A.x, B.x, C.x})) - pixels)));
        const int i1 = std::min(W - 1, static_cast<int>(std::floor(px(std::max({A.x, B.x, C.x})) + pixels)));
        const int j0 = std::max(0, static_cast<int>(std::ceil(py(std::max({A.y, B.y, C.y})) - pixels)));
        const int j1 = std::min(H - 1, static_cast<int>(std::floor(py(std::min({A.y, B.y, C.y})) + pixels)));
        if (i1 < i0 || j1 < j0) continue;
        {
            const int ci = std::clamp(static_cast<int>(std::lround(px((A.x + B.x + C.x) / 3))), 0, W - 1);
            const int cj = std::clamp(static_cast<int>(std::lround(py((A.y + B.y + C.y) / 3))), 0, H - 1);
            const double hit = hit_t[c_.map.index(ci, cj)];
            const double front = std::min({pts[idx[0]].depth, pts[idx[1]].depth, pts[idx[2]].depth});
            if (hit < HUGE_VAL && front > c_.depth_behind(hit, gap_footprints, c_.camera.pixel_screen(ci, cj)))
                continue;
        }
        tested += static_cast<size_t>(i1 - i0 + 1) * static_cast<size_t>(j1 - j0 + 1);
        if (tested > max_tested) {
            out.resize(first);
            return false;
        }
        const double z3[3] = {pts[idx[0]].depth, pts[idx[1]].depth, pts[idx[2]].depth};
        // Each edge's signed distance a x + b y + c (unit normal, the opposite
        // vertex on the positive side): a pixel centre more than r outside any
        // edge lies farther than r from the triangle (the converse need not
        // hold at the corners; the exact test follows). Degenerate triangles
        // (no area) skip this cull.
        double ea[3], eb[3], ec[3];
        const Vec2 V[3] = {A, B, C};
        const double area2 = (B.x - A.x) * (C.y - A.y) - (B.y - A.y) * (C.x - A.x);
        const bool cull = std::fabs(area2) > 0;
        for (int q = 0; q < 3 && cull; ++q) {
            const Vec2 P = V[q], Q = V[(q + 1) % 3];
            const double len = std::hypot(Q.x - P.x, Q.y - P.y), sgn = area2 > 0 ? 1.0 : -1.0;
            ea[q] = -sgn * (Q.y - P.y) / len;
            eb[q] = sgn * (Q.x - P.x) / len;
            ec[q] = -(ea[q] * P.x + eb[q] * P.y);
        }
        for (int j = j0; j <= j1; ++j)
            for (int i = i0; i <= i1; ++i) {
                // Tested first: most pixels near a face's mesh show the face itself
                // (sorting them out afterwards was most of the cost).
                const uint32_t shown = hits[c_.map.index(i, j)].face;
                if (shown == 0 || shown == id) continue;
                const ScreenPoint sp = c_.camera.pixel_screen(i, j);
                const Vec2 p{sp.sx, sp.sy};
                if (cull && (ea[0] * p.x + eb[0] * p.y + ec[0] < -r || ea[1] * p.x + eb[1] * p.y + ec[1] < -r ||
                             ea[2] * p.x + eb[2] * p.y + ec[2] < -r))
                    continue;
                double l[3];
                if (inside_triangle(p, A, B, C, l)) {
                    out.push_back({c_.map.index(i, j), interpolated_uv(l, mesh, idx), interpolated_depth(l, z3)});
                    continue;
                }
                // Outside: the nearest point of its nearest edge, if within reach.
                double best = r2, at = 0;
                int edge = -1;
                for (int q = 0; q < 3; ++q) {
                    double s = 0;
                    const double d2 = segment_distance2(p, pts[idx[q]].s, pts[idx[(q + 1) % 3]].s, s);
                    if (d2 <= best) best = d2, at = s, edge = q;
                }
                if (edge < 0) continue;
                const uint32_t a = idx[edge], b = idx[(edge + 1) % 3];
                out.push_back({c_.map.index(i, j), lerp(mesh.uv[a], mesh.uv[b], at),
                               pts[a].depth + at * (pts[b].depth - pts[a].depth)});
            }
    }
    // One per pixel: the frontmost.
    const auto begin = out.begin() + static_cast<std::ptrdiff_t>(first);
    std::sort(begin, out.end(),
              [](const MeshPixel& x, const MeshPixel& y) { return x.k < y.k || (x.k == y.k && x.depth < y.depth); });
    out.erase(std::unique(begin, out.end(), [](const MeshPixel& x, const MeshPixel& y) { return x.k == y.k; }),
              out.end());
    return true;
}

}  // namespace nurbsrt
