// Placing and concatenating scenes (core/scene/scene_ops.h): a moved copy must be
// exactly the moved surface, and concatenation must keep the face-index contract.
#include <gtest/gtest.h>

#include <random>

#include "core/scene/nurbs.h"
#include "core/scene/scene_ops.h"
#include "tests/renderer_test_surfaces.h"

namespace {

using namespace nurbsrt;

Scene one_face_scene(const NurbsSurface& s) {
    Scene scene;
    Face f;
    f.index = 1;
    f.surface = s;
    f.u_min = s.u_begin();
    f.u_max = s.u_end();
    f.v_min = s.v_begin();
    f.v_max = s.v_end();
    f.mesh.uv = {{f.u_min, f.v_min}, {f.u_max, f.v_min}, {f.u_min, f.v_max}};
    for (const Vec2& uv : f.mesh.uv) f.mesh.xyz.push_back(project(evaluate(s, uv.x, uv.y)));
    f.mesh.triangles = {0, 1, 2};
    for (const Vec3& p : f.mesh.xyz) scene.bbox.extend(p);
    scene.faces.push_back(f);
    scene.bodies.push_back({"body", false, {}});
    scene.source_name = "a.step";
    scene.format = "STEP";
    return scene;
}

TEST(SceneOps, AffineComposesAndMirrors) {
    const Affine r = Affine::rotation_xyz_deg({0, 0, 90});
    const Vec3 p = r.apply({1, 0, 0});
    EXPECT_NEAR(p.x, 0, 1e-15);
    EXPECT_NEAR(p.y, 1, 1e-15);
    const Affine m = Affine::translation({1, 2, 3}) * Affine::scaling(2);
    const Vec3 q = m.apply({1, 1, 1});
    EXPECT_DOUBLE_EQ(q.x, 3);
    EXPECT_DOUBLE_EQ(q.z, 5);
    EXPECT_NEAR(r.determinant(), 1, 1e-15);
    Affine mirror;
    mirror.m[0] = -1;
    EXPECT_LT(mirror.determinant(), 0);
}

// A rational surface moved through its homogeneous control points equals the
// moved points of the original surface (affine maps commute with the rational form).
TEST(SceneOps, TransformMovesRationalSurfaceExactly) {
    const nurbsrt::testing::AnalyticPatch sphere = nurbsrt::testing::sphere_patch();
    Scene scene = one_face_scene(sphere.surface);
    const Affine xf = Affine::translation({10, -3, 7}) * Affine::rotation_xyz_deg({30, 45, 60}) * Affine::scaling(2.5);
    transform_scene(scene, xf);
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> d(0, 1);
    for (int k = 0; k < 200; ++k) {
        const double u = sphere.surface.u_begin() + d(rng) * (sphere.surface.u_end() - sphere.surface.u_begin());
        const double v = sphere.surface.v_begin() + d(rng) * (sphere.surface.v_end() - sphere.surface.v_begin());
        const Vec3 want = xf.apply(project(evaluate(sphere.surface, u, v)));
        const Vec3 got = project(evaluate(scene.faces[0].surface, u, v));
        EXPECT_NEAR(length(want - got), 0, 1e-13);
    }
    EXPECT_FALSE(scene.faces[0].reversed);
    Affine mirror;
    mirror.m[0] = -1;
    transform_scene(scene, mirror);
    EXPECT_TRUE(scene.faces[0].reversed) << "a mirror must flip the orientation";
    for (const Vec3& p : scene.faces[0].mesh.xyz) {
        EXPECT_LE(scene.bbox.lo.x, p.x);
        EXPECT_GE(scene.bbox.hi.x, p.x);
    }
}

TEST(SceneOps, AppendRenumbersFacesAndBodies) {
    const nurbsrt::testing::AnalyticPatch plane = nurbsrt::testing::plane_patch();
    Scene a = one_face_scene(plane.surface), b = one_face_scene(plane.surface);
    b.warnings.push_back("something");
    transform_scene(b, Affine::translation({100, 0, 0}));
    Scene all;
    append_scene(all, a);
    append_scene(all, b);
    ASSERT_EQ(all.faces.size(), 2u);
    EXPECT_EQ(all.faces[0].index, 1u);
    EXPECT_EQ(all.faces[1].index, 2u);
    EXPECT_EQ(all.faces[1].body, 1u);
    EXPECT_EQ(all.bodies.size(), 2u);
    EXPECT_GE(all.bbox.hi.x, 100.0);
    ASSERT_EQ(all.warnings.size(), 1u);
    EXPECT_EQ(all.warnings[0], "a.step: something");
    EXPECT_EQ(all.format, "STEP");
}

}  // namespace
