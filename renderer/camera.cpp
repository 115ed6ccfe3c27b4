// Camera, pixel rays and the projection to the image plane (see camera.h).
#include "renderer/camera.h"

#include <cmath>
#include <numbers>

#include "core/error.h"

namespace nurbsrt {

Camera::Camera(const CameraSpec& spec) : spec_(spec) {
    if (spec.width <= 0 || spec.height <= 0)
        throw Error(ErrorCode::invalid_argument, "camera: image size must be positive");
    const Vec3 view = spec.target - spec.eye;
    if (!(length(view) > 0) || !std::isfinite(length(view)))
        throw Error(ErrorCode::invalid_argument, "camera: eye and target must differ");
    // A right-handed camera frame: f = normalize(target - eye); r = normalize(cross(f, up)); u = cross(r, f)
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
    // One division: this runs at every converged solve, and nine divisions
    // (three per vector) were most of its time.
    const double inv_w = 1 / w;
    const Vec3 c = inv_w * d;  // C - eye
    Cu = inv_w * (du - wu * c);
    Cv = inv_w * (dv - wv * c);
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
    NurbsSurface out = s;  // the same degrees and knots, projected poles
    out.rational = true;   // D varies over the surface even for a polynomial patch
    for (Vec4& c : out.cp) c = camera.project_h(c);
    return out;
}

}  // namespace nurbsrt
