// Preliminary map (OSMesa): face ids where the pixel rays hit, and u, v equal to
// the exact parameters of the pixel-ray hit up to the mesh's interpolation error.
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <cstdio>
#include <thread>

#include "core/error.h"
#include "renderer/solve/newton.h"
#include "renderer/map/preliminary_map.h"
#include "renderer/prepared_scene.h"
#include "renderer/render.h"
#include "renderer_test_surfaces.h"

using namespace nurbsrt;
using namespace nurbsrt::testing;

namespace {

// Exact parameters (a, b) of the pixel ray's hit on the planar patch (the patch
// is affine in u, v, so its mesh interpolates u, v exactly).
bool plane_params(const NurbsSurface& s, const Ray& r, double& a, double& b) {
    const Vec3 o = project(s.at(0, 0)), e1 = project(s.at(1, 0)) - o, e2 = project(s.at(0, 1)) - o;
    const Vec3 n = cross(e1, e2);
    const double den = dot(n, r.dir);
    if (den == 0) return false;
    const double t = dot(n, o - r.origin) / den;
    if (t <= 0) return false;
    const Vec3 q = r.origin + t * r.dir - o;
    a = dot(cross(q, e2), n) / dot(n, n);
    b = dot(cross(e1, q), n) / dot(n, n);
    return true;
}

}  // namespace

TEST(RendererPreliminaryMap, PlaneIdsAndExactUv) {
    const AnalyticPatch p = plane_patch();
    Scene scene;
    scene.faces.push_back(make_face(p, 1, 5));
    for (Projection proj : {Projection::perspective, Projection::orthographic}) {
        CameraSpec spec = p.view;
        spec.projection = proj;
        spec.ortho_height = 3.0;
        spec.width = 160;
        spec.height = 120;
        const Camera cam(spec);
        const PreliminaryMap map = render_preliminary_map(scene, cam);
        ASSERT_EQ(map.width, 160);
        ASSERT_EQ(map.height, 120);
        int inside = 0, outside = 0;
        double max_err = 0;
        for (int j = 0; j < spec.height; ++j)
            for (int i = 0; i < spec.width; ++i) {
                double a = -1, b = -1;
                const bool hit = plane_params(p.surface, cam.pixel_ray(i, j), a, b);
                const size_t k = map.index(i, j);
                constexpr double m = 0.01;  // pixels this close to the patch edge are not checked
                if (hit && a > m && a < 1 - m && b > m && b < 1 - m) {
                    ++inside;
                    ASSERT_EQ(map.face[k], 1u) << i << "," << j;
                    max_err = std::max({max_err, std::abs(map.u[k] - a), std::abs(map.v[k] - b)});
                } else if (!hit || a < -m || a > 1 + m || b < -m || b > 1 + m) {
                    ++outside;
                    EXPECT_EQ(map.face[k], 0u) << i << "," << j;
                }
            }
        EXPECT_GT(inside, 3000);
        EXPECT_GT(outside, 1000);
        EXPECT_LT(max_err, 2e-6);
        std::printf("[ plane map %s ] %d inside, %d outside, max |uv - exact| %.2g\n",
                    cam.perspective() ? "persp" : "ortho", inside, outside, max_err);
    }
}

TEST(RendererPreliminaryMap, Rgb8QuantizesLikeEq4) {
    const AnalyticPatch p = plane_patch();
    Scene scene;
    scene.faces.push_back(make_face(p, 1, 5));
    const Camera cam(p.view);
    const PreliminaryMap f = render_preliminary_map(scene, cam, MapPrecision::float32);
    const PreliminaryMap q = render_preliminary_map(scene, cam, MapPrecision::rgb8);
    int n = 0;
    for (size_t k = 0; k < f.face.size(); ++k) {
        ASSERT_EQ(f.face[k], q.face[k]);
        if (!f.face[k]) continue;
        ++n;
        EXPECT_LE(std::abs(q.u[k] - f.u[k]), 0.5 / 255 + 1e-6);
        const double g = q.u[k] * 255.0;
        EXPECT_NEAR(g, std::round(g), 1e-4);  // on the 8-bit lattice of the [0,1] box
    }
    EXPECT_GT(n, 500);
    EXPECT_FLOAT_EQ(quantize_rgb8(0.5f, 0.0, 2.0), static_cast<float>(2.0 * 64 / 255));
}

TEST(RendererPreliminaryMap, NearestFaceWinsAndBackgroundIsZero) {
    const AnalyticPatch p = plane_patch();
    Scene scene;
    scene.faces.push_back(make_face(p, 1, 3));
    Face front = make_face(p, 2, 3);
    const Camera cam(p.view);
    for (Vec3& x : front.mesh.xyz) x = x - 0.5 * cam.forward();  // towards the eye
    scene.faces.push_back(front);
    const PreliminaryMap map = render_preliminary_map(scene, cam);
    const size_t c = map.index(cam.width() / 2, cam.height() / 2);
    EXPECT_EQ(map.face[c], 2u);
    EXPECT_EQ(map.face[map.index(0, 0)], 0u);
    // An empty scene is all background.
    const PreliminaryMap empty = render_preliminary_map(Scene{}, cam);
    for (uint32_t id : empty.face) ASSERT_EQ(id, 0u);
}

