// One check that two renders are the same frame: every AOV buffer bit for bit
// and every statistic except times (used where a change of threads, of
// preparation or of call order must not change a single pixel).
#pragma once

#include <gtest/gtest.h>

#include "renderer/render.h"

namespace nurbsrt::test {

inline void expect_identical_renders(const RenderResult& a, const RenderResult& b) {
    EXPECT_TRUE(a.image.rgba == b.image.rgba);
    EXPECT_TRUE(a.image.z == b.image.z);
    EXPECT_TRUE(a.image.face == b.image.face);
    EXPECT_TRUE(a.image.normal == b.image.normal);
    EXPECT_TRUE(a.image.u == b.image.u);
    EXPECT_TRUE(a.image.v == b.image.v);
    EXPECT_TRUE(a.image.iterations == b.image.iterations);
    const RenderStats &s = a.stats, &t = b.stats;
    EXPECT_EQ(s.pixels_hit, t.pixels_hit);
    EXPECT_EQ(s.iteration_histogram, t.iteration_histogram);
    EXPECT_EQ(s.mean_iterations, t.mean_iterations);
    EXPECT_EQ(s.converged, t.converged);
    EXPECT_EQ(s.diverged, t.diverged);
    EXPECT_EQ(s.singular, t.singular);
    EXPECT_EQ(s.max_iterations, t.max_iterations);
    EXPECT_EQ(s.left_domain, t.left_domain);
    EXPECT_EQ(s.behind_eye, t.behind_eye);
    EXPECT_EQ(s.trimmed, t.trimmed);
    EXPECT_EQ(s.fallback, t.fallback);
    EXPECT_EQ(s.rescue_neighbour, t.rescue_neighbour);
    EXPECT_EQ(s.rescue_silhouette, t.rescue_silhouette);
    EXPECT_EQ(s.rescue_general, t.rescue_general);
    EXPECT_EQ(s.rescue_trim_tolerance, t.rescue_trim_tolerance);
    EXPECT_EQ(s.rescue_nearer, t.rescue_nearer);
    EXPECT_EQ(s.holes, t.holes);
    EXPECT_EQ(s.map_triangles, t.map_triangles);
}

}  // namespace nurbsrt::test
