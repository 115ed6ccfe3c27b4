// Exploded views (core/scene/explode.h) on the generated two-bracket assembly:
// each top-level part moves rigidly away from the assembly's centre by the
// factor times its size; control points, map meshes and placements alike.
#include <gtest/gtest.h>

#include <cmath>

#include "core/error.h"
#include "core/scene/explode.h"
#include "importer/importer.h"
#include "options/render_request.h"
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
