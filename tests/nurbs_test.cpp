// Analytic checks of the NURBS evaluation core (core/scene/nurbs.h).
#include "core/scene/nurbs.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

using namespace nurbsrt;

namespace {

const double kS = std::sqrt(2.0) / 2.0;  // weight of a quarter-circle's middle control point

// Builds a surface from Cartesian control points and weights (u-major, [i * nv + j]).
NurbsSurface make_surface(int p, int q, std::vector<double> ku, std::vector<double> kv, const std::vector<Vec3>& pts,
                          const std::vector<double>& w = {}) {
    NurbsSurface s;
    s.degree_u = p;
    s.degree_v = q;
    s.num_u = static_cast<int>(ku.size()) - p - 1;
    s.num_v = static_cast<int>(kv.size()) - q - 1;
    s.knots_u = std::move(ku);
    s.knots_v = std::move(kv);
    EXPECT_EQ(pts.size(), static_cast<size_t>(s.num_u * s.num_v));
    s.rational = !w.empty();
    for (size_t k = 0; k < pts.size(); ++k) {
        const double wk = w.empty() ? 1.0 : w[k];
        s.cp.push_back({wk * pts[k].x, wk * pts[k].y, wk * pts[k].z, wk});
    }
    return s;
}

std::vector<double> clamped_bezier_knots(int p) {
    std::vector<double> k(p + 1, 0.0);
    k.insert(k.end(), p + 1, 1.0);
    return k;
}

// Swaps the roles of u and v (transposes the control net).
NurbsSurface transpose(const NurbsSurface& s) {
    NurbsSurface t;
    t.degree_u = s.degree_v;
    t.degree_v = s.degree_u;
    t.num_u = s.num_v;
    t.num_v = s.num_u;
    t.knots_u = s.knots_v;
    t.knots_v = s.knots_u;
    t.rational = s.rational;
    t.cp.resize(s.cp.size());
    for (int i = 0; i < s.num_u; ++i)
        for (int j = 0; j < s.num_v; ++j) t.cp[static_cast<size_t>(j) * t.num_v + i] = s.at(i, j);
    return t;
}

// Full sphere of radius R about c as one rational biquadratic surface with doubled
// interior knots: u is longitude (9-point circle, knots at quarters), v runs from the
// south pole (v = 0) to the north pole (v = 1) (5-point semicircle). Both v-edges are
// collapsed rows of control points: the poles.
NurbsSurface make_sphere(double R, Vec3 c) {
    const double cx[9] = {1, 1, 0, -1, -1, -1, 0, 1, 1};
    const double cy[9] = {0, 1, 1, 1, 0, -1, -1, -1, 0};
    const double cw[9] = {1, kS, 1, kS, 1, kS, 1, kS, 1};
    const double mr[5] = {0, 1, 1, 1, 0};
    const double mz[5] = {-1, -1, 0, 1, 1};
    const double mw[5] = {1, kS, 1, kS, 1};
    std::vector<Vec3> pts;
    std::vector<double> w;
    for (int i = 0; i < 9; ++i)
        for (int j = 0; j < 5; ++j) {
            pts.push_back(c + R * Vec3{cx[i] * mr[j], cy[i] * mr[j], mz[j]});
            w.push_back(cw[i] * mw[j]);
        }
    return make_surface(2, 2, {0, 0, 0, .25, .25, .5, .5, .75, .75, 1, 1, 1}, {0, 0, 0, .5, .5, 1, 1, 1}, pts, w);
}

// 1D de Casteljau on homogeneous points (degree = pts.size() - 1).
Vec4 de_casteljau(std::vector<Vec4> pts, double t) {
    for (size_t k = pts.size() - 1; k > 0; --k)
        for (size_t i = 0; i < k; ++i) pts[i] = (1 - t) * pts[i] + t * pts[i + 1];
    return pts[0];
}

// Derivative of a Bezier curve: n * Bezier of the forward differences.
Vec4 de_casteljau_d(const std::vector<Vec4>& pts, double t) {
    const size_t n = pts.size() - 1;
    std::vector<Vec4> d(n);
    for (size_t i = 0; i < n; ++i) d[i] = static_cast<double>(n) * (pts[i + 1] - pts[i]);
    return de_casteljau(d, t);
}

// Reference evaluation of a tensor-product Bezier patch (homogeneous S, Su, Sv).
SurfaceDerivs bezier_reference(const NurbsSurface& s, double u, double v) {
    std::vector<Vec4> Q(s.num_u), Qv(s.num_u);
    for (int i = 0; i < s.num_u; ++i) {
        std::vector<Vec4> row(s.cp.begin() + static_cast<long>(i) * s.num_v,
                              s.cp.begin() + static_cast<long>(i + 1) * s.num_v);
        Q[i] = de_casteljau(row, v);
        Qv[i] = de_casteljau_d(row, v);
    }
    return {de_casteljau(Q, u), de_casteljau_d(Q, u), de_casteljau(Qv, u)};
}

double max_abs_diff(Vec4 a, Vec4 b) {
    return std::fmax(std::fmax(std::fabs(a.x - b.x), std::fabs(a.y - b.y)),
                     std::fmax(std::fabs(a.z - b.z), std::fabs(a.w - b.w)));
}
double dist(Vec3 a, Vec3 b) { return length(a - b); }

// Central finite differences of the Cartesian surface.
void fd_partials(const NurbsSurface& s, double u, double v, double h, Vec3& fu, Vec3& fv) {
    fu = (project(evaluate(s, u + h, v)) - project(evaluate(s, u - h, v))) / (2 * h);
    fv = (project(evaluate(s, u, v + h)) - project(evaluate(s, u, v - h))) / (2 * h);
}

std::vector<double> knot_vector_with_repeats(int p) {
    // Interior knots: simple, double, multiplicity p (C0 joint), simple, non-uniform.
    std::vector<double> k(p + 1, 0.0);
    for (double t : {0.1, 0.3, 0.3}) k.push_back(t);
    k.insert(k.end(), p, 0.5);
    k.push_back(0.8);
    k.insert(k.end(), p + 1, 1.0);
    return k;
}

}  // namespace

