// The depth-only mesh rasterizer of the tessellating benchmark peer: its t must
// be the contract pixel ray's hit distance with the triangles (perspective and
// orthographic), +inf off the mesh, and the nearer of two overlapping planes.
#include <gtest/gtest.h>

#include <cmath>

#include "bench/mesh_raster.h"
#include "renderer/camera.h"

namespace nurbsrt {
namespace {

// A square [-s, s]^2 in the plane z = h, two triangles.
void add_square(TriangleMesh& m, double s, double h) {
    const uint32_t b = static_cast<uint32_t>(m.xyz.size());
    m.xyz.insert(m.xyz.end(), {{-s, -s, h}, {s, -s, h}, {s, s, h}, {-s, s, h}});
    m.triangles.insert(m.triangles.end(), {b, b + 1, b + 2, b, b + 2, b + 3});
}

// Exact t of the pixel ray with the plane z = h (the ray looks down -z).
double plane_t(const Ray& r, double h) { return (h - r.origin.z) / r.dir.z; }

void check_camera(const CameraSpec& spec) {
    TriangleMesh mesh;
    add_square(mesh, 1.0, 0.0);  // far plane, large
    add_square(mesh, 0.3, 0.5);  // nearer, small: occludes the middle
    const Camera cam(spec);
    MeshRasterizer raster;
    const DepthImage img = raster.render(mesh, cam);
    ASSERT_EQ(img.width, spec.width);
    ASSERT_EQ(img.height, spec.height);
    int inside = 0, outside = 0, near_hits = 0;
    for (int j = 0; j < spec.height; ++j)
        for (int i = 0; i < spec.width; ++i) {
            const Ray r = cam.pixel_ray(i, j);
            const float t = img.t[static_cast<size_t>(j) * spec.width + i];
            auto on = [&](double s, double h) {
                const double tt = plane_t(r, h);
                const Vec3 p = r.origin + tt * r.dir;
                return std::fabs(p.x) < s && std::fabs(p.y) < s ? tt : HUGE_VAL;
            };
            // Pixel centres within 1e-3 of a square's border may fall either way.
            const double a = on(0.3 - 1e-3, 0.5), b = on(1.0 - 1e-3, 0.0);
            const double amb_a = on(0.3 + 1e-3, 0.5), amb_b = on(1.0 + 1e-3, 0.0);
            if (std::isfinite(a)) {
                EXPECT_NEAR(t, a, 1e-5 * a) << i << "," << j;
                ++near_hits;
            } else if (!std::isfinite(amb_a) && std::isfinite(b)) {
                EXPECT_NEAR(t, b, 1e-5 * b) << i << "," << j;
                ++inside;
            } else if (!std::isfinite(amb_a) && !std::isfinite(amb_b)) {
                EXPECT_TRUE(std::isinf(t)) << i << "," << j << " t=" << t;
                ++outside;
            }
        }
    EXPECT_GT(near_hits, 100);
    EXPECT_GT(inside, 100);
    EXPECT_GT(outside, 100);
}

TEST(MeshRaster, PerspectiveDepthIsThePixelRaysHitDistance) {
    CameraSpec spec;
    spec.eye = {0.1, -0.2, 3};
    spec.target = {0, 0, 0};
    spec.up = {0, 1, 0};
    spec.fov_deg = 50;
    spec.width = 96;
    spec.height = 64;
    check_camera(spec);
}

TEST(MeshRaster, OrthographicDepthIsThePixelRaysHitDistance) {
    CameraSpec spec;
    spec.eye = {0, 0, 2};
    spec.target = {0, 0, 0};
    spec.up = {0, 1, 0};
    spec.projection = Projection::orthographic;
    spec.ortho_height = 3;
    spec.width = 64;
    spec.height = 80;
    check_camera(spec);
}

}  // namespace
}  // namespace nurbsrt
