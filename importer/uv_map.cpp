#include "importer/uv_map.h"

#include <algorithm>
#include <cmath>

#include <gp_Pnt.hxx>
#include <gp_Vec.hxx>

namespace nurbsrt::occt {
namespace {

// Newton steps of a point inversion: from the linear guess the error is a few
// per cent of a circular span and Gauss-Newton converges quadratically (the
// point lies on the curve: zero residual), so 4-6 steps reach rounding; 40 is
// a bound for the pathological, never the typical.
constexpr int kMaxSteps = 40;
// Points of the check along each direction of the face box (ends included).
constexpr int kCheckPoints = 9;
// A Gauss-Newton step this small (relative to the parameter range) is the last:
// convergence is quadratic (zero residual), so the error after it is of the
// order of its square, ~1e-16 of the range: rounding. Without this stop every
// inversion paid one more curve evaluation only to see a step of ~1e-16.
constexpr double kLastStepRelative = 1e-8;
// Intervals of to_surface's seed table per direction: a cubic Hermite seed over
// 16 intervals of a rational circle's parameter map starts Newton so close that
// its first step is mostly below kLastStepRelative. The mesh nodes' and trim
// points' inversions are a large share of conversion and meshing; the table
// and the stop above more than halve their curve evaluations.
constexpr int kSeedIntervals = 16;

// The parameter of `c` at which it passes through `p` (which lies on it), by
// Gauss-Newton from `seed` on |c(t) - p|^2 (Piegl & Tiller 6.1 without the
// curvature term, which the zero residual makes unnecessary). `scale`: the
// parameter range, for the step-size stop.
template <class Curve>
double invert_on_curve(const Curve& c, const gp_Pnt& p, double seed, double scale) {
    double t = seed;
    for (int step = 0; step < kMaxSteps; ++step) {
        gp_Pnt q;
        gp_Vec d;
        c.D1(t, q, d);
        const double d2 = d.SquareMagnitude();
        if (!(d2 > 0)) break;  // degenerate iso-curve: the check rejects the map
        const double dt = gp_Vec(q, p).Dot(d) / d2;
        t += dt;
        if (std::fabs(dt) <= kLastStepRelative * scale) break;
    }
    return t;
}

double lerp_range(double x, double a0, double a1, double b0, double b1) {
    return b0 + (x - a0) * (b1 - b0) / (a1 - a0);
}

// The (u,v) at which `s` passes through `p`, by Gauss-Newton from the given
// (u,v); false when it does not converge to the point. Used once per face, for
// the reference point.
bool invert_on_surface(const Geom_Surface& s, const gp_Pnt& p, double& u, double& v, double tol) {
    for (int step = 0; step < kMaxSteps; ++step) {
        gp_Pnt q;
        gp_Vec du, dv;
        s.D1(u, v, q, du, dv);
        const gp_Vec r(q, p);
        const double a = du.Dot(du), b = du.Dot(dv), c = dv.Dot(dv);
        const double det = a * c - b * b;
        if (!(det > 0)) return false;
        const double ru = du.Dot(r), rv = dv.Dot(r);
        u += (c * ru - b * rv) / det;
        v += (a * rv - b * ru) / det;
    }
    return s.Value(u, v).Distance(p) <= tol;
}

}  // namespace

double UVMap::Axis::to_surface(double t) const {
    if (!active) return t;
    return invert_on_curve(*surface_eval, face_iso->Value(t), seed(t), surface1 - surface0);
}

double UVMap::Axis::seed(double t) const {
    if (table_s.empty()) return lerp_range(t, face0, face1, surface0, surface1);
    const double h = (face1 - face0) / kSeedIntervals;
    const double x = std::clamp((t - face0) / h, 0.0, static_cast<double>(kSeedIntervals));
    const int k = std::min(static_cast<int>(x), kSeedIntervals - 1);
    const double f = x - k, f2 = f * f, f3 = f2 * f;
    // Cubic Hermite basis on [k, k + 1] (slopes per unit of t, scaled by h).
    return (2 * f3 - 3 * f2 + 1) * table_s[k] + (f3 - 2 * f2 + f) * h * table_ds[k] +
           (-2 * f3 + 3 * f2) * table_s[k + 1] + (f3 - f2) * h * table_ds[k + 1];
}

void UVMap::Axis::tabulate() {
    std::vector<double> s(kSeedIntervals + 1), ds(kSeedIntervals + 1);
    for (int k = 0; k <= kSeedIntervals; ++k) {
        const double t = face0 + (face1 - face0) * k / kSeedIntervals;
        s[k] = to_surface(t);
        // surface_iso(s(t)) = face_iso(t): ds/dt = (F' . S') / |S'|^2.
        gp_Pnt p;
        gp_Vec df, dsv;
        face_iso->D1(t, p, df);
        surface_iso->D1(s[k], p, dsv);
        const double d2 = dsv.SquareMagnitude();
        ds[k] = d2 > 0 ? df.Dot(dsv) / d2 : (surface1 - surface0) / (face1 - face0);
    }
    table_s = std::move(s);
    table_ds = std::move(ds);
}

double UVMap::Axis::to_face(double s) const {
    if (!active) return s;
    return invert_on_curve(*face_iso, surface_iso->Value(s), lerp_range(s, surface0, surface1, face0, face1),
                           face1 - face0);
}

Vec2 UVMap::to_surface(Vec2 uv) const { return {u_.to_surface(uv.x), v_.to_surface(uv.y)}; }

Vec2 UVMap::to_face(Vec2 uv) const { return {u_.to_face(uv.x), v_.to_face(uv.y)}; }

std::optional<UVMap> UVMap::between(const Handle(Geom_Surface) & face_surface,
                                    const Handle(Geom_BSplineSurface) & converted, double u0, double u1, double v0,
                                    double v1) {
    if (face_surface.IsNull() || converted.IsNull() || !(u1 > u0) || !(v1 > v0)) return std::nullopt;
    double s0, s1, t0, t1;
    converted->Bounds(s0, s1, t0, t1);
    // Tolerance of the check: rounding of the rational evaluation, relative to
    // the face's size and to its coordinates (a part far from the origin).
    // The face's points on the check's grid, evaluated once: they give the
    // tolerance here and are compared with the B-spline's at the end.
    const auto grid_u = [&](int i) { return u0 + (u1 - u0) * i / (kCheckPoints - 1); };
    const auto grid_v = [&](int j) { return v0 + (v1 - v0) * j / (kCheckPoints - 1); };
    gp_Pnt grid[kCheckPoints][kCheckPoints];
    double extent = 0, coords = 0;
    const gp_Pnt corner = face_surface->Value(u0, v0);
    for (int i = 0; i < kCheckPoints; ++i)
        for (int j = 0; j < kCheckPoints; ++j) {
            const gp_Pnt& p = grid[i][j] = face_surface->Value(grid_u(i), grid_v(j));
            extent = std::max(extent, p.Distance(corner));
            coords = std::max({coords, std::fabs(p.X()), std::fabs(p.Y()), std::fabs(p.Z())});
        }
    const double tol = 1e-9 * extent + 1e-12 * coords;

    // The reference point, the box centre, on both surfaces: the iso-curves
    // through it are where each direction's map is found (not a box edge,
    // which may be a sphere's pole or a cone's apex, where an iso-curve is a point).
    const double um = 0.5 * (u0 + u1), vm = 0.5 * (v0 + v1);
    double sm = lerp_range(um, u0, u1, s0, s1), tm = lerp_range(vm, v0, v1, t0, t1);
    if (!invert_on_surface(*converted, face_surface->Value(um, vm), sm, tm, tol)) return std::nullopt;

    UVMap m;
    m.u_ = Axis{true, face_surface->VIso(vm), converted->VIso(tm), u0, u1, s0, s1, {}, {}, {}};
    m.v_ = Axis{true, face_surface->UIso(um), converted->UIso(sm), v0, v1, t0, t1, {}, {}, {}};
    if (m.u_.face_iso.IsNull() || m.u_.surface_iso.IsNull() || m.v_.face_iso.IsNull() || m.v_.surface_iso.IsNull())
        return std::nullopt;
    m.u_.surface_eval = new GeomAdaptor_Curve(m.u_.surface_iso);
    m.v_.surface_eval = new GeomAdaptor_Curve(m.v_.surface_iso);

    // The check: the box's ends map to the surface's (no shift by a period),
    // each direction's map is increasing and inverts back, and the two maps
    // together land on the same point everywhere on a grid over the box (the
    // directions are separable).
    const double eps_u = 1e-9 * (s1 - s0), eps_v = 1e-9 * (t1 - t0);
    if (std::fabs(m.u_.to_surface(u0) - s0) > eps_u || std::fabs(m.u_.to_surface(u1) - s1) > eps_u ||
        std::fabs(m.v_.to_surface(v0) - t0) > eps_v || std::fabs(m.v_.to_surface(v1) - t1) > eps_v)
        return std::nullopt;
    double prev_s = -HUGE_VAL, prev_t = -HUGE_VAL;
    for (int i = 0; i < kCheckPoints; ++i) {
        const double u = grid_u(i), v = grid_v(i);
        const double s = m.u_.to_surface(u), t = m.v_.to_surface(v);
        if (!(s > prev_s) || !(t > prev_t)) return std::nullopt;
        if (std::fabs(m.u_.to_face(s) - u) > 1e-9 * (u1 - u0) || std::fabs(m.v_.to_face(t) - v) > 1e-9 * (v1 - v0))
            return std::nullopt;
        prev_s = s;
        prev_t = t;
    }
    for (int i = 0; i < kCheckPoints; ++i)
        for (int j = 0; j < kCheckPoints; ++j) {
            const Vec2 s = m.to_surface({grid_u(i), grid_v(j)});
            if (!(converted->Value(s.x, s.y).Distance(grid[i][j]) <= tol)) return std::nullopt;
        }
    m.u_.tabulate();
    m.v_.tabulate();
    return m;
}

}  // namespace nurbsrt::occt