TEST(FindSpan, KnotsEndsAndClamping) {
    // n = 7 control points, p = 2; knot 2 has multiplicity 2.
    const double U[] = {0, 0, 0, 1, 2, 2, 3, 4, 4, 4};
    const int n = 7, p = 2;
    EXPECT_EQ(find_span(n, p, 0.0, U), 2);
    EXPECT_EQ(find_span(n, p, 0.5, U), 2);
    EXPECT_EQ(find_span(n, p, 1.0, U), 3);
    EXPECT_EQ(find_span(n, p, 1.999, U), 3);
    EXPECT_EQ(find_span(n, p, 2.0, U), 5);  // repeated knot: span [2,3)
    EXPECT_EQ(find_span(n, p, 3.0, U), 6);
    EXPECT_EQ(find_span(n, p, 3.999, U), 6);
    EXPECT_EQ(find_span(n, p, 4.0, U), 6);  // end knot: last non-empty span
    EXPECT_EQ(find_span(n, p, -1.0, U), 2);
    EXPECT_EQ(find_span(n, p, 7.0, U), 6);
    EXPECT_EQ(find_span(n, p, std::nan(""), U), 2);
    // Every result is a non-empty span containing t.
    for (int k = 0; k <= 400; ++k) {
        const double t = 4.0 * k / 400;
        const int s = find_span(n, p, t, U);
        ASSERT_GE(s, p);
        ASSERT_LE(s, n - 1);
        EXPECT_LT(U[s], U[s + 1]);
        EXPECT_LE(U[s], t);
        if (t < 4.0) {
            EXPECT_LT(t, U[s + 1]);
        }
    }
    // Degree 1, two control points (a single span).
    const double L[] = {0, 0, 1, 1};
    EXPECT_EQ(find_span(2, 1, 0.0, L), 1);
    EXPECT_EQ(find_span(2, 1, 1.0, L), 1);
}

