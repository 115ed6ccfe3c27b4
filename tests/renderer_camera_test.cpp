// Camera: the pixel-ray contract of renderer/camera.h, the projection to R^2 and named views.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <string>

#include "renderer/camera.h"
#include "core/error.h"
#include "core/scene/nurbs.h"

using namespace nurbsrt;

namespace {

CameraSpec persp_spec() {
    CameraSpec s;
    s.eye = {3, -4, 2};
    s.target = {0.5, 0.2, -0.1};
    s.up = {0, 0, 1};
    s.fov_deg = 35;
    s.width = 320;
    s.height = 200;
    return s;
}

CameraSpec ortho_spec() {
    CameraSpec s = persp_spec();
    s.projection = Projection::orthographic;
    s.ortho_height = 7.5;
    return s;
}

void expect_near(Vec3 a, Vec3 b, double tol) {
    EXPECT_NEAR(a.x, b.x, tol);
    EXPECT_NEAR(a.y, b.y, tol);
    EXPECT_NEAR(a.z, b.z, tol);
}

// The view's forward, right and up unit vectors (the camera contract's basis).
struct ViewBasis {
    Vec3 f, r, u;
};
ViewBasis view_basis(const CameraSpec& s) {
    const Vec3 f = normalize(s.target - s.eye);
    const Vec3 r = normalize(cross(f, s.up));
    return {f, r, cross(r, f)};
}

}  // namespace

TEST(RendererCamera, PixelRayContractPerspective) {
    const CameraSpec s = persp_spec();
    const Camera cam(s);
    const auto [f, r, u] = view_basis(s);
    const double a = 320.0 / 200.0, t = std::tan(35.0 * M_PI / 360.0);
    for (auto [i, j] : {std::pair{0, 0}, {319, 199}, {160, 100}, {17, 151}}) {
        const double sx = (2 * (i + 0.5) / 320 - 1) * a, sy = 1 - 2 * (j + 0.5) / 200;
        const Ray ray = cam.pixel_ray(i, j);
        expect_near(ray.origin, s.eye, 0);
        expect_near(ray.dir, normalize(f + t * (sx * r + sy * u)), 1e-15);
        EXPECT_NEAR(length(ray.dir), 1.0, 1e-15);
    }
    // Top-left pixel looks up and left, bottom-right down and right.
    EXPECT_GT(dot(cam.pixel_ray(0, 0).dir, u), 0);
    EXPECT_LT(dot(cam.pixel_ray(0, 0).dir, r), 0);
    EXPECT_LT(dot(cam.pixel_ray(319, 199).dir, u), 0);
    EXPECT_GT(dot(cam.pixel_ray(319, 199).dir, r), 0);
}

TEST(RendererCamera, PixelRayContractOrthographic) {
    const CameraSpec s = ortho_spec();
    const Camera cam(s);
    const auto [f, r, u] = view_basis(s);
    const double a = 320.0 / 200.0;
    for (auto [i, j] : {std::pair{0, 0}, {319, 199}, {160, 100}, {17, 151}}) {
        const double sx = (2 * (i + 0.5) / 320 - 1) * a, sy = 1 - 2 * (j + 0.5) / 200;
        const Ray ray = cam.pixel_ray(i, j);
        expect_near(ray.origin, s.eye + 3.75 * (sx * r + sy * u), 1e-14);
        expect_near(ray.dir, f, 0);
    }
}

// pixel_x and pixel_y invert screen(): the continuous pixel position of a screen
// point, pixel i's centre at i + 0.5 (a 320 x 200 frame: aspect 1.6, both projections).
TEST(RendererCamera, PixelPositionInvertsScreen) {
    for (const CameraSpec& s : {persp_spec(), ortho_spec()}) {
        const Camera cam(s);
        for (auto [px, py] : {std::pair{0.0, 0.0}, {320.0, 200.0}, {160.5, 100.5}, {17.25, 151.75}, {-3.0, 210.0}}) {
            const ScreenPoint sp = cam.screen(px, py);
            EXPECT_NEAR(cam.pixel_x(sp.sx), px, 1e-12);
            EXPECT_NEAR(cam.pixel_y(sp.sy), py, 1e-12);
        }
        const ScreenPoint c = cam.pixel_screen(17, 151);
        EXPECT_NEAR(cam.pixel_x(c.sx), 17.5, 1e-12);
        EXPECT_NEAR(cam.pixel_y(c.sy), 151.5, 1e-12);
    }
}

TEST(RendererCamera, RejectsDegenerateSpecs) {
    CameraSpec s = persp_spec();
    s.target = s.eye;
    EXPECT_THROW(Camera{s}, Error);
    s = persp_spec();
    s.up = s.target - s.eye;
    EXPECT_THROW(Camera{s}, Error);
    s = persp_spec();
    s.width = 0;
    EXPECT_THROW(Camera{s}, Error);
    s = ortho_spec();
    s.ortho_height = 0;
    EXPECT_THROW(Camera{s}, Error);
}

