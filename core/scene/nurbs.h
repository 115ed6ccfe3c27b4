// B-spline basis functions and homogeneous surface evaluation with first partials.
// Algorithms A2.1 (FindSpan), A2.2 (BasisFuns) and A2.3 (DersBasisFuns, first
// derivatives only) of Piegl & Tiller, "The NURBS Book", 2nd ed.
//
// This is the renderer's hot path: for degrees up to kMaxFastDegree everything
// lives in fixed-size stack arrays (no allocation per call); higher degrees take
// a correct but slower path that allocates.
#pragma once

#include "core/scene/scene.h"

namespace nurbsrt {

constexpr int kMaxFastDegree = 15;

// A2.1: the knot span index s with knots[s] <= t < knots[s+1], for a clamped
// knot vector of n control points and degree p; t is clamped into
// [knots[p], knots[n]] and t == knots[n] maps to the last non-empty span.
int find_span(int n, int p, double t, const double* knots);

// A2.3 for k = 1: basis values N[0..p] and their first derivatives dN[0..p] at t
// in span s (N[r] is N_{s-p+r,p}(t)). Arrays must hold p+1 values.
void basis_and_derivs(int s, int p, double t, const double* knots, double* N, double* dN);

// Homogeneous surface point and first partials at (u,v):
//   S  = sum N_i(u) N_j(v) P^w_ij,  Su = sum N_i'(u) N_j(v) P^w_ij,  Sv = sum N_i(u) N_j'(v) P^w_ij.
// (u,v) outside the knot range is clamped to it.
struct SurfaceDerivs {
    Vec4 S, Su, Sv;
};
SurfaceDerivs evaluate_d1(const NurbsSurface& s, double u, double v);

// The tensor product of A3.5 / A3.6 from the basis values N and first derivatives
// dN of knot spans su and sv: for each of the p+1 rows i of the u-span, contract
// the q+1 contiguous control points of that row with the v basis (T = sum_j N_j P_ij,
// Tv = sum_j N'_j P_ij), then accumulate with the u basis. kLevel 0: S only; 1: and
// S_u, S_v; 2: and S_uv. Shared by the knot-search path (nurbs.cpp) and the
// per-span tables (span_basis.h), which differ only in how they get the basis.
struct HomogDerivs {
    Vec4 S, Su, Sv, Suv;
};
// kP, kQ >= 0: the degrees, known at compile time (they must equal s's), so
// that the loops unroll (span_basis.cpp instantiates the common low degrees).
template <int kLevel, int kP = -1, int kQ = -1>
inline HomogDerivs tensor_product(const NurbsSurface& s, int su, int sv, const double* Nu, const double* dNu,
                                  const double* Nv, const double* dNv) {
    constexpr bool kD = kLevel >= 1;
    const int p = kP >= 0 ? kP : s.degree_u, q = kQ >= 0 ? kQ : s.degree_v;
    HomogDerivs r{};
    const Vec4* row = s.cp.data() + static_cast<size_t>(su - p) * s.num_v + (sv - q);
    for (int i = 0; i <= p; ++i, row += s.num_v) {
        Vec4 T{}, Tv{};
        for (int j = 0; j <= q; ++j) {
            const Vec4 P = row[j];
            T += Nv[j] * P;
            if constexpr (kD) Tv += dNv[j] * P;
        }
        r.S += Nu[i] * T;
        if constexpr (kD) {
            r.Su += dNu[i] * T;
            r.Sv += Nu[i] * Tv;
        }
        if constexpr (kLevel >= 2) r.Suv += dNu[i] * Tv;
    }
    return r;
}

// Homogeneous point only (cheaper: no derivative basis).
Vec4 evaluate(const NurbsSurface& s, double u, double v);

// Cartesian point and the rational first partials of C = S/w:
//   C_u = (S_u.xyz - C * S_u.w) / w   (quotient rule; The NURBS Book eq. 4.7 / A4.4)
struct CartesianDerivs {
    Vec3 P, Pu, Pv;
};
CartesianDerivs cartesian_d1(const NurbsSurface& s, double u, double v);
// The same from homogeneous partials already evaluated.
CartesianDerivs cartesian_from(const SurfaceDerivs& h);

// Unit normal of the Cartesian surface, oriented by `reversed` (face orientation).
// Where Pu x Pv vanishes (a degenerate pole edge) the normal is taken from the
// limit: the partials are re-evaluated a small step inside the parameter box.
Vec3 surface_normal(const NurbsSurface& s, double u, double v, bool reversed);

// The unit normal from the rational partials C_u, C_v at a point of s (e.g. a
// Newton iteration's last derivatives), oriented by `reversed`, when they pass
// surface_normal's regularity test; false where they do not (a degenerate pole
// edge, a fold): then surface_normal must take its limits.
bool normal_from_partials(const NurbsSurface& s, Vec3 Cu, Vec3 Cv, bool reversed, Vec3& n);

// Whether every control point lies within `relative` times the control net's
// extent of one plane: then so does the surface (the convex hull property of
// B-splines, Piegl & Tiller 3.4 and 4.4: also for rational ones, weights > 0).
// A line or a point counts as planar.
bool planar_control_net(const NurbsSurface& s, double relative);

}  // namespace nurbsrt