TEST(Basis, PartitionOfUnityAndDerivativeSumZero) {
    double worst_sum = 0, worst_dsum = 0, worst_fd = 0;
    for (int p = 1; p <= 20; ++p) {  // crosses kMaxFastDegree
        const std::vector<double> U = knot_vector_with_repeats(p);
        const int n = static_cast<int>(U.size()) - p - 1;
        std::vector<double> N(p + 1), dN(p + 1), Na(p + 1), dNa(p + 1), Nb(p + 1), dNb(p + 1);
        std::vector<double> ts;
        for (int k = 0; k <= 1000; ++k) ts.push_back(k / 1000.0);
        for (double t : U) ts.push_back(t);  // exactly at every knot
        for (double t : ts) {
            const int s = find_span(n, p, t, U.data());
            basis_and_derivs(s, p, t, U.data(), N.data(), dN.data());
            double sum = 0, dsum = 0, dmax = 0;
            for (int r = 0; r <= p; ++r) {
                EXPECT_GE(N[r], -1e-15) << "p=" << p << " t=" << t;
                sum += N[r];
                dsum += dN[r];
                dmax = std::fmax(dmax, std::fabs(dN[r]));
            }
            worst_sum = std::fmax(worst_sum, std::fabs(sum - 1));
            worst_dsum = std::fmax(worst_dsum, std::fabs(dsum) / std::fmax(1.0, dmax));
            EXPECT_NEAR(sum, 1.0, 1e-13) << "p=" << p << " t=" << t;
            EXPECT_NEAR(dsum, 0.0, 1e-12 * std::fmax(1.0, dmax)) << "p=" << p << " t=" << t;
            // Derivatives against central differences inside the same span.
            const double h = 1e-6;
            if (t - h > 0 && t + h < 1 && find_span(n, p, t - h, U.data()) == s &&
                find_span(n, p, t + h, U.data()) == s) {
                basis_and_derivs(s, p, t - h, U.data(), Na.data(), dNa.data());
                basis_and_derivs(s, p, t + h, U.data(), Nb.data(), dNb.data());
                for (int r = 0; r <= p; ++r) {
                    const double fd = (Nb[r] - Na[r]) / (2 * h);
                    const double err = std::fabs(fd - dN[r]) / std::fmax(1.0, dmax);
                    worst_fd = std::fmax(worst_fd, err);
                    EXPECT_LT(err, 1e-5) << "p=" << p << " t=" << t << " r=" << r;
                }
            }
        }
    }
    std::printf(
        "[ figures  ] basis: max |sum N - 1| = %.3g, max |sum dN|/max|dN| = %.3g, "
        "max rel |dN - FD| = %.3g\n",
        worst_sum, worst_dsum, worst_fd);
}

TEST(Basis, EndKnotValuesAreExact) {
    // At the clamped ends only the first/last basis function is 1.
    const std::vector<double> U = knot_vector_with_repeats(3);
    const int p = 3, n = static_cast<int>(U.size()) - p - 1;
    double N[4], dN[4];
    int s = find_span(n, p, 1.0, U.data());
    basis_and_derivs(s, p, 1.0, U.data(), N, dN);
    EXPECT_EQ(N[3], 1.0);
    EXPECT_EQ(N[0] + N[1] + N[2], 0.0);
    s = find_span(n, p, 0.0, U.data());
    basis_and_derivs(s, p, 0.0, U.data(), N, dN);
    EXPECT_EQ(N[0], 1.0);
    // Degree-p curve clamped: N'_0(0) = -p / (u_{p+1} - u_1).
    EXPECT_NEAR(dN[0], -3.0 / 0.1, 1e-12);
}

