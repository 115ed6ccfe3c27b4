// B-spline basis functions and homogeneous surface evaluation with first partials.
// Algorithms A2.1 (FindSpan), A2.2 (BasisFuns) and A2.3 (DersBasisFuns, first
// derivatives only) of Piegl & Tiller, "The NURBS Book", 2nd ed.
//
// This is the renderer's hot path: for degrees up to kMaxFastDegree everything
// lives in fixed-size stack arrays (no allocation per call); higher degrees take
// a correct but slower path that allocates.
#pragma once

#include "renderer/scene.h"

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

// Homogeneous point only (cheaper: no derivative basis).
Vec4 evaluate(const NurbsSurface& s, double u, double v);

// Cartesian point and the rational first partials of C = S/w:
//   C_u = (S_u.xyz - C * S_u.w) / w   (quotient rule; The NURBS Book eq. 4.7 / A4.4)
struct CartesianDerivs {
    Vec3 P, Pu, Pv;
};
CartesianDerivs cartesian_d1(const NurbsSurface& s, double u, double v);

// Unit normal of the Cartesian surface, oriented by `reversed` (face orientation).
// Where Pu x Pv vanishes (a degenerate pole edge) the normal is taken from the
// limit: the partials are re-evaluated a small step inside the parameter box.
Vec3 surface_normal(const NurbsSurface& s, double u, double v, bool reversed);

// The unit normal from the rational partials C_u, C_v at a point of s (e.g. a
// Newton iteration's last derivatives), oriented by `reversed`, when they pass
// surface_normal's regularity test; false where they do not (a degenerate pole
// edge, a fold): then surface_normal must take its limits.
bool normal_from_partials(const NurbsSurface& s, Vec3 Cu, Vec3 Cv, bool reversed, Vec3& n);

}  // namespace nurbsrt
