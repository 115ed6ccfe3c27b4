// Named views and cameras fitted to a model (see camera.h).
#include <algorithm>
#include <cmath>
#include <numbers>
#include <vector>

#include "renderer/camera.h"
#include "core/error.h"
#include "core/scene/explode.h"

namespace nurbsrt {
namespace {

struct ViewDef {
    const char* name;
    Vec3 dir;  // from eye towards target
    Vec3 up;
};

constexpr double kInvSqrt3 = 0.57735026918962576451;
const ViewDef kViews[] = {
    {"front", {0, 1, 0}, {0, 0, 1}},
    {"back", {0, -1, 0}, {0, 0, 1}},
    {"left", {1, 0, 0}, {0, 0, 1}},
    {"right", {-1, 0, 0}, {0, 0, 1}},
    {"top", {0, 0, -1}, {0, 1, 0}},
    {"bottom", {0, 0, 1}, {0, 1, 0}},
    {"iso", {-kInvSqrt3, -kInvSqrt3, -kInvSqrt3}, {0, 0, 1}},
};

// The preliminary-map mesh's vertices lie on the surfaces, its edges within
// the mesh deflection of them: ImportOptions' default is 0.2 % of the box
// diagonal (importer/importer.h). The fit widens every vertex by this much, so a
// silhouette bulging between two vertices stays inside the margin.
constexpr double kMeshSlackOfDiagonal = 0.002;

// Fitting needs only the extreme points; a stride over this many still finds
// them to within a mesh cell, and keeps the fit of a huge mesh in milliseconds.
constexpr size_t kMaxFitPoints = 200000;

const ViewDef& find_view(const std::string& name) {
    for (const ViewDef& v : kViews)
        if (name == v.name) return v;
    throw Error(ErrorCode::invalid_argument, "unknown view '" + name + "'");
}

void check_fit_inputs(const CameraSpec& base, double margin) {
    if (base.width <= 0 || base.height <= 0)
        throw Error(ErrorCode::invalid_argument, "camera: image size must be positive");
    if (!(margin >= 0 && margin <= kMaxFitMargin))
        throw Error(ErrorCode::invalid_argument, "fit margin must be in [0, 0.45]");
}

// Points in a view frame: x along r, y along u, z along f, relative to `origin`.
struct ViewFrame {
    Vec3 origin, r, u, f;
};

struct Local {
    double x, y, z;
};

std::vector<Local> to_local(const ViewFrame& fr, const std::vector<Vec3>& points) {
    std::vector<Local> out;
    out.reserve(points.size());
    for (const Vec3& p : points) {
        const Vec3 d = p - fr.origin;
        out.push_back({dot(fr.r, d), dot(fr.u, d), dot(fr.f, d)});
    }
    return out;
}

// One image axis of a perspective fit: coordinate c (x or y) of each point and
// its depth z; t is the tangent of the half-angle the points may fill along this
// axis; pad the slack of every point measured across a frustum side.
struct Axis {
    double Local::*c;
    double t;
    double pad;
};

// The frustum sides c - ec = +-t (z - ez) each touching the points: the two
// plane equations give the axis' eye offset ec and depth ez exactly.
void binding_eye(const std::vector<Local>& pts, const Axis& ax, double& ec, double& ez) {
    double hi = -HUGE_VAL, lo = -HUGE_VAL;
    for (const Local& p : pts) {
        hi = std::max(hi, p.*ax.c - ax.t * p.z);
        lo = std::max(lo, -(p.*ax.c) - ax.t * p.z);
    }
    hi += ax.pad, lo += ax.pad;
    ec = 0.5 * (hi - lo);
    ez = -(hi + lo) / (2.0 * ax.t);
}

// For an eye depth ez behind the binding one, the offset ec that centres the
// points' projection on this axis: the smallest half-angle s with a feasible ec
// (bisection: feasibility is monotone in s), and the middle of the feasible ecs.
double centred_offset(const std::vector<Local>& all, const Axis& ax, double ez) {
    // Only points that can be extreme for some s in [0, t] matter. c - s z is
    // linear in s, so a point's largest value over the interval is at an end;
    // every s has a maximum of at least L = max over points of their smallest
    // value. A point whose largest value is below L is never the maximum (the
    // same for -c). This one pass leaves the bisection a few percent of a mesh.
    double L_hi = -HUGE_VAL, L_lo = -HUGE_VAL;
    for (const Local& p : all) {
        const double c = p.*ax.c;
        L_hi = std::max(L_hi, std::min(c, c - ax.t * p.z));
        L_lo = std::max(L_lo, std::min(-c, -c - ax.t * p.z));
    }
    std::vector<Local> pts;
    for (const Local& p : all) {
        const double c = p.*ax.c;
        if (std::max(c, c - ax.t * p.z) >= L_hi || std::max(-c, -c - ax.t * p.z) >= L_lo) pts.push_back(p);
    }
    const auto range = [&](double s, double& lo, double& hi) {
        lo = -HUGE_VAL, hi = HUGE_VAL;
        for (const Local& p : pts) {
            const double d = s * (p.z - ez) - ax.pad;
            lo = std::max(lo, p.*ax.c - d);
            hi = std::min(hi, p.*ax.c + d);
        }
        return lo <= hi;
    };
    double s0 = 0, s1 = ax.t, lo, hi;
    for (int it = 0; it < 60; ++it) {
        const double s = 0.5 * (s0 + s1);
        (range(s, lo, hi) ? s1 : s0) = s;
    }
    range(s1, lo, hi);
    return 0.5 * (lo + hi);
}

CameraSpec fit_points(const ViewDef& view, const std::vector<Vec3>& points, const CameraSpec& base, double margin,
                      double slack) {
    BBox box;
    for (const Vec3& p : points) box.extend(p);
    if (box.empty()) throw Error(ErrorCode::invalid_argument, "cannot fit a view to no points");
    check_fit_inputs(base, margin);
    double R = 0.5 * box.diagonal();
    if (!(R > 0)) R = 1.0, slack = std::max(slack, 1e-6);  // a single point still gets a finite view
    const Vec3 right = normalize(cross(view.dir, view.up));
    const ViewFrame frame{box.center(), right, cross(right, view.dir), view.dir};
    const std::vector<Local> pts = to_local(frame, points);
    const double a = static_cast<double>(base.width) / base.height;
    const double fill = 1.0 - 2.0 * margin;  // share of the frame the model may span per axis
    CameraSpec spec = base;
    spec.up = view.up;
    double ex = 0, ey = 0, ez = 0;
    if (base.projection == Projection::perspective) {
        const double tv = std::tan(0.5 * base.fov_deg * std::numbers::pi / 180.0);
        const double tx = fill * a * tv, ty = fill * tv;
        const Axis ax{&Local::x, tx, slack * std::sqrt(1 + tx * tx)};
        const Axis ay{&Local::y, ty, slack * std::sqrt(1 + ty * ty)};
        double ezx, ezy;
        binding_eye(pts, ax, ex, ezx);
        binding_eye(pts, ay, ey, ezy);
        ez = std::min(ezx, ezy);
        // The other axis has room to spare: centre its projection, which the
        // offset of its own (nearer) solution would not do from further back.
        if (ezx > ez) ex = centred_offset(pts, ax, ez);
        if (ezy > ez) ey = centred_offset(pts, ay, ez);
        spec.eye = frame.origin + ex * frame.r + ey * frame.u + ez * frame.f;
        // The target on the axis at the box centre's depth (the eye is always in
        // front of it: some point has z <= 0 and the frustum contains it).
        spec.target = spec.eye + std::max(-ez, 1e-9 * R) * frame.f;
        return spec;
    }
    double x0 = HUGE_VAL, x1 = -HUGE_VAL, y0 = HUGE_VAL, y1 = -HUGE_VAL;
    for (const Local& p : pts) {
        x0 = std::min(x0, p.x), x1 = std::max(x1, p.x);
        y0 = std::min(y0, p.y), y1 = std::max(y1, p.y);
    }
    const double half = std::max(0.5 * (x1 - x0) / a, 0.5 * (y1 - y0)) + slack;
    spec.ortho_height = 2.0 * std::max(half / fill, 1e-9 * R);
    spec.target = frame.origin + 0.5 * (x0 + x1) * frame.r + 0.5 * (y0 + y1) * frame.u;
    spec.eye = spec.target - 2.0 * R * frame.f;  // eye plane outside the geometry (ortho rays start there)
    return spec;
}

std::vector<Vec3> corners(const BBox& box) {
    std::vector<Vec3> c;
    if (box.empty()) return c;
    for (int k = 0; k < 8; ++k)
        c.push_back({k & 1 ? box.hi.x : box.lo.x, k & 2 ? box.hi.y : box.lo.y, k & 4 ? box.hi.z : box.lo.z});
    return c;
}

// The scene's geometry for fitting: mesh vertices (strided) and their slack.
// Faces marked in `hidden` (per face, or empty) are left out; faces with an
// offset (per face, or empty) are where it moves them.
std::vector<Vec3> fit_points_of(const Scene& scene, const std::vector<uint8_t>& hidden,
                                const std::vector<Vec3>& offsets, double& slack) {
    const auto shown = [&](size_t i) { return hidden.empty() || !hidden[i]; };
    size_t n = 0;
    for (size_t i = 0; i < scene.faces.size(); ++i) n += shown(i) ? scene.faces[i].mesh.xyz.size() : 0;
    slack = 0;
    const BBox box = moved_bbox(scene, offsets);
    if (n == 0) return corners(box);
    slack = kMeshSlackOfDiagonal * box.diagonal();
    const size_t stride = std::max<size_t>(1, n / kMaxFitPoints);
    std::vector<Vec3> pts;
    pts.reserve(n / stride + 8);
    size_t k = 0;
    for (size_t i = 0; i < scene.faces.size(); ++i)
        if (shown(i))
            for (const Vec3& p : scene.faces[i].mesh.xyz)
                if (k++ % stride == 0) pts.push_back(offsets.empty() ? p : p + offsets[i]);
    return pts;
}

// An eye given without a target: look at the centre of the points' box; the
// up of the named view unless it is (nearly) along the view, then +Y or +X; an
// orthographic height not given fits the points around that axis.
CameraSpec look_from_eye(const ViewRequest& rq, const std::vector<Vec3>& points, double slack, const CameraSpec& base) {
    BBox box;
    for (const Vec3& p : points) box.extend(p);
    CameraSpec spec = base;
    spec.eye = *rq.eye;
    spec.target = rq.target ? *rq.target : box.empty() ? Vec3{} : box.center();
    const Vec3 view = spec.target - spec.eye;
    spec.up = find_view(rq.view).up;
    if (rq.up) {
        spec.up = *rq.up;
    } else if (length(view) > 0) {
        for (Vec3 alt : {Vec3{0, 1, 0}, Vec3{1, 0, 0}})
            if (length(cross(normalize(view), spec.up)) < 1e-6) spec.up = alt;
    }
    if (rq.ortho_height) spec.ortho_height = *rq.ortho_height;
    if (base.projection != Projection::orthographic || rq.ortho_height || !(length(view) > 0) || box.empty())
        return spec;
    const Vec3 f = normalize(view), r0 = cross(f, spec.up);
    if (!(length(r0) > 0)) return spec;  // Camera refuses this up with its own message
    const Vec3 r = normalize(r0), u = cross(r, f);
    const double a = static_cast<double>(base.width) / base.height;
    double half = 0;
    for (const Vec3& p : points) {
        const Vec3 d = p - spec.target;
        half = std::max({half, std::abs(dot(r, d)) / a, std::abs(dot(u, d))});
    }
    half += slack;
    spec.ortho_height = 2.0 * std::max(half / (1.0 - 2.0 * rq.fit_margin), 1e-9 * std::max(1.0, box.diagonal()));
    return spec;
}

CameraSpec fitted(const ViewRequest& rq, const std::vector<Vec3>& points, double slack, const CameraSpec& base) {
    check_fit_inputs(base, rq.fit_margin);
    if (rq.eye) return look_from_eye(rq, points, slack, base);
    CameraSpec spec = fit_points(find_view(rq.view), points, base, rq.fit_margin, slack);
    if (rq.target) spec.target = *rq.target;
    if (rq.up) spec.up = *rq.up;
    if (rq.ortho_height) spec.ortho_height = *rq.ortho_height;
    return spec;
}

}  // namespace

bool is_named_view(const std::string& name) {
    for (const ViewDef& v : kViews)
        if (name == v.name) return true;
    return false;
}

CameraSpec named_view(const std::string& name, const BBox& box, const CameraSpec& base, double margin) {
    if (box.empty()) throw Error(ErrorCode::invalid_argument, "cannot fit a view to an empty box");
    return fit_points(find_view(name), corners(box), base, margin, 0);
}

CameraSpec named_view(const std::string& name, const std::vector<Vec3>& points, const CameraSpec& base, double margin,
                      double slack) {
    return fit_points(find_view(name), points, base, margin, slack);
}

CameraSpec fit_view(const std::string& name, const Scene& scene, const CameraSpec& base, double margin) {
    double slack = 0;
    const std::vector<Vec3> pts = fit_points_of(scene, {}, {}, slack);
    if (pts.empty()) throw Error(ErrorCode::invalid_argument, "cannot fit a view to an empty scene");
    return fit_points(find_view(name), pts, base, margin, slack);
}

CameraSpec fitted_camera(const ViewRequest& request, const Scene& scene, const CameraSpec& base,
                         const std::vector<uint8_t>& hidden_faces, const std::vector<Vec3>& face_offsets) {
    double slack = 0;
    const std::vector<Vec3> pts = fit_points_of(scene, hidden_faces, face_offsets, slack);
    if (pts.empty() && !request.eye) throw Error(ErrorCode::invalid_argument, "cannot fit a view to an empty scene");
    return fitted(request, pts, slack, base);
}

CameraSpec fitted_camera(const ViewRequest& request, const BBox& box, const CameraSpec& base) {
    if (box.empty() && !request.eye) throw Error(ErrorCode::invalid_argument, "cannot fit a view to an empty box");
    return fitted(request, corners(box), 0, base);
}

}  // namespace nurbsrt
