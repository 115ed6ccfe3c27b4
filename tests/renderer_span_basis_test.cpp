// Per-span basis tables (renderer/solve/span_basis.h) against the knot search and
// Cox-de Boor evaluation of nurbs.h (Piegl & Tiller A2.1-A2.3), which the
// renderer used in every Newton step before: same span, same values to rounding.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <limits>
#include <random>
#include <vector>

#include "core/scene/nurbs.h"
#include "renderer/solve/span_basis.h"
#include "renderer/solve/surface_patches.h"

namespace {

using namespace nurbsrt;

// A clamped knot vector of degree p for n control points with uneven interior
// spacing, an interior knot of multiplicity p (a C0 joint, like a converted
// face's patch boundary) when there is room, and all knots offset by `origin`
// (parameters far from 0, as some CAD exporters write them).
std::vector<double> knots_for(int n, int p, double origin, double scale) {
    std::vector<double> k(p + 1, origin);
    const int interior = n - p - 1;
    double x = 0;
    for (int i = 0; i < interior; ++i) {
        x += 1.0 + 0.7 * std::sin(3.0 * i + p);  // uneven steps in (0.3, 1.7)
        k.push_back(origin + scale * x);
    }
    x += 1.0;
    for (int r = 0; r <= p; ++r) k.push_back(origin + scale * x);
    // Make one interior knot p-fold where it fits (the vector stays non-decreasing).
    if (interior >= p && p >= 2)
        for (int r = 1; r < p; ++r) k[p + 1 + r] = k[p + 1];
    return k;
}

struct Case {
    int n, p;
    double origin, scale;
};

// The parameters a table is checked at: the knot range's ends, beyond them,
// NaN, every breakpoint (with `neighbours`, also the doubles just below and
// above it), and 400 random ones.
std::vector<double> test_params(const std::vector<double>& U, int n, int p, bool neighbours, std::mt19937& rng) {
    const double lo = U[p], hi = U[n];
    std::vector<double> ts = {lo, hi, lo - 1, hi + 1, std::numeric_limits<double>::quiet_NaN()};
    for (int k = p; k <= n; ++k) {
        ts.push_back(U[k]);
        if (neighbours) {
            ts.push_back(std::nextafter(U[k], -HUGE_VAL));
            ts.push_back(std::nextafter(U[k], HUGE_VAL));
        }
    }
    std::uniform_real_distribution<double> d(lo, hi);
    for (int k = 0; k < 400; ++k) ts.push_back(d(rng));
    return ts;
}

// A table's span and basis at t, and A2.1-A2.2's at t clamped into the knot
// range (NaN: its start), as find_span clamps.
struct Compared {
    int s = -1, sr = -1;
    double N[kMaxTableDegree + 1], dN[kMaxTableDegree + 1], Nr[kMaxTableDegree + 1], dNr[kMaxTableDegree + 1];
};
Compared compare_with_a22(const KnotSpans& spans, int n, int p, const std::vector<double>& U, double t) {
    Compared c;
    spans.basis(t, c.s, c.N, c.dN);
    const double tc = std::isnan(t) ? U[p] : std::clamp(t, U[p], U[n]);
    c.sr = find_span(n, p, tc, U.data());
    basis_and_derivs(c.sr, p, tc, U.data(), c.Nr, c.dNr);
    return c;
}

TEST(SpanBasis, SameSpanAndBasisAsA22) {
    const Case cases[] = {{2, 1, 0, 1},   {4, 2, 0, 1},         {9, 3, 0, 1},      {12, 3, 1000, 0.01},
                          {7, 4, -5, 2},  {11, 5, 0, 1},        {10, 7, 0, 1},     {30, 3, 0, 1e-3},
                          {9, 8, 0, 1},   {20, 8, -3, 0.5},     {24, 8, 100, 0.1}, {10, 9, 0, 1},
                          {12, 10, 0, 1}, {12, 11, 0, 1},       {24, 11, -3, 0.5}, {30, 11, 100, 0.1},
                          {14, 13, 0, 1}, {40, 13, 1000, 0.01}, {16, 15, 0, 1},    {33, 15, -7, 3}};
    std::mt19937 rng(7);
    double worst_N[kMaxTableDegree + 1] = {}, worst_dN[kMaxTableDegree + 1] = {};
    for (const Case& c : cases) {
        SCOPED_TRACE("n=" + std::to_string(c.n) + " p=" + std::to_string(c.p));
        const std::vector<double> U = knots_for(c.n, c.p, c.origin, c.scale);
        const KnotSpans spans(c.n, c.p, U);
        ASSERT_TRUE(spans.usable());
        for (const double t : test_params(U, c.n, c.p, false, rng)) {
            const Compared r = compare_with_a22(spans, c.n, c.p, U, t);
            const double *N = r.N, *dN = r.dN, *Nr = r.Nr, *dNr = r.dNr;
            ASSERT_EQ(r.s, r.sr) << "t=" << t;
            double dmax = 0;
            for (int r = 0; r <= c.p; ++r) dmax = std::max(dmax, std::abs(dNr[r]));
            for (int r = 0; r <= c.p; ++r) worst_N[c.p] = std::max(worst_N[c.p], std::abs(N[r] - Nr[r]));
            for (int r = 0; r <= c.p; ++r) worst_dN[c.p] = std::max(worst_dN[c.p], std::abs(dN[r] - dNr[r]) / dmax);
            for (int r = 0; r <= c.p; ++r) {
                // Basis values are in [0, 1] and sum to 1: absolute error. Derivatives
                // scale with p / h: relative to the largest of them. The power basis's
                // conditioning grows with the degree (measured, printed below: ~1e-15
                // up to degree 10, ~1e-14 at 11-13, ~2e-13 at 15), hence the looser
                // bound above degree 11.
                const double tol = c.p <= 11 ? 1e-13 : 1e-12;
                EXPECT_NEAR(N[r], Nr[r], tol) << "t=" << t << " r=" << r;
                EXPECT_NEAR(dN[r], dNr[r], 10 * tol * dmax) << "t=" << t << " r=" << r;
            }
        }
    }
    for (int p = 1; p <= kMaxTableDegree; ++p)
        std::printf("degree %2d: max |N - N_A2.2| %.1e, max |dN - dN_A2.2| / max |dN| %.1e\n", p, worst_N[p],
                    worst_dN[p]);
}

// Knot vectors of equal (or within 1 % equal) spans: the span of a parameter
// is guessed from the mean span and corrected, instead of searched; the same
// span and basis as A2.1-A2.2, at every breakpoint, the ends, beyond them and
// in between.
TEST(SpanBasis, UniformSpansFoundWithoutSearch) {
    struct Uniform {
        int n, p;
        double origin, step, wobble;  // wobble: relative change of alternate spans
    };
    const Uniform cases[] = {{20, 3, 0, 1, 0},       {50, 2, 1000, 0.01, 0}, {9, 1, -3, 0.25, 0},
                             {64, 3, 0, 0.1, 0.004}, {33, 5, 7, 2, 0.0049},  {12, 3, 0, 1, 0.2}};
    std::mt19937 rng(3);
    for (const Uniform& c : cases) {
        SCOPED_TRACE("n=" + std::to_string(c.n) + " p=" + std::to_string(c.p) + " wobble=" + std::to_string(c.wobble));
        std::vector<double> U(c.p + 1, c.origin);
        double x = c.origin;
        for (int i = 0; i < c.n - c.p; ++i) {
            x += c.step * (1 + (i % 2 ? c.wobble : -c.wobble));
            U.push_back(x);
        }
        for (int r = 0; r < c.p; ++r) U.push_back(x);
        const KnotSpans spans(c.n, c.p, U);
        ASSERT_TRUE(spans.usable());
        for (const double t : test_params(U, c.n, c.p, true, rng)) {
            const Compared r = compare_with_a22(spans, c.n, c.p, U, t);
            ASSERT_EQ(r.s, r.sr) << "t=" << t;
            for (int q = 0; q <= c.p; ++q) EXPECT_NEAR(r.N[q], r.Nr[q], 1e-13) << "t=" << t << " r=" << q;
        }
    }
}

// Every way evaluate_d1 takes with the tables, and with the power-form patches
// made over them: both degrees unrolled (up to 3; one of them 1 and the other
// up to 11; equal up to 11), the v degree unrolled (up to 11), neither (above),
// rational or not.
TEST(SpanBasis, SurfaceEvaluationMatches) {
    const struct {
        int p, q;
        bool rational;
    } degrees[] = {{1, 1, false},  {1, 2, true},  {2, 1, true},    {2, 2, true},   {3, 2, true},    {2, 3, true},
                   {3, 3, false},  {1, 3, false}, {3, 1, true},    {5, 5, false},  {5, 1, false},   {1, 8, false},
                   {8, 1, false},  {4, 7, true},  {8, 11, false},  {11, 3, true},  {12, 12, false}, {1, 11, true},
                   {11, 1, false}, {7, 7, true},  {11, 11, false}, {1, 12, false}, {12, 1, true},   {12, 5, false}};
    std::mt19937 rng(11);
    for (const auto& d : degrees) {
        SCOPED_TRACE("degrees " + std::to_string(d.p) + " x " + std::to_string(d.q));
        NurbsSurface s;
        s.degree_u = d.p;
        s.degree_v = d.q;
        s.num_u = d.p + 6;
        s.num_v = d.q + 3;
        s.knots_u = knots_for(s.num_u, s.degree_u, 0, 1);
        s.knots_v = knots_for(s.num_v, s.degree_v, 10, 0.5);
        s.rational = d.rational;
        std::uniform_real_distribution<double> c(-50, 50), w(0.5, 2);
        for (int k = 0; k < s.num_u * s.num_v; ++k) {
            const double wk = d.rational ? w(rng) : 1.0;
            s.cp.push_back({wk * c(rng), wk * c(rng), wk * c(rng), wk});
        }
        const SurfaceSpans spans = make_surface_spans(s);
        ASSERT_TRUE(spans.usable());
        const SurfacePatches patches = make_surface_patches(s, spans);
        ASSERT_TRUE(patches.usable());
        std::uniform_real_distribution<double> uu(s.u_begin(), s.u_end()), vv(s.v_begin(), s.v_end());
        const double scale = 100 * 2 * std::max(s.num_u, s.num_v);  // control-point size times a derivative's p / h
        for (int k = 0; k < 500; ++k) {
            const double u = uu(rng), v = vv(rng);
            const SurfaceDerivs a = evaluate_d1(s, spans, u, v), b = evaluate_d1(s, u, v);
            const SurfaceDerivs c = evaluate_d1(patches, spans, u, v);
            for (const auto& [x, y] : {std::pair{a.S, b.S}, std::pair{a.Su, b.Su}, std::pair{a.Sv, b.Sv},
                                       std::pair{c.S, b.S}, std::pair{c.Su, b.Su}, std::pair{c.Sv, b.Sv}}) {
                EXPECT_NEAR(x.x, y.x, 1e-12 * scale);
                EXPECT_NEAR(x.y, y.y, 1e-12 * scale);
                EXPECT_NEAR(x.z, y.z, 1e-12 * scale);
                EXPECT_NEAR(x.w, y.w, 1e-12 * scale);
            }
            const CartesianDerivs ca = cartesian_d1(s, spans, u, v), cb = cartesian_d1(s, u, v);
            EXPECT_NEAR(length(ca.P - cb.P), 0, 1e-11 * scale);
            EXPECT_NEAR(length(ca.Pu - cb.Pu), 0, 1e-10 * scale);
        }
    }
}

// A face whose patches would hold more coefficients than the cap (a hostile
// file's one face of very many spans) gets none; the basis tables still serve.
TEST(SpanBasis, PatchesAreCappedPerFace) {
    NurbsSurface s;
    s.degree_u = s.degree_v = 3;
    s.num_u = s.num_v = 200;  // 197 x 197 spans, 16 coefficients each: 621k
    s.knots_u = s.knots_v = knots_for(s.num_u, s.degree_u, 0, 1);
    s.cp.assign(static_cast<size_t>(s.num_u) * s.num_v, Vec4{1, 2, 3, 1});
    const SurfaceSpans spans = make_surface_spans(s);
    ASSERT_TRUE(spans.usable());
    EXPECT_FALSE(make_surface_patches(s, spans).usable());
    s.num_u = 20;  // 17 x 197 spans: 54k
    s.knots_u = knots_for(s.num_u, s.degree_u, 0, 1);
    s.cp.resize(static_cast<size_t>(s.num_u) * s.num_v);
    EXPECT_TRUE(make_surface_patches(s, make_surface_spans(s)).usable());
}

TEST(SpanBasis, HighDegreesAndBadKnotsFallBack) {
    // Above kMaxTableDegree no table is made; evaluate_d1 then takes A2.2 itself.
    NurbsSurface s;
    s.degree_u = s.degree_v = kMaxTableDegree + 2;
    s.num_u = s.num_v = s.degree_u + 1;
    s.knots_u = s.knots_v = knots_for(s.num_u, s.degree_u, 0, 1);
    for (int k = 0; k < s.num_u * s.num_v; ++k) s.cp.push_back({double(k % 7), double(k % 5), double(k % 3), 1.0});
    const SurfaceSpans spans = make_surface_spans(s);
    EXPECT_FALSE(spans.usable());
    const SurfaceDerivs a = evaluate_d1(s, spans, 0.3, 0.6), b = evaluate_d1(s, 0.3, 0.6);
    EXPECT_EQ(a.S.x, b.S.x);
    EXPECT_EQ(a.Su.y, b.Su.y);
    // A knot vector of the wrong length, or with no non-empty span, gives no table.
    EXPECT_FALSE(KnotSpans(4, 2, {0, 0, 0, 1, 1, 1}).usable());
    EXPECT_FALSE(KnotSpans(3, 2, {0, 0, 0, 0, 0, 0}).usable());
}

}  // namespace
