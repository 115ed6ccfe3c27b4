// MeshScreenPoints (renderer/mesh_screen_points.h): the mesh starts of faces no
// nearby pixel shows. A search bounded to a screen distance gives the unbounded
// search's answer wherever the mesh comes within the bound, and nothing where it
// does not; through the first queries' scans and the grid alike.
#include <gtest/gtest.h>

#include <tbb/task_arena.h>

#include <cmath>
#include <random>

#include "renderer/frame.h"
#include "renderer/mesh_screen_points.h"
#include "renderer_test_surfaces.h"

using namespace nurbsrt;
using namespace nurbsrt::testing;

TEST(MeshScreenPoints, BoundedSearchGivesTheUnboundedAnswerWithinTheBound) {
    AnalyticPatch sphere, plane;
    const Scene scene = sphere_and_holed_plane(sphere, plane);
    const Camera cam(iso_view(scene, 96, 64));
    const PreparedScene prepared = prepare(scene, 1);
    const PreliminaryMap map;  // MeshScreenPoints reads the mesh and camera only
    const RenderOptions options;
    tbb::task_arena arena(1);
    Progress progress(options.progress, 1);
    const FrameContext c{prepared, scene, cam, map, options, arena, progress, cam.width(), cam.height(),
                         static_cast<uint32_t>(scene.faces.size())};
    const MeshScreenPoints unbounded(c), bounded(c);
    // Screen units span 2 over the height: bounds of 1, 4 and 16 pixels.
    const double pixel = 2.0 / cam.height();
    std::mt19937 rng(5);
    std::uniform_real_distribution<double> x(-1.8, 1.8), y(-1.2, 1.2);
    int within = 0, beyond = 0;
    for (int k = 0; k < 400; ++k) {
        const ScreenPoint sp{x(rng), y(rng)};
        for (uint32_t id = 1; id <= c.nfaces; ++id) {
            Vec2 all[2];
            double d2 = 0;
            const int n = unbounded.nearest_starts(id, sp, all, &d2);
            ASSERT_GT(n, 0);
            for (const double reach : {1.0, 4.0, 16.0}) {
                const double max_d2 = (reach * pixel) * (reach * pixel);
                Vec2 got[2];
                double got_d2 = -1;
                const int m = bounded.nearest_starts(id, sp, got, &got_d2, max_d2);
                if (d2 <= max_d2) {
                    ++within;
                    ASSERT_EQ(m, n);
                    EXPECT_EQ(got_d2, d2);
                    for (int q = 0; q < n; ++q) {
                        EXPECT_EQ(got[q].x, all[q].x);
                        EXPECT_EQ(got[q].y, all[q].y);
                    }
                } else {
                    ++beyond;
                    EXPECT_EQ(m, 0);
                    EXPECT_EQ(got_d2, HUGE_VAL);
                }
            }
        }
    }
    // Both cases occur often (the points cover the faces and the space around them).
    EXPECT_GT(within, 300);
    EXPECT_GT(beyond, 300);
}