TEST(Surface, BilinearPatch) {
    const Vec3 P00{0, 0, 0}, P01{0, 1, 1}, P10{2, 0, 0}, P11{1, 1, 0.5};
    const NurbsSurface s = make_surface(1, 1, {0, 0, 1, 1}, {-1, -1, 3, 3}, {P00, P01, P10, P11});
    for (int a = 0; a <= 10; ++a)
        for (int b = 0; b <= 10; ++b) {
            const double u = a / 10.0, v = -1 + 4 * b / 10.0, t = (v + 1) / 4;
            const Vec3 ref = (1 - u) * (1 - t) * P00 + (1 - u) * t * P01 + u * (1 - t) * P10 + u * t * P11;
            const Vec3 ru = (1 - t) * (P10 - P00) + t * (P11 - P01);
            const Vec3 rv = 0.25 * ((1 - u) * (P01 - P00) + u * (P11 - P10));
            const CartesianDerivs d = cartesian_d1(s, u, v);
            EXPECT_LT(dist(d.P, ref), 1e-15);
            EXPECT_LT(dist(d.Pu, ru), 1e-15);
            EXPECT_LT(dist(d.Pv, rv), 1e-15);
            EXPECT_EQ(evaluate(s, u, v).w, 1.0);
        }
    // Corners exactly, and clamping outside the knot range.
    EXPECT_LT(dist(project(evaluate(s, 1, 3)), P11), 1e-15);
    EXPECT_LT(dist(project(evaluate(s, 5, 9)), P11), 1e-15);
    EXPECT_LT(dist(project(evaluate(s, -5, -9)), P00), 1e-15);
    EXPECT_LT(dist(project(evaluate(s, -5, 9)), P01), 1e-15);
}

TEST(Surface, PiecewiseLinearPlane) {
    // Degree 1 with interior knots: a plane z = 0 parametrized piecewise linearly.
    std::vector<Vec3> pts;
    const double xs[4] = {0, 1, 3, 6};
    for (double x : xs)
        for (double y : {0.0, 2.0}) pts.push_back({x, y, 0});
    const NurbsSurface s = make_surface(1, 1, {0, 0, 0.25, 0.5, 1, 1}, {0, 0, 1, 1}, pts);
    EXPECT_LT(dist(project(evaluate(s, 0.25, 0.5)), Vec3{1, 1, 0}), 1e-15);
    EXPECT_LT(dist(project(evaluate(s, 0.75, 0.5)), Vec3{4.5, 1, 0}), 1e-15);
    EXPECT_LT(dist(project(evaluate(s, 1.0, 1.0)), Vec3{6, 2, 0}), 1e-15);
    const CartesianDerivs d = cartesian_d1(s, 0.75, 0.5);
    EXPECT_NEAR(d.Pu.x, 6.0, 1e-14);  // (6 - 3) / 0.5
    EXPECT_NEAR(d.Pv.y, 2.0, 1e-14);
    const Vec3 n = surface_normal(s, 0.3, 0.2, false);
    EXPECT_LT(dist(n, Vec3{0, 0, 1}), 1e-15);
    EXPECT_LT(dist(surface_normal(s, 0.3, 0.2, true), Vec3{0, 0, -1}), 1e-15);
}

