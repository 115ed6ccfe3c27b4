// Per-span evaluation tables of the B-spline basis (see span_basis.h).
#include "renderer/solve/span_basis.h"

#include <algorithm>
#include <array>
#include <cmath>

#include "renderer/solve/degree_dispatch.h"

namespace nurbsrt {
namespace {

constexpr int kM = kMaxTableDegree + 1;
// Span lengths within this ratio of each other count as uniform (locate): the
// span guessed from the mean length is then off by at most 1 % of the span
// count, a step or two on the knot vectors CAD files have.
constexpr double kUniformSpans = 1.01;

// A2.3 (Piegl & Tiller, DersBasisFuns): ders[k][r] = k-th derivative of
// N_{s-p+r,p} at t, k = 0..p, for t in span s.
void ders_basis_funs(int s, double t, int p, const double* U, std::array<std::array<double, kM>, kM>& ders) {
    double ndu[kM][kM], a[2][kM], left[kM], right[kM];
    ndu[0][0] = 1.0;
    for (int j = 1; j <= p; ++j) {
        left[j] = t - U[s + 1 - j];
        right[j] = U[s + j] - t;
        double saved = 0.0;
        for (int r = 0; r < j; ++r) {
            ndu[j][r] = right[r + 1] + left[j - r];  // lower triangle: knot differences
            const double temp = ndu[r][j - 1] / ndu[j][r];
            ndu[r][j] = saved + right[r + 1] * temp;  // upper triangle: basis functions
            saved = left[j - r] * temp;
        }
        ndu[j][j] = saved;
    }
    for (int j = 0; j <= p; ++j) ders[0][j] = ndu[j][p];
    for (int r = 0; r <= p; ++r) {
        int s1 = 0, s2 = 1;
        a[0][0] = 1.0;
        for (int k = 1; k <= p; ++k) {
            double d = 0.0;
            const int rk = r - k, pk = p - k;
            if (r >= k) {
                a[s2][0] = a[s1][0] / ndu[pk + 1][rk];
                d = a[s2][0] * ndu[rk][pk];
            }
            const int j1 = rk >= -1 ? 1 : -rk;
            const int j2 = r - 1 <= pk ? k - 1 : p - r;
            for (int j = j1; j <= j2; ++j) {
                a[s2][j] = (a[s1][j] - a[s1][j - 1]) / ndu[pk + 1][rk + j];
                d += a[s2][j] * ndu[rk + j][pk];
            }
            if (r <= pk) {
                a[s2][k] = -a[s1][k - 1] / ndu[pk + 1][r];
                d += a[s2][k] * ndu[r][pk];
            }
            ders[k][r] = d;
            std::swap(s1, s2);
        }
    }
    double f = p;  // multiply by p! / (p-k)!
    for (int k = 1; k <= p; ++k) {
        for (int j = 0; j <= p; ++j) ders[k][j] *= f;
        f *= p - k;
    }
}

}  // namespace

KnotSpans::KnotSpans(int n, int p, const std::vector<double>& knots) : p_(p) {
    if (p < 0 || p > kMaxTableDegree || n <= p || knots.size() != static_cast<size_t>(n + p + 1)) return;
    const double* U = knots.data();
    std::array<std::array<double, kM>, kM> ders{};
    for (int s = p; s < n; ++s) {
        if (!(U[s] < U[s + 1])) continue;
        const double h = U[s + 1] - U[s], half = 0.5 * h;
        const double mid = U[s] + half;  // rounded: x below is measured from this very value
        ders_basis_funs(s, mid, p, U, ders);
        span_.push_back(s);
        start_.push_back(U[s]);
        mid_.push_back(mid);
        inv_half_.push_back(2.0 / h);
        // Taylor coefficients in x = (u - m) / (h/2), m the span's midpoint:
        // N^(k)(m) (h/2)^k / k!.
        double hk = 1.0;  // (h/2)^k / k!
        const size_t base = coef_.size();
        coef_.resize(base + static_cast<size_t>((p + 1) * (p + 1)));
        for (int k = 0; k <= p; ++k) {
            for (int r = 0; r <= p; ++r) coef_[base + static_cast<size_t>(r * (p + 1) + k)] = ders[k][r] * hk;
            hk *= half / (k + 1);
        }
    }
    if (span_.empty()) return;
    start_.push_back(U[span_.back() + 1]);
    // Spans of (nearly) one length: the span of t is guessed from it and the
    // guess corrected by a step or two (locate), instead of a binary search.
    double shortest = HUGE_VAL, longest = 0;
    for (size_t k = 0; k + 1 < start_.size(); ++k) {
        shortest = std::min(shortest, start_[k + 1] - start_[k]);
        longest = std::max(longest, start_[k + 1] - start_[k]);
    }
    if (span_.size() > 1 && longest <= kUniformSpans * shortest)
        inv_span_ = static_cast<double>(span_.size()) / (start_.back() - start_.front());
}

size_t KnotSpans::locate(double t, double& x) const {
    const size_t nspans = span_.size();
    // The span whose [start, next start) holds t; clamped at both ends like find_span.
    size_t k = 0;
    if (t > start_[0]) {  // false for NaN: the first span
        // Uniform spans: the last span starting at or before t, as the search
        // would find it, from a guess. One span (a Bezier patch, a plane, a
        // cylinder along its axis): nothing to search.
        if (inv_span_ > 0) {
            const double guess = (t - start_[0]) * inv_span_;
            k = guess < static_cast<double>(nspans) ? static_cast<size_t>(guess) : nspans - 1;
            while (k > 0 && start_[k] > t) --k;
            while (k + 1 < nspans && start_[k + 1] <= t) ++k;
        } else if (nspans > 1) {
            k = static_cast<size_t>(std::upper_bound(start_.begin(), start_.end() - 1, t) - start_.begin()) - 1;
        }
        if (k >= nspans) k = nspans - 1;
        t = std::min(t, start_[nspans]);
    } else {
        t = start_[0];
    }
    x = (t - mid_[k]) * inv_half_[k];
    return k;
}

template <int kP>
void KnotSpans::basis_fixed(double t, int& s, double* N, double* dN) const {
    const int p = kP >= 0 ? kP : p_;
    double x;
    const size_t k = locate(t, x);
    s = span_[k];
    const double* c = coef_.data() + k * static_cast<size_t>((p + 1) * (p + 1));
    for (int r = 0; r <= p; ++r, c += p + 1) {
        // Horner for the value and its derivative in x together.
        double val = c[p], der = 0.0;
        for (int q = p - 1; q >= 0; --q) {
            der = der * x + val;
            val = val * x + c[q];
        }
        N[r] = val;
        dN[r] = der * inv_half_[k];
    }
}

void KnotSpans::basis(double t, int& s, double* N, double* dN) const {
    // The degrees NURBS conversion and CAD systems produce, unrolled.
    switch (p_) {
        case 1:
            return basis_fixed<1>(t, s, N, dN);
        case 2:
            return basis_fixed<2>(t, s, N, dN);
        case 3:
            return basis_fixed<3>(t, s, N, dN);
        case 4:
            return basis_fixed<4>(t, s, N, dN);
        case 5:
            return basis_fixed<5>(t, s, N, dN);
        case 6:
            return basis_fixed<6>(t, s, N, dN);
        case 7:
            return basis_fixed<7>(t, s, N, dN);
        case 8:
            return basis_fixed<8>(t, s, N, dN);
        default:
            return basis_fixed<-1>(t, s, N, dN);
    }
}

SurfaceSpans make_surface_spans(const NurbsSurface& s) {
    return {KnotSpans(s.num_u, s.degree_u, s.knots_u), KnotSpans(s.num_v, s.degree_v, s.knots_v)};
}

namespace {

// evaluate_d1 with the degrees as template arguments where they are known (-1:
// read from s at run time), so that the basis and tensor-product loops unroll.
// The same operations in the same order as the run-time loops: the same numbers.
template <int kP, int kQ>
SurfaceDerivs evaluate_fixed(const NurbsSurface& s, const SurfaceSpans& spans, double u, double v) {
    constexpr int kMu = kP >= 0 ? kP + 1 : kM, kMv = kQ >= 0 ? kQ + 1 : kM;
    double Nu[kMu], dNu[kMu], Nv[kMv], dNv[kMv];
    int su = 0, sv = 0;
    if constexpr (kP >= 0)
        spans.u.basis_fixed<kP>(u, su, Nu, dNu);
    else
        spans.u.basis(u, su, Nu, dNu);
    if constexpr (kQ >= 0)
        spans.v.basis_fixed<kQ>(v, sv, Nv, dNv);
    else
        spans.v.basis(v, sv, Nv, dNv);
    const HomogDerivs h = tensor_product<1, kP, kQ>(s, su, sv, Nu, dNu, Nv, dNv);
    return {h.S, h.Su, h.Sv};
}

struct TableEvaluation {
    template <int kP, int kQ>
    static SurfaceDerivs run(const NurbsSurface& s, const SurfaceSpans& spans, double u, double v) {
        return evaluate_fixed<kP, kQ>(s, spans, u, v);
    }
};

}  // namespace

SurfaceDerivs evaluate_d1(const NurbsSurface& s, const SurfaceSpans& spans, double u, double v) {
    if (!spans.usable()) return evaluate_d1(s, u, v);
    return degree_dispatch::with_degrees<TableEvaluation>(s.degree_u, s.degree_v, s, spans, u, v);
}

CartesianDerivs cartesian_d1(const NurbsSurface& s, const SurfaceSpans& spans, double u, double v) {
    return spans.usable() ? cartesian_from(evaluate_d1(s, spans, u, v)) : cartesian_d1(s, u, v);
}

}  // namespace nurbsrt
