// Camera, pixel rays and the projection to the image plane (see camera.h).
#include "renderer/camera.h"

#include <algorithm>
#include <cmath>
#include <numbers>

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
    const ViewDef* view = find_view(name);
    if (!view) throw Error(ErrorCode::invalid_argument, "unknown view '" + name + "'");
    if (box.empty()) throw Error(ErrorCode::invalid_argument, "cannot fit a view to an empty box");
    if (base.width <= 0 || base.height <= 0)
        throw Error(ErrorCode::invalid_argument, "camera: image size must be positive");
    constexpr double kMargin = 1.05;  // the box's image fills at most 1/1.05 of the frame
    const double a = static_cast<double>(base.width) / base.height;
    const Vec3 c = box.center();
    const Vec3 f = view->dir;
    const Vec3 r = normalize(cross(f, view->up));
    const Vec3 u = cross(r, f);
    double R = 0.5 * box.diagonal();
    if (!(R > 0)) R = 1.0;  // a point box still gets a finite view
    CameraSpec spec = base;
    spec.target = c;
    spec.up = view->up;
    // Box corners in the view frame, relative to the centre: (x, y, z) along (r, u, f).
    double dist = 0, half_h = 0;
    for (int k = 0; k < 8; ++k) {
        const Vec3 p = Vec3{k & 1 ? box.hi.x : box.lo.x, k & 2 ? box.hi.y : box.lo.y,
                            k & 4 ? box.hi.z : box.lo.z} - c;
        const double x = std::abs(dot(r, p)), y = std::abs(dot(u, p)), z = dot(f, p);
        if (base.projection == Projection::perspective) {
            // Inside the frustum: |x| <= a tan (dist + z) / kMargin, |y| <= tan (dist + z) / kMargin.
            const double tv = std::tan(0.5 * base.fov_deg * std::numbers::pi / 180.0);
            dist = std::max(dist, kMargin * std::max(x / a, y) / tv - z);
            dist = std::max(dist, 0.1 * R - z);  // every corner well in front of the eye
        } else {
            half_h = std::max(half_h, kMargin * std::max(x / a, y));
        }
    }
    if (base.projection == Projection::orthographic) {
        spec.ortho_height = 2.0 * std::max(half_h, 1e-9 * R);
        dist = 2.0 * R;  // eye plane outside the box (orthographic rays start there)
    }
    spec.eye = spec.target - dist * view->dir;
    return spec;
}

}  // namespace nurbsrt
