// MeshScreenPoints' queries for sheets of a face in front of a depth (see
// mesh_screen_points.h): the frontmost mesh point within reach, and the sheets
// covering a screen point front to back.
#include <algorithm>
#include <cmath>
#include <vector>

#include "renderer/frame/mesh_screen_points.h"
#include "renderer/frame/screen_geometry.h"

namespace nurbsrt {

using namespace screen;

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
        // Depth is linear over the triangle: no part of it lies in front of its
        // nearest corner, so a triangle wholly behind the frontmost point so
        // far cannot improve on it (ties still go on, to the key).
        if (std::min({q[0]->depth, q[1]->depth, q[2]->depth}) > front.d2) return;
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
    for_triangles_near(
        id, p, [&] { return max_d2; }, test_triangle);
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
    for_triangles_near(
        id, p, [&] { return best.d2; }, test_triangle);
    if (!best.found) return 0;
    if (covers.empty()) {
        out[0] = best.uv;
        return 1;
    }
    std::sort(covers.begin(), covers.end(),
              [](const Cover& x, const Cover& y) { return x.z < y.z || (x.z == y.z && x.key < y.key); });
    // A triangle listed in several grid cells that the search visits (sp on a
    // cell border) covers sp once: one start per sheet, whatever the grid.
    covers.erase(
        std::unique(covers.begin(), covers.end(), [](const Cover& x, const Cover& y) { return x.key == y.key; }),
        covers.end());
    const int n = std::min(static_cast<int>(covers.size()), max_out);
    for (int k = 0; k < n; ++k) out[k] = covers[k].uv;
    return n;
}

}  // namespace nurbsrt
