// Feature lines: drawn wherever adjacent pixels show background and a face or
// two faces, nowhere else, with a width in pixels; the AOVs untouched.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>

#include "renderer/render.h"
#include "renderer_test_surfaces.h"

using namespace nurbsrt;
using namespace nurbsrt::testing;

namespace {

RenderOptions with_edges(float width) {
    RenderOptions o;
    o.background = {1, 1, 1};
    o.background_alpha = 1;
    o.edges = true;
    o.edge_color = {1, 0, 0};
    o.edge_width = width;
    return o;
}

bool same_pixel(const RenderImage& a, const RenderImage& b, size_t k) {
    return std::equal(&a.rgba[4 * k], &a.rgba[4 * k + 4], &b.rgba[4 * k]);
}

}  // namespace

TEST(RendererEdges, LinesAlongEveryBoundaryAndNowhereElse) {
    AnalyticPatch sphere, plane;
    const Scene scene = sphere_and_holed_plane(sphere, plane);
    const Camera cam(iso_view(scene, 160, 120));
    RenderOptions plain = with_edges(1);
    plain.edges = false;
    // Two pixels wide: the line on a pixel boundary covers the pixel on each side fully.
    const RenderResult a = render(scene, cam, plain), b = render(scene, cam, with_edges(2));
    EXPECT_EQ(a.image.face, b.image.face);
    EXPECT_EQ(a.image.z, b.image.z);
    const int W = cam.width(), H = cam.height();
    auto boundary = [&](int i, int j, int ni, int nj) {
        return ni >= 0 && nj >= 0 && ni < W && nj < H &&
               a.image.face[static_cast<size_t>(j) * W + i] != a.image.face[static_cast<size_t>(nj) * W + ni];
    };
    int boundaries = 0, unmarked = 0, changed = 0, stray = 0, saturated = 0;
    for (int j = 0; j < H; ++j)
        for (int i = 0; i < W; ++i) {
            const size_t k = static_cast<size_t>(j) * W + i;
            for (const auto& [di, dj] : {std::pair{1, 0}, std::pair{0, 1}})
                if (boundary(i, j, i + di, j + dj)) {
                    ++boundaries;
                    const size_t n = static_cast<size_t>(j + dj) * W + i + di;
                    unmarked += same_pixel(a.image, b.image, k) && same_pixel(a.image, b.image, n);
                }
            if (same_pixel(a.image, b.image, k)) continue;
            ++changed;
            // A changed pixel lies within the line's reach (half width + 1/2) of a boundary.
            bool near = false;
            for (int nj = j - 2; nj <= j + 2 && !near; ++nj)
                for (int ni = i - 2; ni <= i + 2 && !near; ++ni)
                    near = boundary(ni, nj, ni + 1, nj) || boundary(ni, nj, ni, nj + 1);
            stray += !near;
            saturated += b.image.rgba[4 * k] > 0.95f && b.image.rgba[4 * k + 1] < 0.05f;
        }
    std::printf("[ edges ] %d face/background boundaries, %d pixels drawn (%d pure line colour), %.1f ms\n", boundaries,
                changed, saturated, b.stats.edges_ms);
    ASSERT_GT(boundaries, 300);
    EXPECT_EQ(unmarked, 0);
    EXPECT_EQ(stray, 0);
    EXPECT_GT(saturated, boundaries / 4);  // the line's core has the line colour
}

TEST(RendererEdges, WidthIsInPixels) {
    AnalyticPatch sphere, plane;
    const Scene scene = sphere_and_holed_plane(sphere, plane);
    double ink_at[2] = {0, 0};
    for (const int size : {120, 240}) {
        const Camera cam(iso_view(scene, size, size * 3 / 4));
        RenderOptions plain = with_edges(1);
        plain.edges = false;
        const RenderResult a = render(scene, cam, plain), thin = render(scene, cam, with_edges(1)),
                           thick = render(scene, cam, with_edges(3));
        // Ink: the summed darkening of the green channel (the line is red on a
        // white or grey-shaded image), i.e. line length x width.
        double ink_thin = 0, ink_thick = 0;
        for (size_t k = 0; k < a.image.face.size(); ++k) {
            ink_thin += a.image.rgba[4 * k + 1] - thin.image.rgba[4 * k + 1];
            ink_thick += a.image.rgba[4 * k + 1] - thick.image.rgba[4 * k + 1];
        }
        std::printf("[ edges ] %dpx wide image: ink of width 1: %.1f, width 3: %.1f (ratio %.2f)\n", size, ink_thin,
                    ink_thick, ink_thick / ink_thin);
        EXPECT_GT(ink_thick / ink_thin, 2.2);
        EXPECT_LT(ink_thick / ink_thin, 3.8);
        ink_at[size == 240] = ink_thin;
    }
    // Twice the resolution: the lines are twice as long in pixels, as wide.
    EXPECT_GT(ink_at[1] / ink_at[0], 1.6);
    EXPECT_LT(ink_at[1] / ink_at[0], 2.4);
}
