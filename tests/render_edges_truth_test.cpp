// Feature lines against the true projected edges: on a box with filleted edges
// and a through-hole, the edges of the image are where OCCT's exact intersector
// (IntCurvesFace_ShapeIntersector, importer/reference/reference_intersector.h) shows
// another face, or none, in the next pixel: the true edge passes between those
// two pixel centres, within a pixel of each. A line one pixel wide is centred on
// the midpoint between two such centres and falls off over half a pixel more
// (pass_edges.cpp), so every pixel it touches must lie in the 3 x 3 around a
// pixel of such a pair (within a pixel of a pixel the true edge passes), and
// every such pair must have a pixel the lines change (every true edge drawn).
// Two views: iso, and top, where the hole's wall is seen 17 degrees from
// edge-on (a sheet's own depth slope must not count as an edge).
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <vector>

#include "importer/importer.h"
#include "importer/reference/reference_intersector.h"
#include "renderer/camera.h"
#include "renderer/prepared_scene.h"
#include "renderer/render.h"
#include "tests/support/fixtures.h"

namespace T = nurbsrt::test;
using namespace nurbsrt;

TEST(EdgesTruth, EveryLinePixelWithinAPixelOfATrueEdgeAndEveryEdgeDrawn) {
    const std::string path = T::holed_filleted_box();
    const Scene scene = import_file(path);
    const PreparedScene prepared = prepare(scene);
    ReferenceIntersector ref(path);
    for (const char* view : {"iso", "top"}) {
        SCOPED_TRACE(view);
        CameraSpec base;
        base.width = 240;
        base.height = 180;
        const Camera cam(fit_view(view, scene, base));
        const int W = cam.width(), H = cam.height();
        RenderOptions plain;
        plain.background = {1, 1, 1};
        plain.background_alpha = 1;
        RenderOptions lined = plain;
        lined.edges = true;
        lined.edge_color = {1, 0, 0};
        lined.edge_width = 1;
        const RenderResult a = render(prepared, cam, plain), b = render(prepared, cam, lined);
        // The reference's face at every pixel centre (0: background).
        std::vector<int> face(static_cast<size_t>(W) * H, 0);
        int errors = 0;
        for (int j = 0; j < H; ++j)
            for (int i = 0; i < W; ++i) {
                const ReferenceHit h = ref.cast(cam.pixel_ray(i, j), HUGE_VAL);
                errors += h.error;
                face[static_cast<size_t>(j) * W + i] = h.hit ? h.face : 0;
            }
        ASSERT_EQ(errors, 0);
        // The line's coverage of pixel k, from the green channel (the line is
        // red, the part grey on white: green only falls where the line covers).
        auto coverage = [&](size_t k) { return 1.0 - b.image.rgba[4 * k + 1] / a.image.rgba[4 * k + 1]; };
        auto drawn = [&](size_t k) { return coverage(k) > 1e-6; };
        std::vector<uint8_t> on_edge(face.size(), 0);  // one of a pair the reference tells apart
        int edges = 0, undrawn = 0;
        for (int j = 0; j < H; ++j)
            for (int i = 0; i < W; ++i) {
                const size_t k = static_cast<size_t>(j) * W + i;
                for (const size_t n : {i + 1 < W ? k + 1 : k, j + 1 < H ? k + W : k}) {
                    if (n == k || face[n] == face[k]) continue;
                    ++edges;
                    on_edge[k] = on_edge[n] = 1;
                    if (!drawn(k) && !drawn(n)) {
                        ++undrawn;
                        std::printf("   undrawn edge px(%d,%d) faces %d | %d\n", i, j, face[k], face[n]);
                    }
                }
            }
        auto next_to_edge = [&](int i, int j) {
            for (int nj = std::max(j - 1, 0); nj <= std::min(j + 1, H - 1); ++nj)
                for (int ni = std::max(i - 1, 0); ni <= std::min(i + 1, W - 1); ++ni)
                    if (on_edge[static_cast<size_t>(nj) * W + ni]) return true;
            return false;
        };
        int lines = 0, stray = 0;
        for (size_t k = 0; k < face.size(); ++k) {
            if (!drawn(k)) continue;
            ++lines;
            const int i = static_cast<int>(k % W), j = static_cast<int>(k / W);
            if (next_to_edge(i, j)) continue;
            ++stray;
            std::printf("   stray line px(%d,%d) coverage %.2f, face %d (ours %u)\n", i, j, coverage(k), face[k],
                        a.image.face[k]);
        }
        std::printf("[ edges ] %s %dx%d: %d true edge pairs, %d undrawn; %d line pixels, %d not next to a true edge\n",
                    view, W, H, edges, undrawn, lines, stray);
        EXPECT_GT(edges, 400);
        EXPECT_EQ(undrawn, 0);
        EXPECT_EQ(stray, 0);
    }
}
