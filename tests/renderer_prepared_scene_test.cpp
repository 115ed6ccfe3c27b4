// Prepare once, render many: frames of one PreparedScene from several cameras
// (and interleaved with another prepared scene, so a GL context's kept map mesh
// must be replaced and restored) are bit-identical to fresh single renders of
// the Scene, with 1 and 2 threads and from several threads at once.
#include <gtest/gtest.h>

#include <thread>
#include <vector>

#include "core/error.h"
#include "renderer/solve/prepared_data.h"
#include "renderer/render.h"
#include "renderer_test_surfaces.h"
#include "tests/support/render_compare.h"

using namespace nurbsrt;
using namespace nurbsrt::testing;

namespace {

// A sphere octant and a cylinder patch trimmed by a triangle loop, side by side.
Scene two_face_scene() {
    const AnalyticPatch sphere = sphere_patch(1.5), cyl = cylinder_patch();
    Scene s;
    s.faces.push_back(make_face(sphere, 1, 10));
    Face f = make_face(cyl, 2, 10);
    TrimLoop loop;
    loop.outer = true;
    loop.points = {{0.05, 0.05}, {0.95, 0.1}, {0.4, 0.9}};
    const double ur = f.u_max - f.u_min, vr = f.v_max - f.v_min;
    for (Vec2& p : loop.points) p = {f.u_min + p.x * ur, f.v_min + p.y * vr};
    f.loops = {loop};
    s.faces.push_back(f);
    s.bbox.extend(sphere.box);
    s.bbox.extend(cyl.box);
    return s;
}

Scene sphere_scene() {
    const AnalyticPatch sphere = sphere_patch(0.7);
    Scene s;
    s.faces.push_back(make_face(sphere, 1, 6));
    s.bbox.extend(sphere.box);
    return s;
}

std::vector<Camera> cameras(const Scene& s) {
    std::vector<Camera> out;
    CameraSpec base;
    base.width = 96;
    base.height = 72;
    for (const char* view : {"iso", "front", "top", "left"}) out.emplace_back(named_view(view, s.bbox, base));
    base.projection = Projection::orthographic;
    out.emplace_back(named_view("iso", s.bbox, base));
    base.width = 40;  // another frame size: the context's framebuffer is remade
    out.emplace_back(named_view("right", s.bbox, base));
    return out;
}

}  // namespace

TEST(PreparedScene, ManyViewsGiveTheImagesOfFreshRenders) {
    const Scene scene = two_face_scene(), other = sphere_scene();
    const PreparedScene prepared = prepare(scene, 2), prepared_other = prepare(other, 1);
    EXPECT_EQ(&prepared.scene(), &scene);
    EXPECT_EQ(prepared.faces().size(), 2u);
    EXPECT_TRUE(prepared.faces()[1].trim.trimmed());
    EXPECT_GT(prepared.map_mesh().triangles(), 0u);
    EXPECT_NE(prepared.id(), prepared_other.id());
    for (NewtonMethod m : {NewtonMethod::proposed, NewtonMethod::martin})
        for (const Camera& cam : cameras(scene)) {
            SCOPED_TRACE(std::string(newton_method_name(m)) + " " + std::to_string(cam.width()));
            RenderOptions o1, o2;
            o1.method = o2.method = m;
            o1.threads = 1;
            o2.threads = 2;
            const RenderResult fresh = render(scene, cam, o1);
            EXPECT_GT(fresh.stats.pixels_hit, 100u);
            EXPECT_GE(fresh.stats.prepare_ms, 0.0);
            const RenderResult a = render(prepared, cam, o1);
            EXPECT_EQ(a.stats.prepare_ms, 0.0);
            test::expect_identical_renders(fresh, a);
            // Another prepared scene in between: the map's kept buffers change hands.
            EXPECT_GT(render(prepared_other, cam, o2).stats.pixels_hit, 0u);
            test::expect_identical_renders(fresh, render(prepared, cam, o2));
        }
}

