// Whole frames: hits and Z against exact intersections, trimming, thread-count
// independence, method agreement, statistics and image files.
#include <gtest/gtest.h>

#include <OpenImageIO/imageio.h>

#include <cstdio>
#include <filesystem>

#include "core/error.h"
#include "renderer/render.h"
#include "renderer_test_surfaces.h"

using namespace nurbsrt;
using namespace nurbsrt::testing;

TEST(RendererRender, HitsMatchExactIntersectionsAndTrim) {
    AnalyticPatch sphere, plane;
    const Scene scene = sphere_and_holed_plane(sphere, plane);
    const Camera cam(iso_view(scene, 200, 150));
    for (NewtonMethod m : {NewtonMethod::proposed, NewtonMethod::martin}) {
        RenderOptions opt;
        opt.method = m;
        const RenderResult r = render(scene, cam, opt);
        int agree = 0, disagree = 0;
        double max_z = 0;
        for (int j = 0; j < cam.height(); ++j)
            for (int i = 0; i < cam.width(); ++i) {
                const Ray ray = cam.pixel_ray(i, j);
                const std::optional<double> ts = sphere.hit(ray);
                std::optional<double> tp = plane.hit(ray);
                // Expected: nearest of sphere / plane-outside-hole.
                uint32_t want = 0;
                double tw = HUGE_VAL;
                if (ts) {
                    want = 1;
                    tw = *ts;
                }
                if (tp && *tp < tw) {
                    // plane params: via Newton-free affine inverse
                    const Vec3 o = project(plane.surface.at(0, 0)), e1 = project(plane.surface.at(1, 0)) - o,
                               e2 = project(plane.surface.at(0, 1)) - o, n = cross(e1, e2);
                    const Vec3 q = ray.origin + *tp * ray.dir - o;
                    const double a = dot(cross(q, e2), n) / dot(n, n), b = dot(cross(e1, q), n) / dot(n, n);
                    const double rr = std::hypot(a - 0.5, b - 0.5);
                    if (std::abs(rr - 0.2) < 0.01) continue;  // near the hole's polygon: ambiguous
                    if (rr > 0.2) {
                        want = 2;
                        tw = *tp;
                    }
                }
                const size_t k = static_cast<size_t>(j) * cam.width() + i;
                if (r.image.face[k] == want) {
                    ++agree;
                    if (want) max_z = std::max(max_z, std::abs(r.image.z[k] - tw) / tw);
                } else {
                    ++disagree;
                }
            }
        std::printf(
            "[ frame %s ] agree %d disagree %d (silhouette pixels), max rel Z err %.2g; hit %zu, "
            "mean it %.2f, conv %llu trimmed %llu div %llu sing %llu maxit %llu left %llu fallback %llu\n",
            newton_method_name(m), agree, disagree, max_z, r.stats.pixels_hit, r.stats.mean_iterations,
            (unsigned long long)r.stats.converged, (unsigned long long)r.stats.trimmed,
            (unsigned long long)r.stats.diverged, (unsigned long long)r.stats.singular,
            (unsigned long long)r.stats.max_iterations, (unsigned long long)r.stats.left_domain,
            (unsigned long long)r.stats.fallback);
        EXPECT_LT(disagree, agree / 200);
        EXPECT_LT(max_z, 1e-6);            // Z is float
        EXPECT_GT(r.stats.trimmed, 100u);  // the hole's pixels converge on the plane, then trim away
    }
}

TEST(RendererRender, SameOutputForOneAndTwoThreads) {
    AnalyticPatch sphere, plane;
    const Scene scene = sphere_and_holed_plane(sphere, plane);
    const Camera cam(iso_view(scene, 160, 120));
    RenderOptions o1, o2;
    o1.threads = 1;
    o2.threads = 2;
    const RenderResult a = render(scene, cam, o1), b = render(scene, cam, o2);
    EXPECT_EQ(a.image.rgba, b.image.rgba);
    EXPECT_EQ(a.image.z, b.image.z);
    EXPECT_EQ(a.image.face, b.image.face);
    EXPECT_EQ(a.stats.iteration_histogram, b.stats.iteration_histogram);
    EXPECT_EQ(a.stats.fallback, b.stats.fallback);
    EXPECT_EQ(a.image.normal, b.image.normal);
    EXPECT_EQ(a.stats.rescue_trim_tolerance, b.stats.rescue_trim_tolerance);
    EXPECT_EQ(a.stats.rescue_general, b.stats.rescue_general);
}