// On a curved patch the map's (u, v) is close to the exact hit's (u, v): Newton
// from it converges, and the start error is of the order of the mesh's chord error.
TEST(RendererPreliminaryMap, CurvedPatchStartsNearExactHit) {
    const AnalyticPatch p = sphere_patch(1.5);
    Scene scene;
    scene.faces.push_back(make_face(p, 1, 16));
    const Camera cam(p.view);
    const PreliminaryMap map = render_preliminary_map(scene, cam);
    const NurbsSurface proj = project_surface(cam, p.surface);
    NewtonParams params;
    params.eps = default_newton_eps(p.box, 1e-9);
    int n = 0, conv = 0;
    long its = 0;
    double max_d = 0;
    for (int j = 0; j < cam.height(); ++j)
        for (int i = 0; i < cam.width(); ++i) {
            const size_t k = map.index(i, j);
            if (!map.face[k]) continue;
            ++n;
            const NewtonResult r =
                newton_proposed(proj, cam, cam.pixel_screen(i, j), map.u[k], map.v[k], {0, 1, 0, 1}, params);
            if (r.status != NewtonStatus::converged) continue;
            ++conv;
            its += r.iterations;
            max_d = std::max({max_d, std::abs(r.u - map.u[k]), std::abs(r.v - map.v[k])});
        }
    EXPECT_GT(n, 400);
    EXPECT_GE(conv, n * 0.97);
    EXPECT_LT(max_d, 0.05);
    std::printf("[ sphere map start ] %d pixels, %d converged, mean iterations %.2f, max |uv0 - uv| %.3g\n", n, conv,
                double(its) / conv, max_d);
}

TEST(RendererPreliminaryMap, ConcurrentThreadsGiveTheSameMap) {
    const AnalyticPatch p = sphere_patch(1.5);
    Scene scene;
    scene.faces.push_back(make_face(p, 1, 12));
    const Camera cam(p.view);
    PreliminaryMap a, b;
    std::thread t1([&] { a = render_preliminary_map(scene, cam); });
    std::thread t2([&] { b = render_preliminary_map(scene, cam); });
    t1.join();
    t2.join();
    EXPECT_EQ(a.face, b.face);
    EXPECT_EQ(a.u, b.u);
    EXPECT_EQ(a.v, b.v);
}

// Large frames are drawn in bands of rows (MapBands): every band size gives the
// face ids of one frame-sized draw, pixel for pixel (the viewport only shifts by
// whole rows, and coverage is decided in llvmpipe's fixed point), including
// bands that do not divide the height and one-row bands. The interpolated
// (u, v) may differ by a few float ulps (llvmpipe evaluates its attribute planes
// from the tile's corner, which moves with the band): measured 1.8e-6 of these
// unit parameter ranges at most, far inside the map's own interpolation error
// (a start for Newton, CurvedPatchStartsNearExactHit).
TEST(RendererPreliminaryMap, BandsGiveTheMapOfOneDraw) {
    AnalyticPatch sphere, plane;
    const Scene scene = sphere_and_holed_plane(sphere, plane);
    const Camera cam(iso_view(scene, 203, 151));
    const PreparedScene prepared = prepare(scene);
    const PreliminaryMap whole = render_preliminary_map(prepared, cam, MapPrecision::float32, {151, nullptr});
    size_t hits = 0;
    for (uint32_t id : whole.face) hits += id != 0;
    ASSERT_GT(hits, whole.face.size() / 10);
    for (int rows : {1, 7, 50, 150}) {
        const PreliminaryMap banded = render_preliminary_map(prepared, cam, MapPrecision::float32, {rows, nullptr});
        EXPECT_EQ(banded.face, whole.face) << rows << " rows per band";
        double du = 0;
        size_t differ = 0;
        for (size_t k = 0; k < whole.u.size(); ++k) {
            const double d = std::max(std::abs(banded.u[k] - whole.u[k]), std::abs(banded.v[k] - whole.v[k]));
            du = std::max(du, d);
            differ += d > 0;
        }
        std::printf("[ bands ] %d rows: %zu of %zu pixels differ, max %.3g\n", rows, differ, whole.u.size(), du);
        EXPECT_LT(du, 1e-5) << rows << " rows per band";
    }
}

// A cancel is seen between bands: a set flag ends the map with Error(canceled).
TEST(RendererPreliminaryMap, CancelStopsBetweenBands) {
    AnalyticPatch sphere, plane;
    const Scene scene = sphere_and_holed_plane(sphere, plane);
    const Camera cam(iso_view(scene, 160, 120));
    const std::atomic<bool> flag{true};
    try {
        render_preliminary_map(prepare(scene), cam, MapPrecision::float32, {10, &flag});
        ADD_FAILURE() << "a canceled map was returned";
    } catch (const Error& e) {
        EXPECT_EQ(e.code(), ErrorCode::canceled);
    }
}

// Warm-up readies pooled renderers: after warming two, at least two wait in the
// pool, and frames drawn one at a time take them from there (the pool does not
// grow, so no context is created in a frame).
TEST(RendererPreliminaryMap, WarmUpReadiesPooledRenderers) {
    warm_up_preliminary_maps(2, 64, 48);
    const size_t idle = idle_map_renderers();
    EXPECT_GE(idle, 2u);
    const AnalyticPatch p = plane_patch();
    Scene scene;
    scene.faces.push_back(make_face(p, 1, 5));
    CameraSpec spec = p.view;
    spec.width = 64;
    spec.height = 48;
    const PreliminaryMap map = render_preliminary_map(scene, Camera(spec));
    EXPECT_GT(std::count(map.face.begin(), map.face.end(), 1u), 100);
    EXPECT_EQ(idle_map_renderers(), idle);
}
