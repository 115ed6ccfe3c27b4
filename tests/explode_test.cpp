// Exploded views (core/scene/explode.h) on the generated two-bracket assembly:
// each top-level part moves rigidly away from the assembly's centre by the
// factor times its size; control points, map meshes and placements alike.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "core/error.h"
#include "core/scene/explode.h"
#include "importer/importer.h"
#include "options/render_request.h"
#include "renderer/render.h"
#include "tests/support/fixtures.h"

namespace nurbsrt {
namespace {

TEST(Explode, TopLevelPartsMoveApartRigidly) {
    const Scene before = import_file(test::assembly());
    Scene after = before;
    const double diag = before.bbox.diagonal();
    ASSERT_EQ(explode_scene(after, 0.5, ExplodeLevel::top), 2u);  // the two brackets
    ASSERT_EQ(after.faces.size(), before.faces.size());
    const Vec3 centre = before.bbox.center();
    for (size_t i = 0; i < before.faces.size(); ++i) {
        const Face& a = before.faces[i];
        const Face& b = after.faces[i];
        ASSERT_EQ(a.mesh.xyz.size(), b.mesh.xyz.size());
        const Vec3 t = b.mesh.xyz[0] - a.mesh.xyz[0];
        EXPECT_NEAR(length(t), 0.5 * diag, 1e-9 * diag) << "face " << i + 1;
        for (size_t k = 0; k < a.mesh.xyz.size(); ++k) EXPECT_NEAR(length(b.mesh.xyz[k] - a.mesh.xyz[k] - t), 0, 1e-9);
        for (size_t k = 0; k < a.surface.cp.size(); ++k) {  // homogeneous: x moves by w t
            const Vec4 &p = a.surface.cp[k], &q = b.surface.cp[k];
            EXPECT_NEAR(q.x - p.x, p.w * t.x, 1e-9 * diag);
            EXPECT_NEAR(q.w, p.w, 0);
        }
        // Away from the centre: the move points the way the face already lay.
        EXPECT_GT(dot(t, a.mesh.xyz[0] - centre), 0) << "face " << i + 1;
    }
    EXPECT_GT(after.bbox.diagonal(), diag);
    EXPECT_EQ(explode_scene(after, 0, ExplodeLevel::top), 0u);
}

// The frame with the parts moved by RenderOptions::face_offsets (per-face
// cameras over the scene as it was prepared) against the frame of the scene
// whose geometry explode_scene moved and which was prepared again: the same
// faces at the same depths over the whole frame, with sections, shadows and
// the ground on, in both projections.
TEST(Explode, OffsetsRenderTheMovedSceneWithoutANewPrepare) {
    const Scene before = import_file(test::assembly());
    Scene moved = before;
    ASSERT_EQ(explode_scene(moved, 0.15, ExplodeLevel::top), 2u);
    const PreparedScene prepared_before = prepare(before, 2), prepared_moved = prepare(moved, 2);
    for (const Projection projection : {Projection::orthographic, Projection::perspective}) {
        RenderRequest r;
        r.width = 256;
        r.height = 192;
        r.view = "iso";
        r.projection = projection;
        r.explode = 0.15;
        RenderOptions with_offsets = render_options_for(r, before);
        ASSERT_EQ(with_offsets.face_offsets.size(), before.faces.size());
        r.explode = 0;
        RenderOptions plain = render_options_for(r, moved);
        ASSERT_TRUE(plain.face_offsets.empty());
        EXPECT_EQ(with_offsets.newton.eps, plain.newton.eps);
        const CameraSpec fit_moved = camera_spec_for(r, moved);
        const CameraSpec fit_offsets = camera_spec_for(r, before, {}, with_offsets.face_offsets);
        EXPECT_NEAR(length(fit_moved.eye - fit_offsets.eye), 0, 1e-9 * moved.bbox.diagonal());
        // A section through the middle of the first part where it moved to,
        // shadows on a ground.
        BBox first;
        for (const Face& f : moved.faces)
            if (f.body == moved.faces[0].body)
                for (const Vec3& p : f.mesh.xyz) first.extend(p);
        for (RenderOptions* o : {&with_offsets, &plain}) {
            o->sections.planes = {{first.center(), {0, 0, 1}}};
            o->ground = true;
            o->antialias = 0;
        }
        const Camera camera(fit_moved);
        const RenderResult a = render(prepared_before, camera, with_offsets);
        const RenderResult b = render(prepared_moved, camera, plain);
        const size_t n = a.image.face.size();
        size_t same = 0, hits = 0;
        double worst = 0;
        for (size_t k = 0; k < n; ++k) {
            if (a.image.face[k] != b.image.face[k]) continue;
            ++same;
            if (!a.image.face[k]) continue;
            ++hits;
            worst = std::max(worst, std::fabs(double(a.image.z[k]) - double(b.image.z[k])));
        }
        EXPECT_GT(hits, 400u) << "the frame shows the parts";
        EXPECT_GE(double(same), 0.9999 * double(n)) << n - same << " pixels differ";
        EXPECT_LE(worst, 1e-6 * moved.bbox.diagonal());
        EXPECT_EQ(a.stats.cap_pixels, b.stats.cap_pixels);
        EXPECT_GT(a.stats.cap_pixels, 0u);
        EXPECT_EQ(a.stats.shadowed_pixels + a.stats.ground_shadowed_pixels,
                  b.stats.shadowed_pixels + b.stats.ground_shadowed_pixels);
    }
}

TEST(Explode, FactorOutsideTheRangeIsRefused) {
    EXPECT_THROW(checked_explode(-0.1, "x"), Error);
    EXPECT_THROW(checked_explode(10.5, "x"), Error);
    EXPECT_THROW(checked_explode(std::nan(""), "x"), Error);
    EXPECT_EQ(checked_explode(10, "x"), 10);
    EXPECT_EQ(parse_render_options(R"({"explode": 0.3, "explode_level": "leaves"})").explode_level,
              ExplodeLevel::leaves);
    EXPECT_THROW(parse_render_options(R"({"explode": 11})"), Error);
    EXPECT_THROW(parse_render_options(R"({"explode_level": "all"})"), Error);
}

}  // namespace
}  // namespace nurbsrt