// A point on pixel (i, j)'s ray, in homogeneous form with any weight, projects to
// that pixel's (sx, sy), and its depth gives back the hit distance t.
TEST(RendererCamera, ProjectedPointOnRayIsItsScreenPoint) {
    std::mt19937_64 rng(7);
    std::uniform_int_distribution<int> col(0, 319), row(0, 199);
    std::uniform_real_distribution<double> tdist(0.5, 20), wdist(0.2, 3);
    for (const CameraSpec& s : {persp_spec(), ortho_spec()}) {
        const Camera cam(s);
        for (int k = 0; k < 200; ++k) {
            const int i = col(rng), j = row(rng);
            const double t = tdist(rng), w = wdist(rng);
            const Ray ray = cam.pixel_ray(i, j);
            const Vec3 p = ray.origin + t * ray.dir;
            const Vec4 P = cam.project_h({w * p.x, w * p.y, w * p.z, w});
            const ScreenPoint sp = cam.pixel_screen(i, j);
            const double sx = P.x / P.z, sy = P.y / P.z;
            EXPECT_NEAR(sx, sp.sx, 1e-13);
            EXPECT_NEAR(sy, sp.sy, 1e-13);
            EXPECT_NEAR(cam.hit_distance_from_depth(cam.depth(P), sp), t, 1e-13 * t);
        }
    }
}

// The projected surface is the projection of the surface (linearity of project_h).
TEST(RendererCamera, ProjectedSurfaceMatchesProjectedPoints) {
    NurbsSurface s{.degree_u = 2,
                   .degree_v = 1,
                   .num_u = 3,
                   .num_v = 2,
                   .knots_u = {0, 0, 0, 1, 1, 1},
                   .knots_v = {0, 0, 1, 1},
                   .cp = {},  // the poles below
                   .rational = true};
    const double w = std::sqrt(0.5);
    // Quarter cylinder of radius 2, height 3 (exact conic weights).
    const Vec3 pts[3] = {{2, 0, 0}, {2, 2, 0}, {0, 2, 0}};
    const double ws[3] = {1, w, 1};
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 2; ++j) {
            const Vec3 p = pts[i] + Vec3{0, 0, 3.0 * j};
            s.cp.push_back({ws[i] * p.x, ws[i] * p.y, ws[i] * p.z, ws[i]});
        }
    for (const CameraSpec& spec : {persp_spec(), ortho_spec()}) {
        const Camera cam(spec);
        const NurbsSurface ps = project_surface(cam, s);
        for (double u : {0.0, 0.3, 0.77, 1.0})
            for (double v : {0.0, 0.5, 1.0}) {
                const Vec4 a = evaluate(ps, u, v);
                const Vec4 b = cam.project_h(evaluate(s, u, v));
                EXPECT_NEAR(a.x, b.x, 1e-12);
                EXPECT_NEAR(a.y, b.y, 1e-12);
                EXPECT_NEAR(a.z, b.z, 1e-12);
                EXPECT_NEAR(a.w, b.w, 1e-12);
            }
    }
}

// GL clip coordinates put the contract's pixel centre of (i, j) at GL window
// position (i + 0.5, H - 1 - j + 0.5).
TEST(RendererCamera, ClipCoordinatesMatchPixelCentres) {
    for (const CameraSpec& s : {persp_spec(), ortho_spec()}) {
        const Camera cam(s);
        for (auto [i, j] : {std::pair{0, 0}, {319, 199}, {100, 30}}) {
            const Ray ray = cam.pixel_ray(i, j);
            const Vec3 p = ray.origin + 5.0 * ray.dir;
            const Vec4 c = cam.clip(p, 1.0, 10.0);
            const double wx = (c.x / c.w + 1) * 0.5 * s.width;
            const double wy = (c.y / c.w + 1) * 0.5 * s.height;
            EXPECT_NEAR(wx, i + 0.5, 1e-9);
            EXPECT_NEAR(wy, s.height - 1 - j + 0.5, 1e-9);
            EXPECT_GT(c.z / c.w, -1);
            EXPECT_LT(c.z / c.w, 1);
        }
    }
}