namespace {

// Pixels where the rendered face set disagrees with the exact sphere octant, and
// background pixels whose 4 neighbours are hit.
struct SphereCheck {
    int missed = 0, extra = 0, holes = 0, expected_hits = 0;
};
SphereCheck check_sphere(const RenderResult& r, const Camera& cam, const AnalyticPatch& sphere) {
    SphereCheck c;
    const int W = cam.width(), H = cam.height();
    auto hit = [&](int i, int j) { return i >= 0 && j >= 0 && i < W && j < H && r.image.face[size_t(j) * W + i] != 0; };
    for (int j = 0; j < H; ++j)
        for (int i = 0; i < W; ++i) {
            const bool want = sphere.hit(cam.pixel_ray(i, j)).has_value();
            c.expected_hits += want;
            c.missed += want && !hit(i, j);
            c.extra += !want && hit(i, j);
            c.holes += !hit(i, j) && hit(i - 1, j) && hit(i + 1, j) && hit(i, j - 1) && hit(i, j + 1);
        }
    return c;
}

// The scene rendered with method m, and its check against the exact sphere.
std::pair<RenderResult, SphereCheck> render_sphere(const Scene& scene, const Camera& cam, const AnalyticPatch& sphere,
                                                   NewtonMethod m) {
    RenderOptions opt;
    opt.method = m;
    RenderResult r = render(scene, cam, opt);
    const SphereCheck c = check_sphere(r, cam, sphere);
    return {std::move(r), c};
}

}  // namespace

// Two faces on one sphere octant, split at v = 0.5, each with a deliberately
// coarse mesh of its own resolution (a T-junction edge in the map, chords far
// inside the silhouette) and trim loops that stop short of the shared edge by
// their trim tolerance (as sampled loops may): the rescue must leave no crack
// along the shared edge and no gap at the silhouette.
TEST(RendererRender, RescueClosesCracksBetweenAdjacentFaces) {
    const AnalyticPatch sphere = sphere_patch(1.5);
    const double delta = 2e-3;
    Scene scene;
    for (int k = 0; k < 2; ++k) {
        const int n = k == 0 ? 2 : 3;
        Face f;
        f.index = k + 1;
        f.surface = sphere.surface;
        f.u_min = 0;
        f.u_max = 1;
        f.v_min = k == 0 ? 0.0 : 0.5;
        f.v_max = k == 0 ? 0.5 : 1.0;
        for (int i = 0; i <= n; ++i)
            for (int j = 0; j <= n; ++j) {
                const double u = double(i) / n, v = f.v_min + (f.v_max - f.v_min) * j / n;
                f.mesh.uv.push_back({u, v});
                f.mesh.xyz.push_back(project(evaluate(f.surface, u, v)));
            }
        for (int i = 0; i < n; ++i)
            for (int j = 0; j < n; ++j) {
                const uint32_t a = i * (n + 1) + j, b = a + (n + 1);
                f.mesh.triangles.insert(f.mesh.triangles.end(), {a, b, b + 1, a, b + 1, a + 1});
            }
        const double v0 = k == 0 ? 0.0 : 0.5 + delta, v1 = k == 0 ? 0.5 - delta : 1.0;
        TrimLoop loop;
        loop.outer = true;
        loop.points = {{0, v0}, {1, v0}, {1, v1}, {0, v1}};
        f.loops = {loop};
        f.trim_tolerance_uv = delta;
        scene.faces.push_back(f);
    }
    scene.bbox = sphere.box;
    CameraSpec spec = sphere.view;
    spec.width = 320;
    spec.height = 240;
    const Camera cam(spec);
    for (NewtonMethod m : {NewtonMethod::proposed, NewtonMethod::martin}) {
        const auto [r, c] = render_sphere(scene, cam, sphere, m);
        RenderOptions no_rescue;
        no_rescue.method = m;
        no_rescue.rescue = false;
        const SphereCheck c0 = check_sphere(render(scene, cam, no_rescue), cam, sphere);
        std::printf(
            "[ split sphere %s ] expected %d: missed %d extra %d holes %d (without rescue: missed %d holes %d); "
            "rescue neighbour %llu silhouette %llu general %llu trim_tolerance %llu\n",
            newton_method_name(m), c.expected_hits, c.missed, c.extra, c.holes, c0.missed, c0.holes,
            (unsigned long long)r.stats.rescue_neighbour, (unsigned long long)r.stats.rescue_silhouette,
            (unsigned long long)r.stats.rescue_general, (unsigned long long)r.stats.rescue_trim_tolerance);
        EXPECT_GT(c0.missed, 20);  // the setup does crack and lose silhouette pixels without the rescue
        EXPECT_EQ(c.missed, 0);
        EXPECT_EQ(c.extra, 0);
        EXPECT_EQ(c.holes, 0);
        EXPECT_EQ(r.stats.holes, 0u);
        EXPECT_GT(r.stats.rescue_trim_tolerance, 0u);
        EXPECT_GT(r.stats.rescue_silhouette, 0u);
        EXPECT_EQ(r.stats.fallback, r.stats.rescue_neighbour + r.stats.rescue_silhouette + r.stats.rescue_general +
                                        r.stats.rescue_trim_tolerance);
    }
}

