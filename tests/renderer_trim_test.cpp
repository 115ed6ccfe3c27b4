// Grid-accelerated even-odd trim test against the brute-force crossing count.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <random>

#include "core/scene/trim.h"

using namespace nurbsrt;

namespace {

// A star-shaped, strongly concave loop around c with n vertices.
TrimLoop star(Vec2 c, double r0, double r1, int n, std::mt19937_64& rng, bool outer) {
    std::uniform_real_distribution<double> R(r0, r1);
    TrimLoop l;
    l.outer = outer;
    for (int k = 0; k < n; ++k) {
        const double a = 2 * M_PI * k / n;
        const double r = (k % 2 ? 0.45 : 1.0) * R(rng);
        l.points.push_back({c.x + r * std::cos(a), c.y + r * std::sin(a)});
    }
    return l;
}

void compare(const std::vector<TrimLoop>& loops, Vec2 lo, Vec2 hi, int samples, std::mt19937_64& rng, int& inside) {
    const TrimTester t(loops);
    std::uniform_real_distribution<double> X(lo.x, hi.x), Y(lo.y, hi.y);
    for (int k = 0; k < samples; ++k) {
        const Vec2 p{X(rng), Y(rng)};
        const bool ref = inside_even_odd_bruteforce(loops, p);
        ASSERT_EQ(t.inside(p), ref) << p.x << "," << p.y;
        inside += ref;
    }
}

}  // namespace

TEST(RendererTrim, UntrimmedIsInside) {
    const TrimTester t;
    EXPECT_FALSE(t.trimmed());
    EXPECT_TRUE(t.inside({0.3, 100}));
}

TEST(RendererTrim, ConcaveLoopsWithHolesMatchBruteForce) {
    std::mt19937_64 rng(3);
    for (int trial = 0; trial < 20; ++trial) {
        std::vector<TrimLoop> loops;
        loops.push_back(star({0.5, 0.5}, 0.35, 0.5, 60 + 40 * trial, rng, true));
        // Holes, one overlapping another (even-odd makes the overlap inside again).
        loops.push_back(star({0.45, 0.5}, 0.05, 0.12, 30, rng, false));
        loops.push_back(star({0.52, 0.55}, 0.04, 0.1, 17, rng, false));
        loops.push_back(star({0.7, 0.35}, 0.03, 0.07, 250, rng, false));
        int inside = 0;
        compare(loops, {-0.1, -0.1}, {1.1, 1.1}, 20000, rng, inside);
        EXPECT_GT(inside, 2000);
    }
}

// Axis-aligned loops on exact coordinates queried on a lattice that includes the
// grid's lines and the loops' own coordinates (points exactly on edges excluded).
TEST(RendererTrim, AxisAlignedLoopsOnALattice) {
    std::vector<TrimLoop> loops(3);
    loops[0].points = {{0, 0}, {4, 0}, {4, 3}, {2, 3}, {2, 2}, {1, 2}, {1, 3}, {0, 3}};  // concave outer
    loops[1].points = {{0.5, 0.5}, {1.5, 0.5}, {1.5, 1.5}, {0.5, 1.5}};                  // hole
    loops[2].points = {{2.5, 0.5}, {3.5, 0.5}, {3.5, 2.5}, {2.5, 2.5}};                  // hole
    const TrimTester t(loops);
    int checked = 0;
    for (int i = -8; i <= 40; ++i)
        for (int j = -8; j <= 32; ++j) {
            const Vec2 p{i * 0.125 + 0.0625 * (j % 2), j * 0.125};
            bool on_edge = false;
            for (const TrimLoop& l : loops)
                for (size_t k = 0, m = l.points.size() - 1; k < l.points.size(); m = k++) {
                    const Vec2 a = l.points[m], b = l.points[k];
                    const double cr = (b.x - a.x) * (p.y - a.y) - (b.y - a.y) * (p.x - a.x);
                    if (cr == 0 && p.x >= std::min(a.x, b.x) && p.x <= std::max(a.x, b.x) &&
                        p.y >= std::min(a.y, b.y) && p.y <= std::max(a.y, b.y))
                        on_edge = true;
                }
            if (on_edge) continue;
            ++checked;
            EXPECT_EQ(t.inside(p), inside_even_odd_bruteforce(loops, p)) << p.x << "," << p.y;
        }
    EXPECT_GT(checked, 1000);
    EXPECT_TRUE(t.inside({0.25, 0.25}));
    EXPECT_FALSE(t.inside({1, 1}));      // in the first hole
    EXPECT_FALSE(t.inside({1.5, 2.5}));  // in the notch
    EXPECT_FALSE(t.inside({5, 1}));      // outside the grid
}

TEST(RendererTrim, GridIsFasterThanBruteForce) {
    std::mt19937_64 rng(5);
    std::vector<TrimLoop> loops{star({0.5, 0.5}, 0.3, 0.5, 4000, rng, true),
                                star({0.5, 0.5}, 0.05, 0.1, 1000, rng, false)};
    const TrimTester t(loops);
    std::uniform_real_distribution<double> U(0, 1);
    std::vector<Vec2> pts(20000);
    for (Vec2& p : pts) p = {U(rng), U(rng)};
    auto t0 = std::chrono::steady_clock::now();
    int a = 0;
    for (const Vec2& p : pts) a += t.inside(p);
    auto t1 = std::chrono::steady_clock::now();
    int b = 0;
    for (const Vec2& p : pts) b += inside_even_odd_bruteforce(loops, p);
    auto t2 = std::chrono::steady_clock::now();
    EXPECT_EQ(a, b);
    const double grid_ns = std::chrono::duration<double, std::nano>(t1 - t0).count() / pts.size();
    const double brute_ns = std::chrono::duration<double, std::nano>(t2 - t1).count() / pts.size();
    std::printf("[ trim 5000 edges ] grid %dx%d: %.0f ns/query, brute force %.0f ns/query\n", t.cells_u(), t.cells_v(),
                grid_ns, brute_ns);
    EXPECT_LT(grid_ns * 10, brute_ns);
}