TEST(Surface, PlanarControlNet) {
    // A plane tilted out of every axis, piecewise linear with interior knots: planar.
    std::vector<Vec3> pts;
    for (double x : {0.0, 1.0, 3.0, 6.0})
        for (double y : {0.0, 2.0}) pts.push_back({x, y, 0.5 * x - 0.25 * y + 7});
    const NurbsSurface plane = make_surface(1, 1, {0, 0, 0.25, 0.5, 1, 1}, {0, 0, 1, 1}, pts);
    EXPECT_TRUE(planar_control_net(plane, 1e-9));
    // One control point lifted off that plane by 1e-6 of the net's extent: not planar.
    NurbsSurface bent = plane;
    bent.cp[3].z += 1e-6 * 6.5;
    EXPECT_FALSE(planar_control_net(bent, 1e-9));
    EXPECT_TRUE(planar_control_net(bent, 1e-5));
    // Rational: a quarter cylinder (weights != 1) and a sphere are curved.
    const std::vector<Vec3> cyl = {{1, 0, 0}, {1, 0, 2}, {1, 1, 0}, {1, 1, 2}, {0, 1, 0}, {0, 1, 2}};
    EXPECT_FALSE(
        planar_control_net(make_surface(2, 1, {0, 0, 0, 1, 1, 1}, {0, 0, 1, 1}, cyl, {1, 1, kS, kS, 1, 1}), 1e-9));
    EXPECT_FALSE(planar_control_net(make_sphere(2.0, Vec3{0, 0, 0}), 1e-9));
    // A degenerate net (all points on one line) counts as planar.
    const std::vector<Vec3> diagonal = {{0, 0, 0}, {1, 1, 1}, {2, 2, 2}, {3, 3, 3}};
    EXPECT_TRUE(planar_control_net(make_surface(1, 1, {0, 0, 1, 1}, {0, 0, 1, 1}, diagonal), 1e-9));
}

TEST(Surface, RationalQuarterCylinder) {
    // u: exact quarter circle of radius 1 (weights 1, sqrt(2)/2, 1); v: height 0..2.
    const std::vector<Vec3> pts = {{1, 0, 0}, {1, 0, 2}, {1, 1, 0}, {1, 1, 2}, {0, 1, 0}, {0, 1, 2}};
    const std::vector<double> w = {1, 1, kS, kS, 1, 1};
    const NurbsSurface s = make_surface(2, 1, {0, 0, 0, 1, 1, 1}, {0, 0, 1, 1}, pts, w);
    double worst_r = 0, worst_fd = 0, worst_n = 0;
    for (int a = 0; a <= 200; ++a)
        for (int b = 0; b <= 4; ++b) {
            const double u = a / 200.0, v = b / 4.0;
            const CartesianDerivs d = cartesian_d1(s, u, v);
            const double r = std::hypot(d.P.x, d.P.y);
            worst_r = std::fmax(worst_r, std::fabs(r - 1));
            EXPECT_NEAR(r, 1.0, 1e-14) << u;
            EXPECT_NEAR(d.P.z, 2 * v, 1e-15);
            EXPECT_GE(d.P.x, -1e-15);
            EXPECT_GE(d.P.y, -1e-15);
            // Outward normal of the cylinder.
            const Vec3 n = surface_normal(s, u, v, false);
            worst_n = std::fmax(worst_n, dist(n, Vec3{d.P.x, d.P.y, 0} / r));
            EXPECT_LT(dist(n, Vec3{d.P.x, d.P.y, 0} / r), 1e-14);
            if (a > 0 && a < 200) {
                Vec3 fu, fv;
                fd_partials(s, u, v, 1e-6, fu, fv);
                worst_fd = std::fmax(worst_fd, dist(fu, d.Pu));
                EXPECT_LT(dist(fu, d.Pu), 1e-8);
                if (b > 0 && b < 4) {  // FD in v is one-sided (clamped) at the ends
                    worst_fd = std::fmax(worst_fd, dist(fv, d.Pv));
                    EXPECT_LT(dist(fv, d.Pv), 1e-8);
                }
                // The tangent is perpendicular to the radius.
                EXPECT_NEAR(dot(d.Pu, Vec3{d.P.x, d.P.y, 0}), 0.0, 1e-14);
            }
        }
    // Ends of the arc, exactly at the end knot.
    EXPECT_LT(dist(project(evaluate(s, 0, 0)), Vec3{1, 0, 0}), 1e-15);
    EXPECT_LT(dist(project(evaluate(s, 1, 1)), Vec3{0, 1, 2}), 1e-15);
    // Midpoint of the arc is at 45 degrees.
    const Vec3 m = project(evaluate(s, 0.5, 0));
    EXPECT_NEAR(m.x, kS, 1e-15);
    EXPECT_NEAR(m.y, kS, 1e-15);
    std::printf(
        "[ figures  ] quarter cylinder: max |r - 1| = %.3g, max |partial - FD| = %.3g, "
        "max |n - n_exact| = %.3g\n",
        worst_r, worst_fd, worst_n);
}