// A sphere octant with a 2 x 2 mesh: the map's silhouette is the chords', far
// inside the exact one; the silhouette extension must recover every pixel whose
// ray hits the exact surface, and nothing else.
// A face whose map mesh lies behind another face's where the surfaces are closer
// than the mesh's deflection (a fold, or two nearly coincident faces): the map
// hands those pixels the farther face and Newton converges there. The
// nearer-sheet pass must find the front face from the neighbouring pixels.
TEST(RendererRender, NearerSheetReplacesAFartherHit) {
    const AnalyticPatch front = plane_patch();
    CameraSpec spec = front.view;
    spec.width = 160;
    spec.height = 120;
    const Camera cam(spec);
    const double gap = 0.01;  // the back face lies this far behind the front one
    Scene scene;
    Face a = make_face(front, 1, 8);
    // Push the middle mesh vertex of the front face far behind both faces: around
    // it the map sees the back face.
    const size_t mid = 4 * 9 + 4;
    a.mesh.xyz[mid] = a.mesh.xyz[mid] + 0.3 * cam.forward();
    AnalyticPatch back = front;
    for (Vec4& c : back.surface.cp)
        c = Vec4{c.x + gap * cam.forward().x * c.w, c.y + gap * cam.forward().y * c.w,
                 c.z + gap * cam.forward().z * c.w, c.w};
    back.box = BBox{};
    finish_box(back);
    scene.faces = {a, make_face(back, 2, 8)};
    scene.bbox.extend(front.box);
    scene.bbox.extend(back.box);

    for (NewtonMethod m : {NewtonMethod::proposed, NewtonMethod::martin}) {
        RenderOptions off;
        off.method = m;
        off.rescue = false;
        const RenderResult plain = render(scene, cam, off);
        size_t back_pixels = 0;
        for (uint32_t f : plain.image.face) back_pixels += f == 2;
        ASSERT_GT(back_pixels, 10u) << "the set-up must put the back face into the map";

        RenderOptions on;
        on.method = m;
        const RenderResult r = render(scene, cam, on);
        EXPECT_GT(r.stats.rescue_nearer, 0u);
        size_t checked = 0;
        for (int j = 0; j < spec.height; ++j)
            for (int i = 0; i < spec.width; ++i) {
                const size_t k = static_cast<size_t>(j) * spec.width + i;
                const std::optional<double> t = front.hit(cam.pixel_ray(i, j));
                if (!t || r.image.face[k] == 0) continue;  // silhouette pixels: other tests
                ++checked;
                EXPECT_EQ(r.image.face[k], 1u) << "pixel " << i << "," << j;
                EXPECT_NEAR(r.image.z[k], *t, 1e-5 * *t) << "pixel " << i << "," << j;
            }
        EXPECT_GT(checked, 1000u);
    }
}

