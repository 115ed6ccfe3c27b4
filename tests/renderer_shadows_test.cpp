// Exact shadows of the key light against the analytic truth: a sphere (eight
// exact rational octants) above a square plate, lit by the rig's key light; the
// shadow on the plate is the set of points whose ray towards the light meets the
// sphere. Every plate pixel's shadow flag must agree with that, except where the
// analytic boundary passes within one pixel; no lit-facing point of the convex
// sphere may shadow itself (acne); the shading darkens exactly the flagged pixels.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "renderer/frame/frame.h"
#include "renderer/passes/lighting.h"
#include "renderer/render.h"
#include "renderer_test_surfaces.h"

using namespace nurbsrt;
using namespace nurbsrt::testing;

namespace {

constexpr double kRadius = 0.7, kHalfPlate = 3.0;
const Vec3 kCentre{0.2, -0.1, 2.0};

// Appends `p` (its box made) as a face of colour `c`, meshed n x n for the map.
void add_coloured(Scene& s, AnalyticPatch& p, int n, Color c) {
    finish_box(p);
    Face f = make_face(p, static_cast<uint32_t>(s.faces.size() + 1), n);
    f.color = c;
    f.has_color = true;
    s.faces.push_back(f);
    s.bbox.extend(p.box);
}

// The eight octants of a sphere: the +x+y+z octant patch turned about z by
// quarter turns, and mirrored in z for the lower half.
void add_sphere(Scene& s) {
    const AnalyticPatch octant = sphere_patch(kRadius);
    for (int half = 0; half < 2; ++half)
        for (int quarter = 0; quarter < 4; ++quarter) {
            AnalyticPatch p = octant;
            for (Vec4& c : p.surface.cp) {
                Vec3 q{c.x, c.y, c.z};  // homogeneous: the map is linear, so it applies to w-scaled points alike
                for (int k = 0; k < quarter; ++k) q = {-q.y, q.x, q.z};
                if (half) q.z = -q.z;
                c = {q.x + kCentre.x * c.w, q.y + kCentre.y * c.w, q.z + kCentre.z * c.w, c.w};
            }
            p.box = BBox{};
            add_coloured(s, p, 8, {0.8f, 0.3f, 0.2f});
        }
}

// A square plate in z = 0, degree 1.
void add_plate(Scene& s) {
    AnalyticPatch p;
    NurbsSurface& ns = p.surface;
    ns.degree_u = ns.degree_v = 1;
    ns.num_u = ns.num_v = 2;
    ns.knots_u = ns.knots_v = {0, 0, 1, 1};
    for (int i = 0; i < 2; ++i)
        for (int j = 0; j < 2; ++j) ns.cp.push_back(hpt({(2 * i - 1) * kHalfPlate, (2 * j - 1) * kHalfPlate, 0}, 1));
    add_coloured(s, p, 4, {0.7f, 0.7f, 0.7f});
}

// Whether the ray from q towards the light meets the sphere (in front of q).
bool analytic_shadow(Vec3 q, Vec3 light) {
    const Vec3 d = q - kCentre;
    const double b = dot(d, light), c = dot(d, d) - kRadius * kRadius;
    const double disc = b * b - c;
    return disc > 0 && -b - std::sqrt(disc) > 0;
}

struct Frame {
    Scene scene;
    Camera camera;
    uint32_t plate = 0;
};

Frame make_frame(int size) {
    Scene s;
    add_sphere(s);
    add_plate(s);
    // Steeply from above, so the shadow falls on the plate beside the sphere.
    CameraSpec spec = look({0.6, -2.5, 9.0}, {0, 0, 0.4}, {0, 1, 0}, 45);
    spec.width = spec.height = size;
    const uint32_t plate = static_cast<uint32_t>(s.faces.size());
    return {std::move(s), Camera(spec), plate};
}

}  // namespace

