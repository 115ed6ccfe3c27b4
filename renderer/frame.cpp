// Progress reporting and cancellation of a frame's passes, and the mesh starts
// of faces no nearby pixel shows (see frame.h).
#include "renderer/frame.h"

#include <algorithm>
#include <cmath>

#include "renderer/error.h"

namespace nurbsrt {

void Progress::add(int64_t n) {
    if (!fn_) return;
    const int64_t d = done_.fetch_add(n, std::memory_order_relaxed) + n;
    if (d < next_.load(std::memory_order_relaxed)) return;
    std::unique_lock<std::mutex> lock(m_, std::try_to_lock);
    if (!lock.owns_lock()) return;
    const int64_t now = done_.load(std::memory_order_relaxed);
    if (now < next_.load(std::memory_order_relaxed)) return;
    next_.store(now + step_, std::memory_order_relaxed);
    report(std::min(0.999, double(now) / double(total_)));
}

void Progress::finish() {
    if (!fn_) return;
    std::lock_guard<std::mutex> lock(m_);
    report(1.0);
}

void Progress::report(double f) {
    if (f <= last_) return;
    last_ = f;
    fn_(f);
}

void throw_if_canceled(const RenderOptions& o) {
    if (canceled(o)) throw Error(ErrorCode::canceled, "the render was canceled");
}

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

namespace {

// The nearest point to p found so far, with its depth and (u, v).
struct NearestPoint {
    double d2 = HUGE_VAL, depth = HUGE_VAL;
    Vec2 uv;
    bool found = false;
    // Nearer on screen wins; at equal distance (p inside several triangles: a
    // face folding over itself) the nearer to the eye, the sheet a ray meets first.
    void offer(double dist2, double z, Vec2 at) {
        if (dist2 < d2 || (dist2 == d2 && z < depth)) d2 = dist2, depth = z, uv = at, found = true;
    }
};

// Squared distance from p to segment ab, and the parameter t in [0, 1] of the nearest point.
double segment_distance2(Vec2 p, Vec2 a, Vec2 b, double& t) {
    const double ex = b.x - a.x, ey = b.y - a.y, len2 = ex * ex + ey * ey;
    t = len2 > 0 ? std::clamp(((p.x - a.x) * ex + (p.y - a.y) * ey) / len2, 0.0, 1.0) : 0.0;
    const double dx = a.x + t * ex - p.x, dy = a.y + t * ey - p.y;
    return dx * dx + dy * dy;
}

Vec2 lerp(Vec2 a, Vec2 b, double t) { return {a.x + t * (b.x - a.x), a.y + t * (b.y - a.y)}; }

}  // namespace

int MeshScreenPoints::nearest_starts(uint32_t id, ScreenPoint sp, Vec2 out[2], double* screen_d2) const {
    const std::vector<Projected>& pts = projected(id).pts;
    const FaceMesh& mesh = c_.scene.faces[id - 1].mesh;
    const Vec2 p{sp.sx, sp.sy};
    NearestPoint best;
    const size_t ntri = mesh.triangles.size() / 3;
    for (size_t t = 0; t < ntri; ++t) {
        const uint32_t* idx = &mesh.triangles[3 * t];
        if (idx[0] >= pts.size() || idx[1] >= pts.size() || idx[2] >= pts.size()) continue;
        const Projected* q[3] = {&pts[idx[0]], &pts[idx[1]], &pts[idx[2]]};
        if (std::isnan(q[0]->s.x) || std::isnan(q[1]->s.x) || std::isnan(q[2]->s.x)) continue;
        // Cull by the triangle's screen box: most triangles are far from p.
        const double x0 = std::min({q[0]->s.x, q[1]->s.x, q[2]->s.x}), x1 = std::max({q[0]->s.x, q[1]->s.x, q[2]->s.x});
        const double y0 = std::min({q[0]->s.y, q[1]->s.y, q[2]->s.y}), y1 = std::max({q[0]->s.y, q[1]->s.y, q[2]->s.y});
        const double bx = std::max({x0 - p.x, 0.0, p.x - x1}), by = std::max({y0 - p.y, 0.0, p.y - y1});
        if (bx * bx + by * by > best.d2) continue;
        const Vec2 A = q[0]->s, B = q[1]->s, C = q[2]->s;
        const double det = (B.y - C.y) * (A.x - C.x) + (C.x - B.x) * (A.y - C.y);
        if (det != 0) {  // barycentric coordinates of p
            const double l0 = ((B.y - C.y) * (p.x - C.x) + (C.x - B.x) * (p.y - C.y)) / det;
            const double l1 = ((C.y - A.y) * (p.x - C.x) + (A.x - C.x) * (p.y - C.y)) / det;
            const double l2 = 1.0 - l0 - l1;
            if (l0 >= 0 && l1 >= 0 && l2 >= 0) {
                const Vec2 &ua = mesh.uv[idx[0]], &ub = mesh.uv[idx[1]], &uc = mesh.uv[idx[2]];
                best.offer(0.0, l0 * q[0]->depth + l1 * q[1]->depth + l2 * q[2]->depth,
                           {l0 * ua.x + l1 * ub.x + l2 * uc.x, l0 * ua.y + l1 * ub.y + l2 * uc.y});
                continue;
            }
        }
        for (int e = 0; e < 3; ++e) {
            const uint32_t a = idx[e], b = idx[(e + 1) % 3];
            double s = 0;
            const double d2 = segment_distance2(p, pts[a].s, pts[b].s, s);
            best.offer(d2, pts[a].depth + s * (pts[b].depth - pts[a].depth), lerp(mesh.uv[a], mesh.uv[b], s));
        }
    }
    NearestPoint vertex;
    for (size_t m = 0; m < pts.size(); ++m) {
        const double dx = pts[m].s.x - p.x, dy = pts[m].s.y - p.y;
        if (!std::isnan(dx)) vertex.offer(dx * dx + dy * dy, pts[m].depth, mesh.uv[m]);
    }
    int n = 0;
    for (const NearestPoint* q : {&best, &vertex})
        if (q->found && (n == 0 || out[0].x != q->uv.x || out[0].y != q->uv.y)) out[n++] = q->uv;
    if (screen_d2) *screen_d2 = best.found ? best.d2 : vertex.d2;
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
            const double bx = std::max({e.lo.x - sp.sx, 0.0, sp.sx - e.hi.x});
            const double by = std::max({e.lo.y - sp.sy, 0.0, sp.sy - e.hi.y});
            if (!(bx * bx + by * by <= max_d2)) continue;  // also a face wholly behind the eye (empty box)
            FarFace f;
            f.id = id;
            f.nstarts = nearest_starts(id, sp, f.starts, &f.d2);
            if (f.nstarts && f.d2 <= max_d2) all.push_back(f);
        }
    const size_t n = std::min(all.size(), static_cast<size_t>(std::max(max_out, 0)));
    std::partial_sort(all.begin(), all.begin() + n, all.end(),
                      [](const FarFace& a, const FarFace& b) { return a.d2 < b.d2 || (a.d2 == b.d2 && a.id < b.id); });
    std::copy(all.begin(), all.begin() + n, out);
    return static_cast<int>(n);
}

}  // namespace nurbsrt