TEST(RendererRender, SilhouetteMatchesAnalyticSphere) {
    const AnalyticPatch sphere = sphere_patch(1.5);
    Scene scene;
    scene.faces.push_back(make_face(sphere, 1, 2));
    scene.bbox = sphere.box;
    CameraSpec spec = sphere.view;
    spec.width = 240;
    spec.height = 180;
    for (Projection proj : {Projection::perspective, Projection::orthographic}) {
        spec.projection = proj;
        spec.ortho_height = 3.0;
        const Camera cam(spec);
        for (NewtonMethod m : {NewtonMethod::proposed, NewtonMethod::martin}) {
            const auto [r, c] = render_sphere(scene, cam, sphere, m);
            std::printf(
                "[ coarse sphere %s %s ] expected %d: missed %d extra %d; silhouette rescue %llu general %llu\n",
                proj == Projection::perspective ? "persp" : "ortho", newton_method_name(m), c.expected_hits, c.missed,
                c.extra, (unsigned long long)r.stats.rescue_silhouette, (unsigned long long)r.stats.rescue_general);
            EXPECT_GT(r.stats.rescue_silhouette, 0u);
            EXPECT_EQ(c.missed, 0);
            EXPECT_EQ(c.extra, 0);
        }
    }
}

TEST(RendererRender, ProgressIsMonotoneAndEndsAtOne) {
    AnalyticPatch sphere, plane;
    const Scene scene = sphere_and_holed_plane(sphere, plane);
    const Camera cam(iso_view(scene, 160, 120));
    std::vector<double> seen;
    RenderOptions opt;
    opt.threads = 2;
    opt.progress = [&](double f) { seen.push_back(f); };  // calls are serialized by the renderer
    const RenderResult r = render(scene, cam, opt);
    ASSERT_GE(seen.size(), 3u);
    EXPECT_EQ(seen.back(), 1.0);
    for (size_t k = 1; k < seen.size(); ++k) EXPECT_GT(seen[k], seen[k - 1]);
    RenderOptions quiet;
    quiet.threads = 2;
    EXPECT_EQ(render(scene, cam, quiet).image.rgba, r.image.rgba);  // no effect on the output
}

// A cancel flag set before the frame, or while it runs (from the progress
// callback, i.e. mid-frame on a rendering thread), ends the render with
// Error(canceled) instead of a partial image; an unset flag changes nothing.
TEST(RendererRender, CancelFlagStopsTheFrame) {
    AnalyticPatch sphere, plane;
    const Scene scene = sphere_and_holed_plane(sphere, plane);
    const Camera cam(iso_view(scene, 160, 120));
    auto flag = std::make_shared<std::atomic<bool>>(true);
    RenderOptions opt;
    opt.threads = 2;
    opt.cancel = flag;
    try {
        render(scene, cam, opt);
        ADD_FAILURE() << "a canceled render returned an image";
    } catch (const Error& e) {
        EXPECT_EQ(e.code(), ErrorCode::canceled);
    }

    flag->store(false);
    double last = 0;
    opt.progress = [&](double f) {
        last = f;
        if (f > 0.3) flag->store(true);
    };
    EXPECT_THROW(render(scene, cam, opt), Error);
    EXPECT_GT(last, 0.3);
    EXPECT_LT(last, 1.0);  // it never reported a finished frame

    flag->store(false);
    opt.progress = nullptr;
    RenderOptions plain;
    plain.threads = 2;
    EXPECT_EQ(render(scene, cam, opt).image.rgba, render(scene, cam, plain).image.rgba);
}