TEST(PreparedScene, ConcurrentFramesOfOnePreparedScene) {
    const Scene scene = two_face_scene();
    const std::shared_ptr<const Scene> owned = std::make_shared<const Scene>(scene);
    const PreparedScene prepared = prepare(owned);
    const std::vector<Camera> cams = cameras(scene);
    std::vector<RenderResult> fresh;
    for (const Camera& cam : cams) fresh.push_back(render(scene, cam, RenderOptions{}));
    std::vector<std::vector<RenderResult>> got(3);
    std::vector<std::thread> threads;
    for (size_t t = 0; t < got.size(); ++t)
        threads.emplace_back([&, t] {
            RenderOptions o;
            o.threads = 1;
            for (const Camera& cam : cams) got[t].push_back(render(prepared, cam, o));
        });
    for (std::thread& t : threads) t.join();
    for (const std::vector<RenderResult>& g : got)
        for (size_t k = 0; k < cams.size(); ++k) test::expect_identical_renders(fresh[k], g[k]);
}

TEST(PreparedScene, ChecksFaceNumbering) {
    Scene s = sphere_scene();
    s.faces[0].index = 2;
    EXPECT_THROW(prepare(s), Error);
    EXPECT_THROW(prepare(std::shared_ptr<const Scene>()), Error);
}

// A flat bicubic face of n x n control points on a grid of the plane z = 0
// (uniform knots), over [x0, x0 + 1] x [0, 1].
AnalyticPatch dense_flat_patch(int n, double x0) {
    AnalyticPatch p;
    p.name = "dense flat";
    NurbsSurface& s = p.surface;
    s.degree_u = s.degree_v = 3;
    s.num_u = s.num_v = n;
    std::vector<double> interior;
    for (int k = 1; k < n - 3; ++k) interior.push_back(double(k) / (n - 3));
    s.knots_u = s.knots_v = clamped_knots(3, interior);
    for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j) s.cp.push_back(hpt({x0 + double(i) / (n - 1), double(j) / (n - 1), 0}, 1));
    return p;
}

// The power-form patches of a whole scene stay within their budget (2^21
// coefficients): 12 faces of 117 x 117 bicubic spans would hold 2.6 M; the
// largest keep only their basis tables, and every face still renders exactly.
TEST(PreparedScene, PatchMemoryIsBoundedPerScene) {
    constexpr int kFaces = 12;
    Scene s;
    for (int k = 0; k < kFaces; ++k) {
        s.faces.push_back(make_face(dense_flat_patch(120, 1.1 * k), k + 1, 4));
        s.bbox.extend(Vec3{1.1 * k, 0, 0});
        s.bbox.extend(Vec3{1.1 * k + 1, 1, 0});
    }
    const PreparedScene p = prepare(s);
    size_t total = 0;
    int with = 0;
    for (const PreparedFace& f : p.faces()) {
        total += f.patches.coef.size();
        with += f.patches.usable();
    }
    EXPECT_LE(total, size_t(1) << 21);
    EXPECT_GT(with, 0);
    EXPECT_LT(with, kFaces);
    CameraSpec base;
    base.width = 240;
    base.height = 60;
    const Camera cam(named_view("top", s.bbox, base));
    const RenderResult r = render(p, cam, RenderOptions{});
    std::vector<int> pixels(kFaces + 1, 0);
    for (int j = 0; j < cam.height(); ++j)
        for (int i = 0; i < cam.width(); ++i) {
            const size_t k = static_cast<size_t>(j) * cam.width() + i;
            const uint32_t face = r.image.face[k];
            if (!face) continue;
            ++pixels[face];
            const Ray ray = cam.pixel_ray(i, j);
            EXPECT_NEAR((ray.origin + double(r.image.z[k]) * ray.dir).z, 0.0, 1e-5);
        }
    for (int f = 1; f <= kFaces; ++f) EXPECT_GT(pixels[f], 100) << "face " << f;
}
