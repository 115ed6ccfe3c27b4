// Newton iteration for ray/patch hits: the paper's projected step (eq. 9-11) and
// Martin et al.'s two-plane step, with the shared termination rules (12)-(14).
// See newton.h for the definitions.
#include "renderer/solve/newton.h"

#include <algorithm>
#include <cmath>

namespace nurbsrt {

const char* newton_status_name(NewtonStatus s) {
    switch (s) {
        case NewtonStatus::converged:
            return "converged";
        case NewtonStatus::diverged:
            return "diverged";
        case NewtonStatus::singular:
            return "singular";
        case NewtonStatus::max_iterations:
            return "max_iterations";
        case NewtonStatus::left_domain:
            return "left_domain";
        case NewtonStatus::behind_eye:
            return "behind_eye";
    }
    return "unknown";
}

UvBox face_uv_box(const NurbsSurface& s, double u0, double u1, double v0, double v1, double tol) {
    UvBox b{u0, u1, v0, v1};
    if (!(u1 > u0) || !(v1 > v0)) return b;
    auto coincide = [&](bool along_v, int n) {
        for (int k = 0; k <= n; ++k) {
            const double f = double(k) / n;
            const Vec4 a = along_v ? evaluate(s, u0, v0 + f * (v1 - v0)) : evaluate(s, u0 + f * (u1 - u0), v0);
            const Vec4 c = along_v ? evaluate(s, u1, v0 + f * (v1 - v0)) : evaluate(s, u0 + f * (u1 - u0), v1);
            if (!(a.w != 0 && c.w != 0)) return false;
            const Vec3 pa{a.x / a.w, a.y / a.w, a.z / a.w}, pc{c.x / c.w, c.y / c.w, c.z / c.w};
            if (!(length(pa - pc) <= tol)) return false;
        }
        return true;
    };
    b.wrap_u = coincide(true, 2 * (s.num_v + 8));
    b.wrap_v = coincide(false, 2 * (s.num_u + 8));
    return b;
}

namespace {

inline Vec3 xyz(Vec4 h) { return {h.x, h.y, h.z}; }

// Across a seam, a parameter beyond the box continues from the opposite edge.
inline void wrap(double& x, double x0, double x1) {
    const double period = x1 - x0;
    if (x < x0 || x > x1) x = x0 + (x - x0) - period * std::floor((x - x0) / period);
}

// Wrap across seams, then clamp (u, v) into the box; returns true when the clamp
// had to move it (wrapping is not leaving the domain).
inline bool clamp_to_box(double& u, double& v, const UvBox& b) {
    if (b.wrap_u) wrap(u, b.u0, b.u1);
    if (b.wrap_v) wrap(v, b.v0, b.v1);
    const double cu = std::clamp(u, b.u0, b.u1), cv = std::clamp(v, b.v0, b.v1);
    const bool moved = cu != u || cv != v;
    u = cu;
    v = cv;
    return moved;
}

// Box handling of a step from (u, v) to (un, vn): clamp onto the box. Default: a
// second clamp fails (left_domain). Robust: clamping is always allowed; only a
// clamped iterate that did not move (stuck on the border, the solution beyond
// it) fails. Returns false on failure.
inline bool accept_box(double u, double v, double& un, double& vn, const UvBox& box, bool robust, bool& clamped_once) {
    if (!clamp_to_box(un, vn, box)) return true;
    if (robust) return un != u || vn != v;
    if (clamped_once) return false;
    clamped_once = true;
    return true;
}

// (14) for both methods: |det| > eps_det * (product of the column lengths),
// compared squared against the product of the squared lengths: the same test
// without a square root per column (three per proposed step, two per Martin
// step, each a long-latency instruction on the Newton step's critical path).
// NaN anywhere fails it, as the unsquared test did.
inline bool regular(double det, double eps_det, double squared_lengths) {
    return det * det > eps_det * eps_det * squared_lengths;
}

// ||F||^2 of the projected system in model units (see newton.h, (12)). F is the
// image-plane offset (X / D - xR, Y / D - yR) times the model size of an image
// unit at the point's depth (Camera::image_to_model_scale): depth tan(fov / 2)
// with depth = D / w (perspective), h / 2 at any depth (orthographic). With
// g = (X - xR D, Y - yR D) = D F the D cancels:
//   perspective   ||F|| = |g| / |D| * |D / w| tan(fov / 2) = |g| scale(1) / |w|
//   orthographic  ||F|| = |g| / |D| * h / 2                 = |g| scale(1) / |D|
// one division instead of three, and no square root: (12) and (13) compare
// squares (newton_iterate), and each is a long-latency instruction on the
// critical path of every iteration.
inline double proposed_residual2(const Vec4& S, const Camera& cam, ScreenPoint s) {
    const double gx = S.x - s.sx * S.z, gy = S.y - s.sy * S.z;
    const double q = cam.image_to_model_scale(1.0) / (cam.perspective() ? S.w : S.z);
    return (gx * gx + gy * gy) * (q * q);
}

}  // namespace

bool proposed_step(const SurfaceDerivs& d, ScreenPoint s, double eps_det, Step& out) {
    // Columns P = (X, Y, D), P_u, P_v, R = (xR, yR, 1); det[a, b, c] = a . (b x c).
    const Vec3 P = xyz(d.S), Pu = xyz(d.Su), Pv = xyz(d.Sv), R{s.sx, s.sy, 1.0};
    const double M = dot(P, cross(Pu, Pv));                                         // (10) M   = det[P, P_u, P_v]
    if (!regular(M, eps_det, dot(P, P) * dot(Pu, Pu) * dot(Pv, Pv))) return false;  // (14)
    const double MU = dot(R, cross(Pv, P));                                         // (10) M_U = det[P, R, P_v]
    const double MV = dot(R, cross(P, Pu));                                         // (11) M_V = det[P, P_u, R]
    const double k = P.z / M;  // (9)  (du, dv) = (w / M) (M_U, M_V)
    out = {k * MU, k * MV};
    return true;
}

bool textbook_step(const SurfaceDerivs& d, ScreenPoint s, double eps_det, Step& out) {
    const double X = d.S.x, Y = d.S.y, D = d.S.z, D2 = D * D;
    // (7): J = d(X/D, Y/D)/d(u, v) by the quotient rule; F = (X/D - xR, Y/D - yR).
    const double a = (d.Su.x * D - X * d.Su.z) / D2, b = (d.Sv.x * D - X * d.Sv.z) / D2;
    const double c = (d.Su.y * D - Y * d.Su.z) / D2, e = (d.Sv.y * D - Y * d.Sv.z) / D2;
    const double f1 = X / D - s.sx, f2 = Y / D - s.sy;
    const double det = a * e - b * c;
    if (!(std::abs(det) > eps_det * std::hypot(a, c) * std::hypot(b, e))) return false;
    out = {-(e * f1 - b * f2) / det, -(-c * f1 + a * f2) / det};  // (6) -J^{-1} F
    return true;
}

RayPlanes ray_planes(const Ray& ray) {
    const Vec3 dir = ray.dir;
    // Martin et al.: N1 from the two largest components of dir, so it is well defined.
    Vec3 n1 = (std::abs(dir.x) > std::abs(dir.y) && std::abs(dir.x) > std::abs(dir.z)) ? Vec3{dir.y, -dir.x, 0}
                                                                                       : Vec3{0, dir.z, -dir.y};
    n1 = normalize(n1);
    const Vec3 n2 = normalize(cross(n1, dir));
    return {n1, n2, -dot(n1, ray.origin), -dot(n2, ray.origin)};
}

namespace {

// The Newton iteration both methods share: the loop, the termination rules
// (12)-(14), the box handling and the bookkeeping of NewtonResult, written once.
// `System` plugs in what the papers make differ (as pbrt-v4's NewtonBisection
// takes its function): a template parameter, so each method's evaluation and
// step inline into its own copy of the loop, with no indirect call per iteration.
//   State eval(u, v)                  the surface and F at (u, v); State::r2 = ||F||^2,
//                                     model units (12): the tests compare squares,
//                                     without a square root per iteration
//   State at(d)                       the same from the surface's derivatives d
//                                     at (u, v), evaluated already (`start`)
//   bool step(state, eps_det, Step&)  the method's Newton step; false when
//                                     singular by (14)
//   void finish(state, NewtonResult&) t and the model-space partials at the root
//   void stopped(state, NewtonResult&) gap_bound and t_bound where it failed
//                                     (res.residual = ||F|| already set)
template <class System>
NewtonResult newton_iterate(const System& sys, double u0, double v0, const UvBox& box, const NewtonParams& params,
                            const SurfaceDerivs* start) {
    NewtonResult res;
    const double eps2 = params.eps * params.eps;  // (12) on squared residuals (State::r2)
    double u = u0, v = v0;
    clamp_to_box(u, v, box);
    bool clamped_once = false;
    auto s = start && u == u0 && v == v0 ? sys.at(*start) : sys.eval(u, v);
    // The end of the iteration at state s (the square root of its residual
    // taken once, here); the caller returns res.
    auto end = [&](NewtonStatus status) {
        res.residual = std::sqrt(s.r2);
        res.status = status;
        if (status == NewtonStatus::converged) {
            sys.finish(s, res);
            if (!(res.t > 0)) res.status = NewtonStatus::behind_eye;
        } else {
            sys.stopped(s, res);
        }
    };
    for (int it = 0;; ++it) {
        res.u = u;
        res.v = v;
        res.iterations = it;
        if (s.r2 < eps2) {  // (12)
            end(NewtonStatus::converged);
            return res;
        }
        if (it == params.max_iterations) {
            end(NewtonStatus::max_iterations);
            return res;
        }
        Step st;
        if (!sys.step(s, params.eps_det, st)) {  // (14)
            end(NewtonStatus::singular);
            return res;
        }
        double un = u + st.du, vn = v + st.dv;  // (5)
        if (!accept_box(u, v, un, vn, box, params.robust, clamped_once)) {
            end(NewtonStatus::left_domain);
            return res;
        }
        auto sn = sys.eval(un, vn);
        // (13); robust: backtrack along the (clamped) step before giving up
        // (NewtonParams::backtracks halvings).
        for (int half = 0; params.robust && !(sn.r2 <= s.r2) && half < params.backtracks; ++half) {
            un = 0.5 * (u + un);
            vn = 0.5 * (v + vn);
            sn = sys.eval(un, vn);
        }
        if (!(sn.r2 <= s.r2)) {  // (13)
            res.iterations = it + 1;
            end(NewtonStatus::diverged);
            return res;
        }
        u = un;
        v = vn;
        s = sn;
    }
}

// Sisojevs & Glazs 2010: the patch projected into the image plane, homogeneous
// (non-rational) derivatives, the step of eq. (9)-(11).
struct ProposedSystem {
    SurfaceEvaluation projected;
    const Camera& camera;
    ScreenPoint s;
    struct State {
        SurfaceDerivs d;
        double r2;  // ||F||^2
    };
    State eval(double u, double v) const { return at(projected.d1(u, v)); }
    State at(const SurfaceDerivs& d) const { return {d, proposed_residual2(d.S, camera, s)}; }
    bool step(const State& st, double eps_det, Step& out) const { return proposed_step(st.d, s, eps_det, out); }
    void finish(const State& st, NewtonResult& res) const {
        res.t = camera.hit_distance_from_depth(camera.depth(st.d.S), s);
        camera.model_partials(st.d.S, st.d.Su, st.d.Sv, res.Cu, res.Cv);
    }
    // The residual r is the point's offset from the ray within the plane at its
    // depth z (perpendicular to f), where the ray lies at distance z / cos(a)
    // (a: the angle between the ray and f). The point is then at least r cos(a)
    // from the ray, and its foot on the ray at most z / cos(a) + r along it.
    // Orthographic: the ray is along f, both exact (cos(a) = 1, t = z).
    void stopped(const State& st, NewtonResult& res) const {
        const double z = camera.depth(st.d.S), r = res.residual;
        if (!camera.perspective()) {
            res.gap_bound = r;
            res.t_bound = z;
            return;
        }
        const double per_depth = camera.hit_distance_from_depth(1.0, s);  // 1 / cos(a)
        res.gap_bound = r / per_depth;
        res.t_bound = std::abs(z) * per_depth + r;
    }
};

// Martin et al. 2000: the Cartesian surface and its rational partials, the ray
// as two planes; F = the point's signed distances from the planes.
struct MartinSystem {
    SurfaceEvaluation surface;
    const Ray& ray;
    RayPlanes pl;
    struct State {
        CartesianDerivs c;
        double f1, f2, r2;  // F and ||F||^2
    };
    // cartesian_d1 (nurbs.h, span_basis.h) is cartesian_from(evaluate_d1) on
    // every path: the same numbers.
    State eval(double u, double v) const { return at(surface.d1(u, v)); }
    State at(const SurfaceDerivs& d) const { return at(cartesian_from(d)); }
    State at(const CartesianDerivs& c) const {
        const double f1 = dot(pl.n1, c.P) + pl.d1, f2 = dot(pl.n2, c.P) + pl.d2;
        return {c, f1, f2, f1 * f1 + f2 * f2};
    }
    bool step(const State& st, double eps_det, Step& out) const {
        // J = [N1.C_u  N1.C_v; N2.C_u  N2.C_v] with the rational partials.
        const CartesianDerivs& c = st.c;
        const double a = dot(pl.n1, c.Pu), b = dot(pl.n1, c.Pv);
        const double cc = dot(pl.n2, c.Pu), e = dot(pl.n2, c.Pv);
        const double det = a * e - b * cc;
        if (!regular(det, eps_det, dot(c.Pu, c.Pu) * dot(c.Pv, c.Pv))) return false;  // (14)
        out = {-(e * st.f1 - b * st.f2) / det, -(-cc * st.f1 + a * st.f2) / det};     // -J^{-1} F
        return true;
    }
    void finish(const State& st, NewtonResult& res) const {
        res.t = dot(st.c.P - ray.origin, ray.dir);
        res.Cu = st.c.Pu;
        res.Cv = st.c.Pv;
    }
    // F is the point's distance from the two planes through the ray: exact.
    void stopped(const State& st, NewtonResult& res) const {
        res.gap_bound = res.residual;
        res.t_bound = dot(st.c.P - ray.origin, ray.dir);
    }
};

}  // namespace

NewtonResult newton_proposed(const NurbsSurface& projected, const Camera& camera, ScreenPoint s, double u0, double v0,
                             const UvBox& box, const NewtonParams& params, const SurfaceSpans* spans,
                             const SurfaceDerivs* start, const SurfacePatches* patches) {
    return newton_iterate(ProposedSystem{{projected, spans, patches}, camera, s}, u0, v0, box, params, start);
}

NewtonResult newton_martin(const NurbsSurface& surface, const Ray& ray, double u0, double v0, const UvBox& box,
                           const NewtonParams& params, const SurfaceSpans* spans, const SurfaceDerivs* start,
                           const SurfacePatches* patches) {
    return newton_iterate(MartinSystem{{surface, spans, patches}, ray, ray_planes(ray)}, u0, v0, box, params, start);
}

}  // namespace nurbsrt
