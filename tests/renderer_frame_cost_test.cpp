// The frame cost estimate (renderer/frame_cost.h) counts the passes that change
// a frame's work and memory: anti-aliasing in proportion to its rays, shadows
// with their light map, both together multiplied (anti-aliasing samples are
// shaded with shadows too). The factors themselves are calibrated by `nurbsrt
// bench --only look`; here: that they are applied, and only when asked.
#include <gtest/gtest.h>

#include "renderer/frame_cost.h"
#include "renderer/prepared_scene.h"
#include "renderer/passes/shadow_rays.h"
#include "renderer_test_surfaces.h"

using namespace nurbsrt;
using namespace nurbsrt::testing;

TEST(FrameCost, AntialiasingAndShadowsAddWorkAndMemory) {
    const AnalyticPatch sphere = sphere_patch(1.0);
    Scene s;
    s.faces.push_back(make_face(sphere, 1, 8));
    s.bbox.extend(sphere.box);
    const PreparedScene prepared = prepare(s, 1);
    const int w = 640, h = 480;
    const FrameCost plain = estimate_frame_cost(prepared, w, h);
    const FrameCost aa4 = estimate_frame_cost(prepared, w, h, {4, false});
    const FrameCost aa8 = estimate_frame_cost(prepared, w, h, {8, false});
    const FrameCost shadows = estimate_frame_cost(prepared, w, h, {0, true});
    const FrameCost both = estimate_frame_cost(prepared, w, h, {4, true});
    ASSERT_GT(plain.core_seconds, 0);
    EXPECT_DOUBLE_EQ(estimate_frame_cost(prepared, w, h, {0, false}).core_seconds, plain.core_seconds);
    EXPECT_NEAR(aa4.core_seconds / plain.core_seconds, 2.0, 1e-9);
    EXPECT_NEAR(aa8.core_seconds / plain.core_seconds, 3.0, 1e-9);
    EXPECT_NEAR(shadows.core_seconds / plain.core_seconds, 1.6, 1e-9);
    EXPECT_NEAR(both.core_seconds / plain.core_seconds, 3.2, 1e-9);
    EXPECT_EQ(aa4.memory_bytes - plain.memory_bytes, size_t(w) * h);  // one edge flag per pixel
    // The light map (640 across for this view) and its framebuffer: at least 24 bytes a pixel.
    EXPECT_EQ(light_map_size(w, h), 640);
    EXPECT_GE(shadows.memory_bytes - plain.memory_bytes, size_t(640) * 640 * 24);
    EXPECT_EQ(light_map_size(100, 50), 256);
    EXPECT_EQ(light_map_size(4000, 3000), 2048);
}