TEST(RendererCamera, NamedViewsContainTheBox) {
    BBox box;
    box.extend(Vec3{-10, 5, 2});
    box.extend(Vec3{30, 8, 40});
    for (Projection proj : {Projection::perspective, Projection::orthographic})
        for (auto [w, h] : {std::pair{640, 480}, {300, 900}})
            for (const char* name : {"iso", "front", "back", "left", "right", "top", "bottom"}) {
                CameraSpec base;
                base.projection = proj;
                base.fov_deg = 30;
                base.width = w;
                base.height = h;
                const Camera cam(named_view(name, box, base));
                const double a = cam.aspect();
                double max_extent = 0;
                for (int c = 0; c < 8; ++c) {
                    const Vec3 p{c & 1 ? box.hi.x : box.lo.x, c & 2 ? box.hi.y : box.lo.y, c & 4 ? box.hi.z : box.lo.z};
                    const Vec4 P = cam.project_h({p.x, p.y, p.z, 1});
                    ASSERT_GT(cam.depth(P), 0) << name;
                    const double sx = P.x / P.z, sy = P.y / P.z;
                    EXPECT_LT(std::abs(sx), a) << name;
                    EXPECT_LT(std::abs(sy), 1.0) << name;
                    max_extent = std::max({max_extent, std::abs(sx) / a, std::abs(sy)});
                }
                EXPECT_GT(max_extent, 0.8) << name << ": fitted far too loosely";
            }
    // View directions as documented.
    CameraSpec base;
    const Camera front(named_view("front", box, base));
    expect_near(front.forward(), {0, 1, 0}, 1e-15);
    const Camera top(named_view("top", box, base));
    expect_near(top.forward(), {0, 0, -1}, 1e-15);
    EXPECT_THROW(named_view("diagonal", box, base), Error);
    EXPECT_THROW(named_view("iso", BBox{}, base), Error);
}

// The fit is exact: the corners' projection spans 1 - 2 margin of the frame on
// its binding axis and is centred on both axes, for any aspect, both projections.
TEST(RendererCamera, NamedViewsFitExactlyWithTheMargin) {
    BBox box;
    box.extend(Vec3{-10, 5, 2});
    box.extend(Vec3{30, 8, 40});
    for (double margin : {0.0, 0.05, 0.2})
        for (Projection proj : {Projection::perspective, Projection::orthographic})
            for (auto [w, h] : {std::pair{640, 480}, {300, 300}, {200, 600}})
                for (const char* name : {"iso", "front", "back", "left", "right", "top", "bottom"}) {
                    CameraSpec base;
                    base.projection = proj;
                    base.width = w;
                    base.height = h;
                    const Camera cam(named_view(name, box, base, margin));
                    const double a = cam.aspect();
                    double x0 = HUGE_VAL, x1 = -HUGE_VAL, y0 = HUGE_VAL, y1 = -HUGE_VAL;
                    for (int c = 0; c < 8; ++c) {
                        const Vec3 p{c & 1 ? box.hi.x : box.lo.x, c & 2 ? box.hi.y : box.lo.y,
                                     c & 4 ? box.hi.z : box.lo.z};
                        const Vec4 P = cam.project_h({p.x, p.y, p.z, 1});
                        ASSERT_GT(cam.depth(P), 0) << name;
                        x0 = std::min(x0, P.x / P.z / a), x1 = std::max(x1, P.x / P.z / a);
                        y0 = std::min(y0, P.y / P.z), y1 = std::max(y1, P.y / P.z);
                    }
                    const std::string what = std::string(name) + " " + std::to_string(w) + "x" + std::to_string(h);
                    EXPECT_NEAR(std::max(x1 - x0, y1 - y0), 2 * (1 - 2 * margin), 1e-9) << what;
                    EXPECT_NEAR(x0 + x1, 0, 1e-9) << what << ": not centred across";
                    EXPECT_NEAR(y0 + y1, 0, 1e-9) << what << ": not centred up";
                }
    CameraSpec base;
    EXPECT_THROW(named_view("iso", box, base, -0.01), Error);
    EXPECT_THROW(named_view("iso", box, base, 0.5), Error);
}

// An eye alone looks at the model's centre; an orthographic height not given is
// fitted around that axis; target and up given replace the fitted ones.
TEST(RendererCamera, FittedCameraFromAnEye) {
    BBox box;
    box.extend(Vec3{-10, 5, 2});
    box.extend(Vec3{30, 8, 40});
    CameraSpec base;
    base.width = 400;
    base.height = 300;
    ViewRequest rq;
    rq.eye = Vec3{100, -50, 80};
    CameraSpec s = fitted_camera(rq, box, base);
    expect_near(s.eye, *rq.eye, 0);
    expect_near(s.target, box.center(), 1e-12);
    // Straight above the centre the iso up (+Z) is along the view: +Y is taken.
    rq.eye = Vec3{10, 6.5, 500};
    s = fitted_camera(rq, box, base);
    expect_near(s.up, {0, 1, 0}, 0);
    EXPECT_NO_THROW(Camera{s});
    base.projection = Projection::orthographic;
    s = fitted_camera(rq, box, base);
    // Seen from above: 40 x 3 in x, y around the centre; binding is x: 20 / a / 0.9.
    EXPECT_NEAR(s.ortho_height, 2 * 20.0 / (4.0 / 3.0) / 0.9, 1e-9);
    rq.ortho_height = 7;
    rq.target = Vec3{0, 0, 0};
    rq.up = Vec3{1, 0, 0};
    s = fitted_camera(rq, box, base);
    EXPECT_EQ(s.ortho_height, 7);
    expect_near(s.target, {0, 0, 0}, 0);
    expect_near(s.up, {1, 0, 0}, 0);
}
