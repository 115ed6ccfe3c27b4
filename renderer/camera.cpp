// Camera, pixel rays and the projection to the image plane (see camera.h).
#include "renderer/camera.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <vector>

#include "renderer/error.h"

namespace nurbsrt {

Camera::Camera(const CameraSpec& spec) : spec_(spec) {
    if (spec.width <= 0 || spec.height <= 0)
        throw Error(ErrorCode::invalid_argument, "camera: image size must be positive");
    const Vec3 view = spec.target - spec.eye;
    if (!(length(view) > 0) || !std::isfinite(length(view)))
        throw Error(ErrorCode::invalid_argument, "camera: eye and target must differ");
    // DESIGN.md: f = normalize(target - eye); r = normalize(cross(f, up)); u = cross(r, f)
    f_ = normalize(view);
    const Vec3 side = cross(f_, spec.up);
    if (!(length(side) > 1e-12 * length(spec.up)))
        throw Error(ErrorCode::invalid_argument, "camera: up must not be parallel to the view direction");
    r_ = normalize(side);
    u_ = cross(r_, f_);
    aspect_ = static_cast<double>(spec.width) / spec.height;
    if (perspective()) {
        if (!(spec.fov_deg > 0 && spec.fov_deg < 180))
            throw Error(ErrorCode::invalid_argument, "camera: fov_deg must be in (0, 180)");
        tan_half_ = std::tan(0.5 * spec.fov_deg * std::numbers::pi / 180.0);
    } else if (!(spec.ortho_height > 0) || !std::isfinite(spec.ortho_height)) {
        throw Error(ErrorCode::invalid_argument, "camera: orthographic height must be positive");
    }
}

Ray Camera::ray(ScreenPoint s) const {
    if (perspective())  // dir = normalize(f + tan(fov/2) (sx r + sy u))
        return {spec_.eye, normalize(f_ + tan_half_ * (s.sx * r_ + s.sy * u_))};
    // origin = eye + (height/2) (sx r + sy u); dir = f
    return {spec_.eye + 0.5 * spec_.ortho_height * (s.sx * r_ + s.sy * u_), f_};
}

Vec4 Camera::project_h(Vec4 pw) const {
    const Vec3 d{pw.x - pw.w * spec_.eye.x, pw.y - pw.w * spec_.eye.y, pw.z - pw.w * spec_.eye.z};
    if (perspective()) {
        const double k = 1.0 / tan_half_;
        return {k * dot(r_, d), k * dot(u_, d), dot(f_, d), pw.w};
    }
    const double k = 2.0 / spec_.ortho_height;
    return {k * dot(r_, d), k * dot(u_, d), pw.w, dot(f_, d)};
}

void Camera::model_partials(const Vec4& P, const Vec4& Pu, const Vec4& Pv, Vec3& Cu, Vec3& Cv) const {
    // Inverse of project_h relative to the eye: (d, w) with d = S.xyz - w eye.
    auto unproject = [&](const Vec4& p, Vec3& d, double& w) {
        if (perspective()) {
            d = (tan_half_ * p.x) * r_ + (tan_half_ * p.y) * u_ + p.z * f_;
            w = p.w;
        } else {
            const double k = 0.5 * spec_.ortho_height;
            d = (k * p.x) * r_ + (k * p.y) * u_ + p.w * f_;
            w = p.z;
        }
    };
    Vec3 d, du, dv;
    double w, wu, wv;
    unproject(P, d, w);
    unproject(Pu, du, wu);
    unproject(Pv, dv, wv);
    const Vec3 c = d / w;  // C - eye
    Cu = (du - wu * c) / w;
    Cv = (dv - wv * c) / w;
}

double Camera::hit_distance_from_depth(double depth_along_f, ScreenPoint s) const {
    if (!perspective()) return depth_along_f;
    // dir = (f + tan (sx r + sy u)) / L with L = sqrt(1 + tan^2 (sx^2 + sy^2)), so f.dir = 1/L.
    return depth_along_f * std::sqrt(1.0 + tan_half_ * tan_half_ * (s.sx * s.sx + s.sy * s.sy));
}

Vec4 Camera::clip(Vec3 p, double n, double fr) const {
    const Vec3 d = p - spec_.eye;
    const double xc = dot(r_, d), yc = dot(u_, d), zc = dot(f_, d);
    if (perspective()) {
        // x_ndc = xc / (zc tan a) = sx / a; y_ndc = yc / (zc tan) = sy; w_clip = zc.
        const double A = (fr + n) / (fr - n), B = -2.0 * fr * n / (fr - n);
        return {xc / (tan_half_ * aspect_), yc / tan_half_, A * zc + B, zc};
    }
    const double h2 = 0.5 * spec_.ortho_height;
    return {xc / (h2 * aspect_), yc / h2, (2.0 * zc - (fr + n)) / (fr - n), 1.0};
}

NurbsSurface project_surface(const Camera& camera, const NurbsSurface& s) {
    NurbsSurface out;
    out.degree_u = s.degree_u;
    out.degree_v = s.degree_v;
    out.num_u = s.num_u;
    out.num_v = s.num_v;
    out.knots_u = s.knots_u;
    out.knots_v = s.knots_v;
    out.rational = true;  // D varies over the surface even for a polynomial patch
    out.cp.resize(s.cp.size());
    for (size_t k = 0; k < s.cp.size(); ++k) out.cp[k] = camera.project_h(s.cp[k]);
    return out;
}

namespace {

struct ViewDef {
    const char* name;
    Vec3 dir;  // from eye towards target
    Vec3 up;
};

constexpr double kInvSqrt3 = 0.57735026918962576451;
const ViewDef kViews[] = {
    {"front", {0, 1, 0}, {0, 0, 1}},  {"back", {0, -1, 0}, {0, 0, 1}},
    {"left", {1, 0, 0}, {0, 0, 1}},   {"right", {-1, 0, 0}, {0, 0, 1}},
    {"top", {0, 0, -1}, {0, 1, 0}},   {"bottom", {0, 0, 1}, {0, 1, 0}},
    {"iso", {-kInvSqrt3, -kInvSqrt3, -kInvSqrt3}, {0, 0, 1}},
};

const ViewDef* find_view(const std::string& name) {
    for (const ViewDef& v : kViews)
        if (name == v.name) return &v;
    return nullptr;
}

}  // namespace

bool is_named_view(const std::string& name) { return find_view(name) != nullptr; }

CameraSpec named_view(const std::string& name, const BBox& box, const CameraSpec& base) {
    if (box.empty()) throw Error(ErrorCode::invalid_argument, "cannot fit a view to an empty box");
    std::vector<Vec3> corners;
    for (int k = 0; k < 8; ++k)
        corners.push_back({k & 1 ? box.hi.x : box.lo.x, k & 2 ? box.hi.y : box.lo.y, k & 4 ? box.hi.z : box.lo.z});
    return named_view(name, corners, base);
}

CameraSpec named_view(const std::string& name, const std::vector<Vec3>& points, const CameraSpec& base) {
    const ViewDef* view = find_view(name);
    if (!view) throw Error(ErrorCode::invalid_argument, "unknown view '" + name + "'");
    BBox box;
    for (const Vec3& p : points) box.extend(p);
    if (box.empty()) throw Error(ErrorCode::invalid_argument, "cannot fit a view to no points");
    if (base.width <= 0 || base.height <= 0)
        throw Error(ErrorCode::invalid_argument, "camera: image size must be positive");
    constexpr double kMargin = 1.05;  // the points' image fills at most 1/1.05 of the frame
    const double a = static_cast<double>(base.width) / base.height;
    const Vec3 f = view->dir;
    const Vec3 r = normalize(cross(f, view->up));
    const Vec3 u = cross(r, f);
    double R = 0.5 * box.diagonal();
    if (!(R > 0)) R = 1.0;  // a point box still gets a finite view
    // Centre the target on the middle of the points' extent across the view
    // (not the box centre: for an oblique view of a flat part the two differ a lot).
    Vec3 c = box.center();
    double x0 = HUGE_VAL, x1 = -HUGE_VAL, y0 = HUGE_VAL, y1 = -HUGE_VAL;
    for (const Vec3& p : points) {
        const Vec3 d = p - c;
        x0 = std::min(x0, dot(r, d)), x1 = std::max(x1, dot(r, d));
        y0 = std::min(y0, dot(u, d)), y1 = std::max(y1, dot(u, d));
    }
    c = c + 0.5 * (x0 + x1) * r + 0.5 * (y0 + y1) * u;
    CameraSpec spec = base;
    spec.target = c;
    spec.up = view->up;
    // Points in the view frame, relative to the target: (x, y, z) along (r, u, f).
    const double tv = std::tan(0.5 * base.fov_deg * std::numbers::pi / 180.0);
    double dist = 0, half_h = 0;
    for (const Vec3& q : points) {
        const Vec3 p = q - c;
        const double x = std::abs(dot(r, p)), y = std::abs(dot(u, p)), z = dot(f, p);
        if (base.projection == Projection::perspective) {
            // Inside the frustum: |x| <= a tan (dist + z) / kMargin, |y| <= tan (dist + z) / kMargin.
            dist = std::max(dist, kMargin * std::max(x / a, y) / tv - z);
            dist = std::max(dist, 0.1 * R - z);  // every point well in front of the eye
        } else {
            half_h = std::max(half_h, kMargin * std::max(x / a, y));
        }
    }
    if (base.projection == Projection::orthographic) {
        spec.ortho_height = 2.0 * std::max(half_h, 1e-9 * R);
        dist = 2.0 * R;  // eye plane outside the geometry (orthographic rays start there)
    }
    spec.eye = spec.target - dist * view->dir;
    if (base.projection == Projection::perspective) {
        // Perspective magnifies the near side, so centring across the view is
        // only approximate. Refine on the projected extent: move the camera
        // parallel to the image plane onto the extent's centre, then move it
        // along the view so the extent fills 1/kMargin of the frame. Three
        // rounds settle to well under a pixel.
        for (int round = 0; round < 3; ++round) {
            double sx0 = HUGE_VAL, sx1 = -HUGE_VAL, sy0 = HUGE_VAL, sy1 = -HUGE_VAL, z_near = HUGE_VAL;
            for (const Vec3& q : points) {
                const Vec3 d = q - spec.eye;
                const double z = dot(f, d);
                z_near = std::min(z_near, z);
                if (!(z > 0)) continue;
                const double sx = dot(r, d) / (z * tv), sy = dot(u, d) / (z * tv);
                sx0 = std::min(sx0, sx), sx1 = std::max(sx1, sx);
                sy0 = std::min(sy0, sy), sy1 = std::max(sy1, sy);
            }
            if (!(sx1 >= sx0)) break;
            const double zc = dot(f, spec.target - spec.eye);
            const Vec3 shift = (0.5 * (sx0 + sx1) * zc * tv) * r + (0.5 * (sy0 + sy1) * zc * tv) * u;
            spec.eye = spec.eye + shift;
            spec.target = spec.target + shift;
            // Sizes at the target's depth scale as zc / (zc + step).
            const double fill = kMargin * std::max(0.5 * (sx1 - sx0) / a, 0.5 * (sy1 - sy0));
            const double step = std::max((fill - 1.0) * zc, -(z_near - 0.1 * R));  // never past the nearest point
            spec.eye = spec.eye - step * f;
        }
    }
    return spec;
}

CameraSpec fit_view(const std::string& name, const Scene& scene, const CameraSpec& base) {
    size_t n = 0;
    for (const Face& f : scene.faces) n += f.mesh.xyz.size();
    if (n == 0) return named_view(name, scene.bbox, base);
    // The preliminary-map mesh lies within its deflection of the surfaces, which
    // the 5% margin absorbs. Large meshes are subsampled: the fit needs extremes,
    // and a stride over ~200k points still finds them to within a mesh cell.
    const size_t stride = std::max<size_t>(1, n / 200000);
    std::vector<Vec3> pts;
    pts.reserve(n / stride + 8);
    size_t k = 0;
    for (const Face& f : scene.faces)
        for (const Vec3& p : f.mesh.xyz)
            if (k++ % stride == 0) pts.push_back(p);
    return named_view(name, pts, base);
}

}  // namespace nurbsrt