TEST(RendererShadows, BoundaryOnThePlateMatchesTheAnalyticShadow) {
    const Frame fr = make_frame(256);
    RenderOptions opt;
    opt.shadows = true;
    const RenderResult r = render(fr.scene, fr.camera, opt);
    const Vec3 light = light_rig(fr.camera).key;
    ASSERT_GT(light.z, 0.3) << "the key light must shine from above the plate for this test";
    const int W = fr.camera.width(), H = fr.camera.height();
    ASSERT_EQ(r.image.shadow.size(), static_cast<size_t>(W) * H);
    // Analytic classification of every plate pixel: the pixel ray meets z = 0 at q.
    std::vector<int8_t> truth(static_cast<size_t>(W) * H, -1);  // -1: not a plate pixel
    for (int j = 0; j < H; ++j)
        for (int i = 0; i < W; ++i) {
            const size_t k = static_cast<size_t>(j) * W + i;
            if (r.image.face[k] != fr.plate) continue;
            const Ray ray = fr.camera.pixel_ray(i, j);
            const Vec3 q = ray.origin + (-ray.origin.z / ray.dir.z) * ray.dir;
            truth[k] = analytic_shadow(q, light) ? 1 : 0;
        }
    // A plate pixel is on the analytic boundary when an 8-neighbour is classified
    // the other way: the boundary passes within one pixel of its centre.
    auto on_boundary = [&](int i, int j) {
        const int8_t own = truth[static_cast<size_t>(j) * W + i];
        bool b = false;
        for_each_neighbour(W, H, i, j, 1, [&](int ni, int nj) {
            const int8_t t = truth[static_cast<size_t>(nj) * W + ni];
            b |= t >= 0 && t != own;
        });
        return b;
    };
    long shadowed = 0, agree = 0, boundary = 0, near_boundary = 0, wrong = 0;
    for (int j = 0; j < H; ++j)
        for (int i = 0; i < W; ++i) {
            const size_t k = static_cast<size_t>(j) * W + i;
            if (truth[k] < 0) continue;
            shadowed += truth[k];
            const bool edge = on_boundary(i, j);
            boundary += edge;
            if (r.image.shadow[k] == truth[k]) {
                ++agree;
                continue;
            }
            (edge ? near_boundary : wrong) += 1;
            if (!edge && wrong <= 5)
                ADD_FAILURE() << "pixel (" << i << ", " << j << "): shadow " << int(r.image.shadow[k]) << ", analytic "
                              << int(truth[k]) << ", more than a pixel from the boundary";
        }
    std::printf(
        "[ shadows ] plate pixels: %ld agree, %ld differ within 1 px of the boundary (of %ld there), %ld "
        "differ farther; %ld analytically shadowed; %llu light rays, map %d px\n",
        agree, near_boundary, boundary, wrong, shadowed, static_cast<unsigned long long>(r.stats.shadow_rays),
        r.stats.shadow_map_size);
    EXPECT_GT(shadowed, 1000) << "the shadow must be large enough to judge";
    // The boundary matches the analytic one within one pixel everywhere...
    EXPECT_EQ(wrong, 0);
    // ...and the pixels beside it agree too, but for light rays grazing the
    // sphere's silhouette (inside it by under 1 % of its radius: two nearly
    // equal roots, where Newton from the map's starts diverges).
    EXPECT_LE(near_boundary, boundary / 20);
    EXPECT_TRUE(r.stats.shadows);
    EXPECT_EQ(r.stats.shadowed_pixels,
              static_cast<uint64_t>(std::count(r.image.shadow.begin(), r.image.shadow.end(), 1)));
}

TEST(RendererShadows, NoAcneOnTheLitSideAndOnlyShadowedPixelsDarken) {
    const Frame fr = make_frame(160);
    RenderOptions plain, with;
    with.shadows = true;
    const RenderResult a = render(fr.scene, fr.camera, plain), b = render(fr.scene, fr.camera, with);
    const Vec3 light = light_rig(fr.camera).key;
    EXPECT_TRUE(a.image.shadow.empty());
    EXPECT_FALSE(a.stats.shadows);
    EXPECT_EQ(a.stats.shadow_rays, 0u);
    long sphere_lit = 0, acne = 0, darker = 0, changed_unflagged = 0;
    for (size_t k = 0; k < b.image.face.size(); ++k) {
        ASSERT_EQ(a.image.face[k], b.image.face[k]);  // shadows change colours only
        const uint32_t f = b.image.face[k];
        const bool same = std::equal(&a.image.rgba[4 * k], &a.image.rgba[4 * k + 4], &b.image.rgba[4 * k]);
        if (b.image.shadow[k]) {
            darker += b.image.rgba[4 * k] < a.image.rgba[4 * k];
        } else {
            changed_unflagged += !same;
        }
        if (f && f != fr.plate) {
            const Ray ray = fr.camera.pixel_ray(static_cast<int>(k % 160), static_cast<int>(k / 160));
            const Vec3 p = ray.origin + static_cast<double>(b.image.z[k]) * ray.dir;
            const Vec3 n = normalize(p - kCentre);
            // The sphere is convex and the plate below it: a point facing the
            // light is lit, however grazing (the point's own surface is the
            // only surface near its light ray).
            if (dot(n, light) > 0.02) {
                ++sphere_lit;
                acne += b.image.shadow[k];
            }
        }
    }
    std::printf("[ shadows ] sphere pixels facing the light: %ld, self-shadowed: %ld; shadowed pixels darker: %ld\n",
                sphere_lit, acne, darker);
    EXPECT_GT(sphere_lit, 500);
    EXPECT_EQ(acne, 0);
    EXPECT_EQ(changed_unflagged, 0) << "pixels the key light reaches must keep their colour";
    EXPECT_EQ(static_cast<uint64_t>(darker), b.stats.shadowed_pixels);
    EXPECT_GT(darker, 300);
}

TEST(RendererShadows, IndependentOfTheThreadCount) {
    const Frame fr = make_frame(96);
    RenderOptions one, two;
    one.shadows = two.shadows = true;
    one.antialias = two.antialias = 4;
    one.threads = 1;
    two.threads = 2;
    const RenderResult a = render(fr.scene, fr.camera, one), b = render(fr.scene, fr.camera, two);
    EXPECT_EQ(a.image.rgba, b.image.rgba);
    EXPECT_EQ(a.image.shadow, b.image.shadow);
    EXPECT_EQ(a.stats.shadow_rays, b.stats.shadow_rays);
}
