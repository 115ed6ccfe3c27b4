// Per-span evaluation tables of a surface's B-spline basis, built once per face
// by prepare(), so that a Newton step evaluates the basis functions and their
// first derivatives by Horner's rule on polynomial coefficients: no division and
// no Cox-de Boor recursion per step (Piegl & Tiller A2.2 costs p(p+1)/2 divisions
// per direction and evaluation, on one dependency chain).
//
// On a non-empty knot span [u_s, u_{s+1}) the p+1 nonzero basis functions are
// polynomials of degree p. In the local parameter x = (u - m) / (h/2), m the
// span's midpoint and h = u_{s+1} - u_s,
//   N_{s-p+r,p}(u) = sum_k c[r][k] x^k,   c[r][k] = N^(k)_{s-p+r,p}(m) (h/2)^k / k!
// (Taylor at the midpoint), the derivatives N^(k) from A2.3 (DersBasisFuns).
// Centred, x lies in [-1, 1] and the coefficients are those of (1+x)^a (1-x)^b
// scaled by 2^-p: no larger than the binomial ones. Expanded at the left end
// instead (t in [0, 1]) they grow like 3^p / 2^p times more, and the Horner sum's
// cancellation cost digits with the degree (measured: 1e-13 at degree 8, 2e-12 at
// 11, against ~1e-15 and ~1e-14 centred). So the Horner sum is as accurate as A2.2
// to a few units in the last place up to degree 11 and to ~2e-13 at 15 (the unit
// tests compare them on uneven, repeated and offset knot vectors and print the
// largest differences per degree).
// The table depends on the knot vector only: the projected surface of a frame
// (project_surface) shares the model surface's table.
#pragma once

#include <cstddef>
#include <vector>

#include "core/scene/nurbs.h"

namespace nurbsrt {

// Degrees tabulated: all that the stack-only A2.2 path takes (kMaxFastDegree).
// CAD surfaces are almost all of degree <= 5 (mostly 1-3), but NURBS conversion
// gives degree 8 and 11 too, and a part with many such faces spent most of its
// primary solves' time on the A2.2 path.
constexpr int kMaxTableDegree = kMaxFastDegree;

// The table of one knot vector.
class KnotSpans {
public:
    KnotSpans() = default;
    // n control points, degree p, knots of size n + p + 1 (clamped). Empty (not
    // usable) when p > kMaxTableDegree or the knot vector has no non-empty span.
    KnotSpans(int n, int p, const std::vector<double>& knots);
    bool usable() const { return !span_.empty(); }

    // Basis values N[0..p] and first derivatives dN[0..p] at t (clamped into the
    // knot range, NaN to its start) and the knot span index s, exactly as
    // find_span + basis_and_derivs give them.
    void basis(double t, int& s, double* N, double* dN) const;
    // The same with the degree known at compile time (kP == the table's degree),
    // so that the loops unroll; kP = -1: the table's degree at run time.
    template <int kP>
    void basis_fixed(double t, int& s, double* N, double* dN) const;
    // The non-empty spans, each span k's knot index s (its p+1 basis functions
    // are N_{s-p..s}), its coefficients c[r][k] ((p+1) x (p+1), row r for
    // N_{s-p+r}) in the local parameter x, and dx/dt there.
    size_t spans() const { return span_.size(); }
    int knot_index(size_t k) const { return span_[k]; }
    const double* coefficients(size_t k) const { return coef_.data() + k * static_cast<size_t>((p_ + 1) * (p_ + 1)); }
    double inv_half(size_t k) const { return inv_half_[k]; }
    // The non-empty span holding t (clamped like find_span) and t's local
    // parameter x in [-1, 1] there.
    size_t locate(double t, double& x) const;
    size_t memory_bytes() const {
        return (start_.capacity() + mid_.capacity() + inv_half_.capacity() + coef_.capacity()) * sizeof(double) +
               span_.capacity() * sizeof(int);
    }

private:
    int p_ = 0;
    std::vector<double> start_;     // left end of each non-empty span, then the last span's right end
    double inv_span_ = 0;           // spans per parameter unit where they are uniform, else 0
    std::vector<int> span_;         // knot index s of each non-empty span
    std::vector<double> mid_;       // midpoint of each non-empty span, the Taylor expansion's centre
    std::vector<double> inv_half_;  // 2 / span length: dx/du
    std::vector<double> coef_;      // per span (p+1) x (p+1): c[r][k]
};

// Both directions of a surface's tables.
struct SurfaceSpans {
    KnotSpans u, v;
    bool usable() const { return u.usable() && v.usable(); }
};
SurfaceSpans make_surface_spans(const NurbsSurface& s);

// evaluate_d1 (nurbs.h) with the basis from the tables; spans must come from
// make_surface_spans of s or of a surface with the same degrees and knots.
SurfaceDerivs evaluate_d1(const NurbsSurface& s, const SurfaceSpans& spans, double u, double v);
// cartesian_d1 (nurbs.h) likewise.
CartesianDerivs cartesian_d1(const NurbsSurface& s, const SurfaceSpans& spans, double u, double v);

}  // namespace nurbsrt
