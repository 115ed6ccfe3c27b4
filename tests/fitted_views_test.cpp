// Fitted views end to end, as a user gets them (import -> fitted_camera ->
// render): every named view of models of different shapes, at landscape,
// square and tall frames, in both projections, shows the whole part with its
// margin clear (no hit pixel on the frame border) and fills the frame (the hit
// area's larger extent is a good share of the frame's matching extent).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "importer/importer.h"
#include "renderer/camera.h"
#include "renderer/prepared_scene.h"
#include "renderer/render.h"
#include "support/fixtures.h"

using namespace nurbsrt;

namespace {

struct HitBox {
    int x0 = 1 << 30, y0 = 1 << 30, x1 = -1, y1 = -1;
    bool empty() const { return x1 < 0; }
};

HitBox hit_box(const RenderImage& im) {
    HitBox b;
    for (int y = 0; y < im.height; ++y)
        for (int x = 0; x < im.width; ++x)
            if (im.face[static_cast<size_t>(y) * im.width + x] != 0)
                b.x0 = std::min(b.x0, x), b.x1 = std::max(b.x1, x), b.y0 = std::min(b.y0, y), b.y1 = std::max(b.y1, y);
    return b;
}

// Share of the frame the hit area spans along its binding axis.
double fill_of(const HitBox& b, int width, int height) {
    return std::max(double(b.x1 - b.x0 + 1) / width, double(b.y1 - b.y0 + 1) / height);
}

struct Frame {
    int width, height;
};
// 4:3 landscape, square, and a tall 1:3 frame (the rod lies across it in most views).
constexpr Frame kFrames[] = {{160, 120}, {120, 120}, {60, 180}};
const char* const kViews[] = {"iso", "front", "back", "left", "right", "top", "bottom"};

// With the default 5 % margin the binding axis spans 90 % of the frame up to
// the mesh slack and pixel rounding; a loose fit (the model small in the frame)
// is what this bound catches.
constexpr double kMinFill = 0.8;

void check_model(const std::string& label, const std::string& path) {
    const Scene scene = import_file(path);
    const PreparedScene prepared = prepare(scene);
    double worst_fill = 1;
    for (Projection proj : {Projection::perspective, Projection::orthographic})
        for (const Frame& fr : kFrames)
            for (const char* view : kViews) {
                CameraSpec base;
                base.projection = proj;
                base.width = fr.width;
                base.height = fr.height;
                ViewRequest rq;
                rq.view = view;
                const Camera camera(fitted_camera(rq, scene, base));
                const RenderResult r = render(prepared, camera, RenderOptions{});
                const std::string what = label + " " + view + " " + std::to_string(fr.width) + "x" +
                                         std::to_string(fr.height) +
                                         (proj == Projection::perspective ? " perspective" : " orthographic");
                const HitBox b = hit_box(r.image);
                ASSERT_FALSE(b.empty()) << what << ": nothing hit";
                EXPECT_GT(b.x0, 0) << what << ": touches the left border";
                EXPECT_GT(b.y0, 0) << what << ": touches the top border";
                EXPECT_LT(b.x1, fr.width - 1) << what << ": touches the right border";
                EXPECT_LT(b.y1, fr.height - 1) << what << ": touches the bottom border";
                const double fill = fill_of(b, fr.width, fr.height);
                EXPECT_GE(fill, kMinFill) << what << ": the part fills too little of the frame";
                worst_fill = std::min(worst_fill, fill);
            }
    ::testing::Test::RecordProperty("worst_fill", std::to_string(worst_fill));
    std::printf("%s: smallest fill over 42 views %.3f\n", label.c_str(), worst_fill);
}

TEST(FittedViews, OcctBearing) { check_model("bearing.iges", "/usr/share/opencascade/data/iges/bearing.iges"); }
TEST(FittedViews, OcctScrew) { check_model("screw.step", "/usr/share/opencascade/data/step/screw.step"); }
TEST(FittedViews, ElongatedRod) { check_model("elongated_rod", test::elongated_rod()); }

// fit_margin sets the empty border: at 20 % a side the part spans 60 % of the
// frame on its binding axis (up to the mesh slack and a pixel), and never more.
TEST(FittedViews, MarginSetsTheBorder) {
    const Scene scene = import_file("/usr/share/opencascade/data/step/screw.step");
    const PreparedScene prepared = prepare(scene);
    for (Projection proj : {Projection::perspective, Projection::orthographic})
        for (const char* view : {"iso", "front", "top"}) {
            CameraSpec base;
            base.projection = proj;
            base.width = 160;
            base.height = 120;
            ViewRequest rq;
            rq.view = view;
            rq.fit_margin = 0.2;
            const RenderResult r = render(prepared, Camera(fitted_camera(rq, scene, base)), RenderOptions{});
            const HitBox b = hit_box(r.image);
            ASSERT_FALSE(b.empty()) << view;
            const double fill = fill_of(b, base.width, base.height);
            EXPECT_GT(fill, 0.55) << view;
            EXPECT_LT(fill, 0.62) << view;
            // 20 % of 160 and of 120 pixels, less a pixel of rounding.
            EXPECT_GE(std::min(b.x0, base.width - 1 - b.x1), 31) << view;
            EXPECT_GE(std::min(b.y0, base.height - 1 - b.y1), 23) << view;
        }
}

}  // namespace

// The named views' directions and ups as the README, the CLI's --help and the
// OpenAPI View schema document them (CAD convention, Z up): the direction from
// the eye to the target, and the image's up, for both projections.
TEST(FittedViews, DocumentedDirections) {
    struct Documented {
        const char* view;
        Vec3 along, up;
    };
    const double s = 1 / std::sqrt(3.0);
    const Documented kDocumented[] = {
        {"front", {0, 1, 0}, {0, 0, 1}},  {"back", {0, -1, 0}, {0, 0, 1}}, {"left", {1, 0, 0}, {0, 0, 1}},
        {"right", {-1, 0, 0}, {0, 0, 1}}, {"top", {0, 0, -1}, {0, 1, 0}},  {"bottom", {0, 0, 1}, {0, 1, 0}},
        {"iso", {-s, -s, -s}, {0, 0, 1}},
    };
    const Scene scene = import_file(test::elongated_rod());
    for (Projection proj : {Projection::perspective, Projection::orthographic})
        for (const Documented& d : kDocumented) {
            CameraSpec base;
            base.projection = proj;
            ViewRequest rq;
            rq.view = d.view;
            const CameraSpec cs = fitted_camera(rq, scene, base);
            const Vec3 along = normalize(cs.target - cs.eye);
            EXPECT_GT(dot(along, d.along), 1 - 1e-12) << d.view;
            // The image's up: the up made perpendicular to the view (iso's
            // +Z tilts towards the eye), the camera's and the documented one alike.
            auto image_up = [&](Vec3 u) { return normalize(u - dot(u, along) * along); };
            EXPECT_GT(dot(image_up(cs.up), image_up(d.up)), 1 - 1e-9) << d.view << " up";
        }
}
