// B-spline basis functions and (rational) surface evaluation.
// References: L. Piegl, W. Tiller, "The NURBS Book", 2nd ed. (1997):
//   A2.1 FindSpan, A2.2 BasisFuns, A2.3 DersBasisFuns (here k = 1 only),
//   eq. (2.9) derivative of a basis function, A3.5/A3.6 surface point / derivatives
//   (tensor product), eq. (4.19)-(4.20) / A4.4 rational surface derivatives.
//
// Hot path: degrees <= kMaxFastDegree use fixed stack arrays; higher degrees use one
// heap buffer per call. Both share the same code (the scratch pointers differ).
#include "core/scene/nurbs.h"

#include <algorithm>
#include <vector>

namespace nurbsrt {
namespace {

// Clamps t into [lo, hi]; NaN maps to lo so that evaluation never reads out of range.
inline double clamp_param(double t, double lo, double hi) {
    if (!(t > lo)) return lo;
    if (t > hi) return hi;
    return t;
}

// A2.2 up to degree p-1, then the last triangle step of degree p which also yields the
// first derivatives (A2.3 with k = 1, equivalently eq. 2.9):
//   N'_{i,p} = p N_{i,p-1} / (u_{i+p} - u_i) - p N_{i+1,p-1} / (u_{i+p+1} - u_{i+1}).
// In the last step temp_r = N_{s-p+1+r,p-1} / (u_{s+1+r} - u_{s+1+r-p}), so
//   dN[r] = p (temp_{r-1} - temp_r) with temp_{-1} = temp_p = 0.
// Denominators are >= knots[s+1] - knots[s] > 0 for a non-empty span s.
// left/right must hold p+1 values.
template <bool kDerivs>
inline void basis_core(int s, int p, double t, const double* U, double* N, double* dN, double* left, double* right) {
    N[0] = 1.0;
    if (p == 0) {
        if constexpr (kDerivs) dN[0] = 0.0;
        return;
    }
    for (int j = 1; j < p; ++j) {
        left[j] = t - U[s + 1 - j];
        right[j] = U[s + j] - t;
        double saved = 0.0;
        for (int r = 0; r < j; ++r) {
            const double temp = N[r] / (right[r + 1] + left[j - r]);
            N[r] = saved + right[r + 1] * temp;
            saved = left[j - r] * temp;
        }
        N[j] = saved;
    }
    // Last step j = p.
    left[p] = t - U[s + 1 - p];
    right[p] = U[s + p] - t;
    double saved = 0.0, prev = 0.0;
    const double dp = static_cast<double>(p);
    for (int r = 0; r < p; ++r) {
        const double temp = N[r] / (right[r + 1] + left[p - r]);
        N[r] = saved + right[r + 1] * temp;
        saved = left[p - r] * temp;
        if constexpr (kDerivs) {
            dN[r] = dp * (prev - temp);
            prev = temp;
        }
    }
    N[p] = saved;
    if constexpr (kDerivs) dN[p] = dp * prev;
}

// Scratch arrays of one surface evaluation: basis values and derivatives in u and v,
// and the left/right work arrays of A2.2.
struct Scratch {
    double *Nu, *dNu, *Nv, *dNv, *left, *right;
};

using Homog2 = HomogDerivs;

// Point and partials up to kLevel (see tensor_product in nurbs.h) at (u, v).
template <int kLevel>
Homog2 eval_core(const NurbsSurface& s, double u, double v, const Scratch& w) {
    const int p = s.degree_u, q = s.degree_v;
    const double* U = s.knots_u.data();
    const double* V = s.knots_v.data();
    u = clamp_param(u, U[p], U[s.num_u]);
    v = clamp_param(v, V[q], V[s.num_v]);
    const int su = find_span(s.num_u, p, u, U);
    const int sv = find_span(s.num_v, q, v, V);
    constexpr bool kD = kLevel >= 1;
    basis_core<kD>(su, p, u, U, w.Nu, w.dNu, w.left, w.right);
    basis_core<kD>(sv, q, v, V, w.Nv, w.dNv, w.left, w.right);
    return tensor_product<kLevel>(s, su, sv, w.Nu, w.dNu, w.Nv, w.dNv);
}

// Runs eval_core with stack scratch for low degrees, heap scratch above kMaxFastDegree.
template <int kLevel>
Homog2 eval_dispatch(const NurbsSurface& s, double u, double v) {
    const int m = std::max(s.degree_u, s.degree_v) + 1;
    if (m <= kMaxFastDegree + 1) {
        constexpr int K = kMaxFastDegree + 1;
        double Nu[K], dNu[K], Nv[K], dNv[K], left[K], right[K];
        return eval_core<kLevel>(s, u, v, Scratch{Nu, dNu, Nv, dNv, left, right});
    }
    std::vector<double> buf(static_cast<size_t>(6) * m);
    double* b = buf.data();
    return eval_core<kLevel>(s, u, v, Scratch{b, b + m, b + 2 * m, b + 3 * m, b + 4 * m, b + 5 * m});
}

inline Vec3 xyz(Vec4 h) { return {h.x, h.y, h.z}; }

// Rational first (and mixed) partials of C = A / w with A = xyz of S (eq. 4.19-4.20, A4.4):
//   C_u = (A_u - w_u C) / w,  C_v = (A_v - w_v C) / w,
//   C_uv = (A_uv - w_uv C - w_u C_v - w_v C_u) / w.
struct Cart2 {
    Vec3 P, Pu, Pv, Puv;
};
inline Cart2 to_cartesian(const Homog2& h, bool mixed) {
    Cart2 c;
    const double iw = 1.0 / h.S.w;
    c.P = xyz(h.S) * iw;
    c.Pu = (xyz(h.Su) - h.Su.w * c.P) * iw;
    c.Pv = (xyz(h.Sv) - h.Sv.w * c.P) * iw;
    if (mixed) {
        c.Puv = (xyz(h.Suv) - h.Suv.w * c.P - h.Su.w * c.Pv - h.Sv.w * c.Pu) * iw;
    }
    return c;
}

}  // namespace

// A2.1 (binary search), with clamping of t and the end-knot convention made explicit:
// t <= knots[p] gives the first non-empty span, t >= knots[n] the last one, so the
// result always satisfies knots[s] < knots[s+1] for a valid clamped knot vector.
int find_span(int n, int p, double t, const double* knots) {
    const double* U = knots;
    if (!(t > U[p])) {  // also NaN
        int s = p;
        while (s < n - 1 && !(U[s] < U[s + 1])) ++s;
        return s;
    }
    if (t >= U[n]) {
        int s = n - 1;
        while (s > p && !(U[s] < U[s + 1])) --s;
        return s;
    }
    // Invariant U[low] <= t < U[high]; ends with U[mid] <= t < U[mid+1].
    int low = p, high = n;
    int mid = (low + high) / 2;
    while (t < U[mid] || t >= U[mid + 1]) {
        if (t < U[mid])
            high = mid;
        else
            low = mid;
        mid = (low + high) / 2;
    }
    return mid;
}

void basis_and_derivs(int s, int p, double t, const double* knots, double* N, double* dN) {
    if (p <= kMaxFastDegree) {
        double left[kMaxFastDegree + 1], right[kMaxFastDegree + 1];
        basis_core<true>(s, p, t, knots, N, dN, left, right);
        return;
    }
    std::vector<double> lr(2 * static_cast<size_t>(p + 1));
    basis_core<true>(s, p, t, knots, N, dN, lr.data(), lr.data() + p + 1);
}

SurfaceDerivs evaluate_d1(const NurbsSurface& s, double u, double v) {
    const Homog2 h = eval_dispatch<1>(s, u, v);
    return {h.S, h.Su, h.Sv};
}

Vec4 evaluate(const NurbsSurface& s, double u, double v) { return eval_dispatch<0>(s, u, v).S; }

CartesianDerivs cartesian_d1(const NurbsSurface& s, double u, double v) {
    const Cart2 c = to_cartesian(eval_dispatch<1>(s, u, v), false);
    return {c.P, c.Pu, c.Pv};
}

CartesianDerivs cartesian_from(const SurfaceDerivs& h) {
    const Cart2 c = to_cartesian(HomogDerivs{h.S, h.Su, h.Sv, {}}, false);
    return {c.P, c.Pu, c.Pv};
}

// Degenerate pole edges. If an edge v = v0 of the parameter box collapses to one point
// (a whole row of control points equal, e.g. a sphere's pole or a body's pointed tip),
// P_u vanishes along it, and near it P_u(u, v0 + h) = h P_uv(u, v0) + O(h^2), so
//   P_u x P_v = h (P_uv x P_v) + O(h^2):
// the normal's limit from inside the box is sign(h) (P_uv x P_v), evaluated exactly at
// (u, v0) from the analytic mixed partial (second-order limit; no step size to tune and
// exact for the sphere). The symmetric case (edge u = u0 collapsed, P_v = 0) gives
// sign(h) (P_u x P_uv). sign(h) is +1 when the point lies in the lower half of the
// box (inside is +h) and -1 in the upper half. If that limit vanishes too (higher-order
// degeneracy, or P_u parallel to P_v with neither zero: a fold), the normal is taken a
// small step towards the box centre, with growing steps.
//
// Degeneracy test: partials scaled by the knot ranges (so a parametrization's units do
// not matter), |P_u x P_v| <= kRel * max(|P_u|, |P_v|)^2. Near a true pole at relative
// parameter distance h the direct cross product has relative error ~ eps / h and the
// limit formula ~ h, so kRel = 1e-8 keeps either side's error around 1e-8.
namespace {
// The regularity test above and the normal where it passes.
bool regular_normal(Vec3 Pu, Vec3 Pv, double ru, double rv, Vec3& out) {
    constexpr double kRel = 1e-8;
    // Squared: one square root (the normalization's) instead of four, at every hit.
    const Vec3 n = cross(Pu, Pv);
    const double a2 = dot(Pu, Pu) * (ru * ru), b2 = dot(Pv, Pv) * (rv * rv);
    const double big2 = std::max(a2, b2), n2 = dot(n, n);
    const double nn2 = n2 * ((ru * rv) * (ru * rv));
    if (nn2 > (kRel * kRel) * big2 * big2 && std::isfinite(nn2)) {
        out = (1 / std::sqrt(n2)) * n;
        return true;
    }
    return false;
}
}  // namespace

bool normal_from_partials(const NurbsSurface& s, Vec3 Cu, Vec3 Cv, bool reversed, Vec3& n) {
    if (!regular_normal(Cu, Cv, s.u_end() - s.u_begin(), s.v_end() - s.v_begin(), n)) return false;
    if (reversed) n = -n;
    return true;
}

Vec3 surface_normal(const NurbsSurface& s, double u, double v, bool reversed) {
    const double sign_orient = reversed ? -1.0 : 1.0;
    const double u0 = s.u_begin(), u1 = s.u_end(), v0 = s.v_begin(), v1 = s.v_end();
    const double ru = u1 - u0, rv = v1 - v0;
    u = clamp_param(u, u0, u1);
    v = clamp_param(v, v0, v1);

    auto regular = [&](const Cart2& c, Vec3& out) { return regular_normal(c.Pu, c.Pv, ru, rv, out); };

    const Cart2 c = to_cartesian(eval_dispatch<2>(s, u, v), true);
    Vec3 n;
    if (regular(c, n)) return sign_orient * n;

    // Second-order limit at a collapsed edge.
    const double a = length(c.Pu) * ru, b = length(c.Pv) * rv;
    if (std::max(a, b) > 0 && std::min(a, b) <= 1e-4 * std::max(a, b)) {
        Vec3 m;
        double ref;
        if (a <= b) {  // P_u vanishes: the edge v = const collapsed
            const double h_sign = (v - v0 <= v1 - v) ? 1.0 : -1.0;
            m = h_sign * cross(c.Puv, c.Pv);
            ref = length(c.Puv) * length(c.Pv);
        } else {  // P_v vanishes: the edge u = const collapsed
            const double h_sign = (u - u0 <= u1 - u) ? 1.0 : -1.0;
            m = h_sign * cross(c.Pu, c.Puv);
            ref = length(c.Pu) * length(c.Puv);
        }
        const double lm = length(m);
        if (lm > 1e-10 * ref && std::isfinite(lm)) return sign_orient * (m / lm);
    }

    // Fallback: a small step towards the centre of the box.
    const double du = (u < 0.5 * (u0 + u1)) ? ru : (u > 0.5 * (u0 + u1) ? -ru : 0.0);
    const double dv = (v < 0.5 * (v0 + v1)) ? rv : (v > 0.5 * (v0 + v1) ? -rv : 0.0);
    for (double step : {1e-6, 1e-4, 1e-2, 0.1}) {
        const Cart2 cs = to_cartesian(eval_dispatch<1>(s, u + step * du, v + step * dv), false);
        if (regular(cs, n)) return sign_orient * n;
    }
    return {0.0, 0.0, sign_orient};  // fully degenerate (a point): any unit vector
}

bool planar_control_net(const NurbsSurface& s, double relative) {
    if (s.cp.empty()) return true;
    std::vector<Vec3> p(s.cp.size());
    for (size_t k = 0; k < p.size(); ++k) {
        const Vec4& c = s.cp[k];
        p[k] = Vec3{c.x, c.y, c.z} * (1.0 / c.w);
    }
    // A plane through p[0], the point farthest from it and the point farthest
    // from that line: the best-conditioned of the net's own triangles.
    Vec3 far{0, 0, 0}, n{0, 0, 0};
    for (const Vec3& q : p)
        if (dot(q - p[0], q - p[0]) > dot(far, far)) far = q - p[0];
    for (const Vec3& q : p) {
        const Vec3 c = cross(far, q - p[0]);
        if (dot(c, c) > dot(n, n)) n = c;
    }
    const double extent = length(far);
    if (!(length(n) > relative * extent * extent)) return true;  // all on a line (or a point)
    n = n * (1.0 / length(n));
    for (const Vec3& q : p)
        if (std::fabs(dot(q - p[0], n)) > relative * extent) return false;
    return true;
}

}  // namespace nurbsrt