TEST(Surface, RationalSphereRadiusPartialsAndNormals) {
    const double R = 3.5;
    const Vec3 c{1, -2, 0.5};
    const NurbsSurface s = make_sphere(R, c);
    double worst_r = 0, worst_fd = 0, worst_n = 0;
    for (int a = 0; a <= 160; ++a)
        for (int b = 0; b <= 80; ++b) {
            const double u = a / 160.0, v = b / 80.0;
            const CartesianDerivs d = cartesian_d1(s, u, v);
            const double r = length(d.P - c);
            worst_r = std::fmax(worst_r, std::fabs(r - R) / R);
            EXPECT_NEAR(r, R, 1e-14 * R) << u << " " << v;
            const Vec3 exact = (d.P - c) / R;
            const Vec3 n = surface_normal(s, u, v, false);
            worst_n = std::fmax(worst_n, dist(n, exact));
            EXPECT_LT(dist(n, exact), 1e-13) << u << " " << v;
            EXPECT_LT(dist(surface_normal(s, u, v, true), -exact), 1e-13);
            // Finite differences away from the C1 joints (knots) and the ends.
            const double h = 1e-6;
            bool near_knot = false;
            for (double k : {0.0, 0.25, 0.5, 0.75, 1.0}) near_knot |= std::fabs(u - k) < 2 * h;
            for (double k : {0.0, 0.5, 1.0}) near_knot |= std::fabs(v - k) < 2 * h;
            if (!near_knot) {
                Vec3 fu, fv;
                fd_partials(s, u, v, h, fu, fv);
                const double e = std::fmax(dist(fu, d.Pu), dist(fv, d.Pv)) / R;
                worst_fd = std::fmax(worst_fd, e);
                EXPECT_LT(e, 1e-8);
            }
        }
    std::printf(
        "[ figures  ] sphere: max |r - R|/R = %.3g, max rel |partial - FD| = %.3g, "
        "max |n - n_exact| (incl. poles) = %.3g\n",
        worst_r, worst_fd, worst_n);
}

TEST(Surface, SpherePoleNormal) {
    const double R = 2.0;
    const Vec3 c{0, 0, 0};
    const NurbsSurface s = make_sphere(R, c);
    // At the poles P_u vanishes exactly: the regular cross product is zero.
    const CartesianDerivs d = cartesian_d1(s, 0.3, 1.0);
    EXPECT_LT(length(d.Pu), 1e-14);
    EXPECT_LT(length(cross(d.Pu, d.Pv)), 1e-13);
    double worst_near = 0;
    for (double u : {0.0, 0.1, 0.25, 0.3, 0.6, 0.99, 1.0}) {
        const Vec3 north = surface_normal(s, u, 1.0, false);
        const Vec3 south = surface_normal(s, u, 0.0, false);
        EXPECT_TRUE(std::isfinite(north.x) && std::isfinite(north.y) && std::isfinite(north.z));
        EXPECT_LT(dist(north, Vec3{0, 0, 1}), 1e-14) << u;
        EXPECT_LT(dist(south, Vec3{0, 0, -1}), 1e-14) << u;
        EXPECT_LT(dist(surface_normal(s, u, 1.0, true), Vec3{0, 0, -1}), 1e-14) << u;
        EXPECT_LT(dist(surface_normal(s, u, 0.0, true), Vec3{0, 0, 1}), 1e-14) << u;
        // Just inside the pole (both sides of the degeneracy threshold) and outside the range.
        for (double h : {1e-15, 1e-12, 1e-9, 1e-8, 1e-7, 1e-5}) {
            const Vec3 exact = (project(evaluate(s, u, 1 - h)) - c) / R;
            const double e = dist(surface_normal(s, u, 1 - h, false), exact);
            worst_near = std::fmax(worst_near, e);
            EXPECT_LT(e, 1e-6) << u << " " << h;
        }
        EXPECT_LT(dist(surface_normal(s, u, 1.5, false), Vec3{0, 0, 1}), 1e-14);
    }
    std::printf("[ figures  ] sphere pole: max |n - n_exact| within 1e-15..1e-5 of the pole = %.3g\n", worst_near);
    // The same sphere with u and v swapped: now P_v vanishes on the edges u = 0, 1,
    // and the orientation flips (P_v x P_u): normals point inward.
    const NurbsSurface t = transpose(s);
    for (double v : {0.0, 0.2, 0.5, 1.0}) {
        EXPECT_LT(dist(surface_normal(t, 1.0, v, false), Vec3{0, 0, -1}), 1e-14) << v;
        EXPECT_LT(dist(surface_normal(t, 0.0, v, false), Vec3{0, 0, 1}), 1e-14) << v;
        EXPECT_LT(dist(surface_normal(t, 0.0, v, true), Vec3{0, 0, -1}), 1e-14) << v;
    }
}

