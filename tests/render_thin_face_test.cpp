// A face narrower than a pixel in front of another, against the analytic truth:
// the thin_ring fixture (a flat ring a third of a pixel wide, in front of a
// plate) seen from the front. Where the ring runs diagonally the preliminary map
// shows it only every second or third pixel, and the pixels between see the
// plate, level all around: the full-frame check (which re-casts only spikes,
// steps and enclosed background) does not look there, so this test checks every
// pixel: each whose ray crosses the ring, by more than kEdgeMargin inside its
// edges, must show the ring, and each whose ray passes outside it by that
// margin must not.
//
// History: of the 328 pixel rays that cross the ring, 176 showed the plate
// before the nearer-sheet pass tried thin faces around their map pixels
// (thin_tries), 112 after: where the ring runs along a row or a column the map
// mesh's chords sag inward by about the ring's width (deflection ~0.14 against
// 0.08), so the mesh's strip passes between two rows of pixel centres where the
// exact ring covers one row's, and no map pixel of the ring lies near; trying
// thin faces over their whole mesh on screen (thin_face_tries) took them to 0.
#include <gtest/gtest.h>

#include <cmath>

#include "importer/importer.h"
#include "renderer/camera.h"
#include "renderer/render.h"
#include "support/fixtures.h"

namespace T = nurbsrt::test;
using namespace nurbsrt;

namespace {

// Rays closer than this to the ring's edges are not judged: 1 % of its width,
// far above the trim loops' sampling tolerance (3e-6 of the face's (u, v) box,
// ~2e-4 here) and far below a pixel (0.2).
constexpr double kEdgeMargin = 0.01 * T::kThinRingWidth;
constexpr int kSize = 512;

}  // namespace

TEST(RenderThinFace, EveryPixelOfARingThinnerThanAPixel) {
    const Scene scene = import_file(T::thin_ring());
    // The ring: the face whose mesh lies in the plane y = -kThinRingGap.
    uint32_t ring = 0;
    for (const Face& f : scene.faces) {
        bool in_plane = !f.mesh.xyz.empty();
        for (const Vec3& p : f.mesh.xyz) in_plane &= std::fabs(p.y + T::kThinRingGap) < 1e-6;
        if (in_plane) ring = f.index;
    }
    ASSERT_NE(ring, 0u) << "no ring face in the fixture";

    CameraSpec base;
    base.width = base.height = kSize;
    base.projection = Projection::orthographic;
    const Camera camera(fit_view("front", scene, base));
    const RenderResult r = render(prepare(scene), camera, RenderOptions{});

    long inside = 0, missed = 0, extra = 0;
    for (int j = 0; j < kSize; ++j)
        for (int i = 0; i < kSize; ++i) {
            const Ray ray = camera.pixel_ray(i, j);
            ASSERT_GT(std::fabs(ray.dir.y), 0.5) << "the front view looks along y";
            const double t = (-T::kThinRingGap - ray.origin.y) / ray.dir.y;
            const double x = ray.origin.x + t * ray.dir.x - T::kThinRingCentre;
            const double z = ray.origin.z + t * ray.dir.z - T::kThinRingCentre;
            const double rho = std::hypot(x, z);
            const bool ours = r.image.face[static_cast<size_t>(j) * kSize + i] == ring;
            if (rho > T::kThinRingRadius + kEdgeMargin && rho < T::kThinRingRadius + T::kThinRingWidth - kEdgeMargin) {
                ++inside;
                missed += !ours;
            } else if ((rho < T::kThinRingRadius - kEdgeMargin ||
                        rho > T::kThinRingRadius + T::kThinRingWidth + kEdgeMargin) &&
                       ours) {
                ++extra;
            }
        }
    std::printf("[ thin ring ] %ld pixel rays cross the ring: %ld show another face, %ld outside it show the ring\n",
                inside, missed, extra);
    // A ring of radius 30 and width 0.08 at ~0.2 per pixel: ~250 pixel centres.
    EXPECT_GT(inside, 100);
    EXPECT_EQ(missed, 0);
    EXPECT_EQ(extra, 0);
}