TEST(RendererRender, WritesExrWithAovsAndPng) {
    AnalyticPatch sphere, plane;
    const Scene scene = sphere_and_holed_plane(sphere, plane);
    const Camera cam(iso_view(scene, 64, 48));
    const RenderResult r = render(scene, cam, RenderOptions{});
    const auto dir = std::filesystem::temp_directory_path() / "nurbsrt_render_test";
    std::filesystem::create_directories(dir);
    write_image(r.image, (dir / "f.exr").string());
    write_image(r.image, (dir / "f.png").string());
    auto in = OIIO::ImageInput::open((dir / "f.exr").string());
    ASSERT_TRUE(in);
    const OIIO::ImageSpec& spec = in->spec();
    EXPECT_EQ(spec.width, 64);
    ASSERT_EQ(spec.nchannels, 12);
    std::vector<std::string> names(spec.channelnames.begin(), spec.channelnames.end());
    for (const char* c : {"R", "G", "B", "A", "Z", "face", "N.X", "N.Y", "N.Z", "u", "v", "iterations"})
        EXPECT_NE(std::find(names.begin(), names.end(), c), names.end()) << c;
    auto channel = [&](const char* c) {
        return static_cast<int>(std::find(names.begin(), names.end(), c) - names.begin());
    };
    const int fc = channel("face"), ic = channel("iterations");
    EXPECT_EQ(spec.channelformat(fc), OIIO::TypeDesc::UINT32);
    EXPECT_EQ(spec.channelformat(ic), OIIO::TypeDesc::UINT32);
    std::vector<uint32_t> face(64 * 48), its(64 * 48);
    ASSERT_TRUE(in->read_image(0, 0, fc, fc + 1, OIIO::TypeDesc::UINT32, face.data()));
    EXPECT_EQ(face, r.image.face);
    ASSERT_TRUE(in->read_image(0, 0, ic, ic + 1, OIIO::TypeDesc::UINT32, its.data()));
    for (size_t k = 0; k < its.size(); ++k) EXPECT_EQ(its[k], r.image.iterations[k]);
    std::vector<float> u(64 * 48), nz(64 * 48);
    ASSERT_TRUE(in->read_image(0, 0, channel("u"), channel("u") + 1, OIIO::TypeDesc::FLOAT, u.data()));
    ASSERT_TRUE(in->read_image(0, 0, channel("N.Z"), channel("N.Z") + 1, OIIO::TypeDesc::FLOAT, nz.data()));
    EXPECT_EQ(u, r.image.u);
    for (size_t k = 0; k < nz.size(); ++k) {
        EXPECT_EQ(nz[k], r.image.normal[3 * k + 2]);
        if (r.image.face[k]) {  // unit shading normals where hit
            const float* n = &r.image.normal[3 * k];
            EXPECT_NEAR(n[0] * n[0] + n[1] * n[1] + n[2] * n[2], 1.0f, 1e-5f);
        }
    }
    in->close();
    EXPECT_GT(std::filesystem::file_size(dir / "f.png"), 100u);
    EXPECT_THROW(write_image(r.image, (dir / "f.unknownext").string()), std::exception);
}

// Speed of the two methods on the same frames (printed; the paper reports a
// 14-24% speed-up of `proposed`).
TEST(RendererRender, MethodTiming) {
    Scene scene;
    uint32_t id = 1;
    for (const AnalyticPatch& p : {sphere_patch(1.5), saddle_patch(), high_degree_patch()}) {
        Face f = make_face(p, id++, 16);
        // Spread the patches apart.
        const Vec3 off{4.0 * (id - 2), 0, 0};
        for (Vec4& c : f.surface.cp) c = c + Vec4{off.x * c.w, off.y * c.w, off.z * c.w, 0};
        for (Vec3& x : f.mesh.xyz) x = x + off;
        scene.faces.push_back(f);
        for (const Vec3& x : f.mesh.xyz) scene.bbox.extend(x);
    }
    const Camera cam(iso_view(scene, 512, 512));
    double ms[2] = {0, 0};
    for (int rep = 0; rep < 3; ++rep)
        for (NewtonMethod m : {NewtonMethod::proposed, NewtonMethod::martin}) {
            RenderOptions o;
            o.method = m;
            o.threads = 1;
            const RenderResult r = render(scene, cam, o);
            const double t = r.stats.newton_ms;
            double& best = ms[m == NewtonMethod::martin];
            best = rep == 0 ? t : std::min(best, t);
            if (rep == 2)
                std::printf(
                    "[ 512x512 %s ] newton %.1f ms (best of 3), map %.1f ms, shade %.1f ms, hits %zu, mean it %.2f\n",
                    newton_method_name(m), best, r.stats.preliminary_map_ms, r.stats.shade_ms, r.stats.pixels_hit,
                    r.stats.mean_iterations);
        }
    std::printf("[ 512x512 ] proposed / martin newton time = %.3f\n", ms[0] / ms[1]);
}
