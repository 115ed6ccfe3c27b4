// The OCCT peers of `nurbsrt bench` behind their OCCT-free headers: the exact
// ray caster (importer/reference/reference_intersector.h, also the accuracy test's oracle)
// and the BRepMesh tessellation (importer/faces/tessellate.h), on the sphere fixture
// (radius 15 at the origin), alone and placed twice.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "importer/reference/reference_intersector.h"
#include "importer/faces/tessellate.h"
#include "core/error.h"
#include "tests/support/fixtures.h"

namespace nurbsrt {
namespace {

namespace T = nurbsrt::test;
constexpr double kR = 15.0;

Ray down_from(double x, double y) { return Ray{{x, y, 100.0}, {0, 0, -1}}; }

TEST(ReferenceIntersector, NearestHitOfASphere) {
    ReferenceIntersector ref(T::sphere());
    EXPECT_EQ(ref.faces(), 1);
    const ReferenceHit h = ref.cast(down_from(0, 0), 1000);
    ASSERT_TRUE(h.hit);
    EXPECT_FALSE(h.error);
    EXPECT_NEAR(h.t, 100.0 - kR, 1e-6);  // the near side, not the far one at 115
    EXPECT_EQ(h.face, 1);
    // Off-centre: t = 100 - sqrt(R^2 - x^2 - y^2).
    const ReferenceHit o = ref.cast(down_from(9, -5), 1000);
    ASSERT_TRUE(o.hit);
    EXPECT_NEAR(o.t, 100.0 - std::sqrt(kR * kR - 81 - 25), 1e-6);
    EXPECT_FALSE(ref.cast(down_from(16, 0), 1000).hit);
    EXPECT_FALSE(ref.cast(down_from(0, 0), 50).hit) << "t_max must cut the ray";
}

TEST(ReferenceIntersector, PlacedCopiesAreNumberedCopyAfterCopy) {
    ReferenceIntersector ref(T::sphere(), {Affine{}, Affine::translation({100, 0, 0})});
    EXPECT_EQ(ref.faces(), 2);
    const ReferenceHit a = ref.cast(down_from(0, 0), 1000), b = ref.cast(down_from(100, 3), 1000);
    ASSERT_TRUE(a.hit);
    ASSERT_TRUE(b.hit);
    EXPECT_EQ(a.face, 1);
    EXPECT_EQ(b.face, 2);
    EXPECT_NEAR(b.t, 100.0 - std::sqrt(kR * kR - 9), 1e-6);
    EXPECT_FALSE(ref.cast(down_from(50, 0), 1000).hit);
}

TEST(ReferenceIntersector, RejectsAPlacementOcctCannotHold) {
    Affine shear;
    shear.m[1] = 0.5;  // x' = x + 0.5 y
    EXPECT_THROW(ReferenceIntersector(T::sphere(), {shear}), Error);
    EXPECT_THROW(ReferenceIntersector(T::sphere(), {Affine::scaling(2)}), Error);
    EXPECT_NO_THROW(ReferenceIntersector(T::sphere(), {Affine::rotation_xyz_deg({0, 0, 90})}));
}

TEST(Tessellator, MeshLiesOnTheSphereWithinTheDeflection) {
    Tessellator tess(T::sphere());
    const Tessellation coarse = tess.mesh(0.5, 0.5, false);
    const Tessellation fine = tess.mesh(0.01, 0.5, false);
    ASSERT_GT(coarse.mesh.triangle_count(), 0u);
    EXPECT_GT(fine.mesh.triangle_count(), 2 * coarse.mesh.triangle_count()) << "finer deflection, more triangles";
    EXPECT_EQ(fine.faces_without_triangles, 0);
    double max_sag[2] = {0, 0};
    for (int k = 0; k < 2; ++k) {
        const Tessellation& t = k == 0 ? coarse : fine;
        const double defl = k == 0 ? 0.5 : 0.01;
        for (const Vec3& p : t.mesh.xyz) EXPECT_NEAR(length(p), kR, 1e-6);  // nodes on the surface
        for (size_t i = 0; i + 2 < t.mesh.triangles.size(); i += 3) {
            const Vec3 c = (t.mesh.xyz[t.mesh.triangles[i]] + t.mesh.xyz[t.mesh.triangles[i + 1]] +
                            t.mesh.xyz[t.mesh.triangles[i + 2]]) /
                           3.0;
            max_sag[k] = std::max(max_sag[k], kR - length(c));
        }
        // BRepMesh bounds the sag of its edges and checks faces at sample points;
        // a triangle's centroid sags up to ~4/3 of its edges' sag: allow 2x.
        EXPECT_LE(max_sag[k], 2.0 * defl) << "deflection " << defl;
    }
    EXPECT_LT(max_sag[1], 0.1 * max_sag[0]) << "a 50x finer deflection must shrink the error";
}

TEST(Tessellator, PlacementsCopyTheMesh) {
    Tessellator one(T::sphere());
    Tessellator two(T::sphere(), {Affine{}, Affine::translation({100, 0, 0})});
    const Tessellation a = one.mesh(0.1, 0.5, false), b = two.mesh(0.1, 0.5, false);
    ASSERT_EQ(b.mesh.triangle_count(), 2 * a.mesh.triangle_count());
    ASSERT_EQ(b.mesh.xyz.size(), 2 * a.mesh.xyz.size());
    const size_t n = a.mesh.xyz.size();
    for (size_t k = 0; k < n; ++k) {
        EXPECT_NEAR(b.mesh.xyz[n + k].x, a.mesh.xyz[k].x + 100, 1e-9);
        EXPECT_NEAR(b.mesh.xyz[n + k].y, a.mesh.xyz[k].y, 1e-9);
    }
    EXPECT_EQ(b.mesh.triangles[a.mesh.triangles.size()], a.mesh.triangles[0] + n);
}

}  // namespace
}  // namespace nurbsrt
