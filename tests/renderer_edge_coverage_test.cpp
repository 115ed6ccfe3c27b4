// The coverage of a pixel by one side of a straight edge, estimated from the
// sides its samples fell on, against the exact area (a half-plane clipped to the
// unit square, by the shoelace formula here, not the estimator's box spline).
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <random>
#include <vector>

#include "renderer/passes/edge_coverage.h"

using namespace nurbsrt;

namespace {

// The area of the unit square where (x, y) . (cx, cy) < t: the square clipped
// by the half-plane (Sutherland & Hodgman 1974), then the shoelace formula.
double clipped_area(double cx, double cy, double t) {
    const double sq[4][2] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
    std::vector<std::array<double, 2>> poly;
    for (int k = 0; k < 4; ++k) {
        const double* p = sq[k];
        const double* q = sq[(k + 1) % 4];
        const double fp = cx * p[0] + cy * p[1] - t, fq = cx * q[0] + cy * q[1] - t;
        if (fp < 0) poly.push_back({p[0], p[1]});
        if ((fp < 0) != (fq < 0)) {
            const double s = fp / (fp - fq);
            poly.push_back({p[0] + s * (q[0] - p[0]), p[1] + s * (q[1] - p[1])});
        }
    }
    double a = 0;
    for (size_t k = 0; k < poly.size(); ++k) {
        const auto& p = poly[k];
        const auto& q = poly[(k + 1) % poly.size()];
        a += p[0] * q[1] - q[0] * p[1];
    }
    return std::abs(a) / 2;
}

}  // namespace

// Random straight edges through a pixel sampled by a jittered 4 x 4 grid and the
// centre: the estimate beats the box average of the same 17 samples on average
// and is never far off.
TEST(EdgeCoverage, StraightEdgesBetterThanTheBoxAverage) {
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> u(0, 1);
    double box_error = 0, fit_error = 0, worst = 0, worst_box = 0;
    int pixels = 0, fitted = 0;
    for (int trial = 0; trial < 4000; ++trial) {
        const double angle = 2 * M_PI * u(rng), cx = std::cos(angle), cy = std::sin(angle);
        const double t = cx * 0.5 + cy * 0.5 + 1.2 * (u(rng) - 0.5);  // through or near the pixel
        const double exact = clipped_area(cx, cy, t);
        if (exact < 1e-3 || exact > 1 - 1e-3) continue;
        SidePoints in, out;
        auto add = [&](double x, double y) { (cx * x + cy * y < t ? in : out).add(x, y); };
        add(0.5, 0.5);
        for (int a = 0; a < 4; ++a)
            for (int b = 0; b < 4; ++b) add((a + u(rng)) / 4, (b + u(rng)) / 4);
        const double box = double(in.size()) / (in.size() + out.size());
        const double fit = straight_edge_coverage(in, out);
        ++pixels;
        box_error += std::abs(box - exact);
        worst_box = std::max(worst_box, std::abs(box - exact));
        if (std::isnan(fit)) {  // all samples on one side: the box average stays
            EXPECT_TRUE(in.size() == 0 || out.size() == 0);
            fit_error += std::abs(box - exact);
            continue;
        }
        ++fitted;
        fit_error += std::abs(fit - exact);
        worst = std::max(worst, std::abs(fit - exact));
    }
    box_error /= pixels;
    fit_error /= pixels;
    std::printf("[ edge coverage ] %d pixels (%d fitted): mean error %.4f, box average %.4f; worst %.3f, box %.3f\n",
                pixels, fitted, fit_error, box_error, worst, worst_box);
    ASSERT_GT(pixels, 2000);
    EXPECT_GT(fitted, pixels * 8 / 10);
    EXPECT_LT(fit_error, 0.8 * box_error);
    EXPECT_LT(worst, worst_box);
}

// An edge at a known place: samples on both sides of x = 0.3 give about 0.3.
TEST(EdgeCoverage, VerticalEdge) {
    SidePoints left, right;
    for (int a = 0; a < 8; ++a)
        for (int b = 0; b < 8; ++b) {
            const double x = (a + 0.5) / 8, y = (b + 0.5) / 8;
            (x < 0.3 ? left : right).add(x, y);
        }
    // The columns at x = 0.1875 and 0.3125 bound the edge: lines between them
    // (and tilted ones through the gap) cover 0.25 on average, within half a
    // column of the true 0.3.
    EXPECT_NEAR(straight_edge_coverage(left, right), 0.3, 0.0625);
    EXPECT_NEAR(straight_edge_coverage(right, left), 0.7, 0.0625);
}

// No straight line separates a checkerboard's colours; all samples on one side
// leave nothing to estimate.
TEST(EdgeCoverage, NotSeparableOrOneSidedIsNaN) {
    SidePoints black, white, all, none;
    for (int a = 0; a < 4; ++a)
        for (int b = 0; b < 4; ++b) {
            ((a + b) % 2 == 0 ? black : white).add((a + 0.5) / 4, (b + 0.5) / 4);
            all.add((a + 0.5) / 4, (b + 0.5) / 4);
        }
    EXPECT_TRUE(std::isnan(straight_edge_coverage(black, white)));
    EXPECT_TRUE(std::isnan(straight_edge_coverage(all, none)));
}