TEST(Surface, CollapsedEdgeNonSphere) {
    // A bicubic "tip" patch (like the duck body's nose): the whole row i = 0 collapses to
    // the apex (0,0,1); the surface is a smooth cap z = 1 - x^2 - y^2 near it.
    // Control net: P_ij = apex for i = 0, else points of the paraboloid on rays.
    std::vector<Vec3> pts;
    const int nu = 4, nv = 4;
    for (int i = 0; i < nu; ++i)
        for (int j = 0; j < nv; ++j) {
            const double r = i / 3.0, th = (j / 3.0) * 1.2;
            pts.push_back({r * std::cos(th), r * std::sin(th), 1 - r * r});
        }
    const NurbsSurface s = make_surface(3, 3, clamped_bezier_knots(3), clamped_bezier_knots(3), pts);
    // Reference: the normal a tiny step inside, computed by the regular formula.
    for (double v : {0.0, 0.3, 0.7, 1.0}) {
        const Vec3 n0 = surface_normal(s, 0.0, v, false);
        const Vec3 n1 = surface_normal(s, 1e-6, v, false);
        EXPECT_TRUE(std::isfinite(n0.x) && std::isfinite(n0.y) && std::isfinite(n0.z));
        EXPECT_NEAR(length(n0), 1.0, 1e-14);
        EXPECT_LT(dist(n0, n1), 1e-5) << v;
        EXPECT_LT(dist(surface_normal(s, 0.0, v, true), -n0), 1e-15);
    }
}

TEST(Surface, HighDegreeBezierMatchesDeCasteljau) {
    std::mt19937_64 rng(42);
    std::uniform_real_distribution<double> coord(-1, 1), weight(0.5, 2);
    for (auto [p, q] : {std::pair{15, 15}, std::pair{15, 3}, std::pair{20, 20}, std::pair{20, 2}, std::pair{3, 20}}) {
        std::vector<Vec3> pts;
        std::vector<double> w;
        for (int k = 0; k < (p + 1) * (q + 1); ++k) {
            pts.push_back({coord(rng), coord(rng), coord(rng)});
            w.push_back(weight(rng));
        }
        const NurbsSurface s = make_surface(p, q, clamped_bezier_knots(p), clamped_bezier_knots(q), pts, w);
        double worst_s = 0, worst_d = 0;
        for (int a = 0; a <= 20; ++a)
            for (int b = 0; b <= 20; ++b) {
                const double u = a / 20.0, v = b / 20.0;
                const SurfaceDerivs d = evaluate_d1(s, u, v);
                const SurfaceDerivs ref = bezier_reference(s, u, v);
                worst_s = std::fmax(worst_s, max_abs_diff(d.S, ref.S));
                worst_d = std::fmax(worst_d,
                                    std::fmax(max_abs_diff(d.Su, ref.Su), max_abs_diff(d.Sv, ref.Sv)) / std::max(p, q));
                EXPECT_EQ(evaluate(s, u, v).w, d.S.w);  // same basis code for both entry points
            }
        EXPECT_LT(worst_s, 1e-13) << p << "x" << q;
        EXPECT_LT(worst_d, 1e-12) << p << "x" << q;
        std::printf(
            "[ figures  ] Bezier %dx%d (%s path): max |S - deCasteljau| = %.3g, "
            "max |dS - ref| / degree = %.3g\n",
            p, q, std::max(p, q) <= kMaxFastDegree ? "fast" : "slow", worst_s, worst_d);
    }
}

TEST(Surface, GeneralPartialsMatchFiniteDifferences) {
    // Non-uniform rational B-spline with repeated interior knots, degrees (3, 2).
    std::mt19937_64 rng(7);
    std::uniform_real_distribution<double> jitter(-0.3, 0.3), weight(0.5, 2);
    const std::vector<double> ku = {0, 0, 0, 0, 0.2, 0.2, 0.45, 0.7, 1, 1, 1, 1};
    const std::vector<double> kv = {-2, -2, -2, -1, 0.5, 0.5, 3, 3, 3};
    const int nu = static_cast<int>(ku.size()) - 4, nv = static_cast<int>(kv.size()) - 3;
    std::vector<Vec3> pts;
    std::vector<double> w;
    for (int i = 0; i < nu; ++i)
        for (int j = 0; j < nv; ++j) {
            pts.push_back({i + jitter(rng), j + jitter(rng), std::sin(i * 0.7) + jitter(rng)});
            w.push_back(weight(rng));
        }
    const NurbsSurface s = make_surface(3, 2, ku, kv, pts, w);
    std::uniform_real_distribution<double> U(0, 1), V(-2, 3);
    double worst = 0;
    int checked = 0;
    for (int k = 0; k < 2000; ++k) {
        const double u = U(rng), v = V(rng), h = 1e-6;
        bool near = false;
        for (double t : ku) near |= std::fabs(u - t) < 2 * h;
        for (double t : kv) near |= std::fabs(v - t) < 2 * h;
        if (near) continue;
        const CartesianDerivs d = cartesian_d1(s, u, v);
        Vec3 fu, fv;
        fd_partials(s, u, v, h, fu, fv);
        const double e =
            std::fmax(dist(fu, d.Pu) / std::fmax(1.0, length(d.Pu)), dist(fv, d.Pv) / std::fmax(1.0, length(d.Pv)));
        worst = std::fmax(worst, e);
        EXPECT_LT(e, 1e-7) << u << " " << v;
        EXPECT_LT(dist(d.P, project(evaluate(s, u, v))), 1e-14);
        // The normal is the normalized cross product of the partials.
        EXPECT_LT(dist(surface_normal(s, u, v, false), normalize(cross(d.Pu, d.Pv))), 1e-14);
        ++checked;
    }
    EXPECT_GT(checked, 1900);
    std::printf("[ figures  ] general (3,2) NURBS: max rel |partial - FD| = %.3g\n", worst);
}

TEST(Surface, InterpolatesCornersAndEndKnot) {
    const NurbsSurface s = make_sphere(1.0, {0, 0, 0});
    // Clamped: the corners are the corner control points, also exactly at u = v = 1.
    EXPECT_LT(dist(project(evaluate(s, 1, 1)), project(s.at(8, 4))), 1e-15);
    EXPECT_LT(dist(project(evaluate(s, 1, 0.5)), Vec3{1, 0, 0}), 1e-15);
    EXPECT_LT(dist(project(evaluate(s, 0.5, 0.5)), Vec3{-1, 0, 0}), 1e-15);
    // Clamping outside the range equals the boundary value.
    EXPECT_EQ(project(evaluate(s, 1.7, 0.5)).x, project(evaluate(s, 1.0, 0.5)).x);
    EXPECT_EQ(project(evaluate(s, -3, 0.25)).y, project(evaluate(s, 0.0, 0.25)).y);
}
