// The map from an analytic face's own (u,v) to those of its surface converted
// alone by GeomConvert (importer/uv_map.h), checked against OCCT's evaluation
// of both surfaces: the mapped parameters give the same point, the map inverts,
// it is not the identity where a circle is involved (else the test would prove
// nothing), and a pair of surfaces that do not correspond gets no map.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include <BRepBuilderAPI_MakeFace.hxx>
#include <BRepPrimAPI_MakeCylinder.hxx>
#include <BRepPrimAPI_MakeSphere.hxx>
#include <GeomConvert.hxx>
#include <Geom_ConicalSurface.hxx>
#include <Geom_CylindricalSurface.hxx>
#include <Geom_Plane.hxx>
#include <Geom_RectangularTrimmedSurface.hxx>
#include <Geom_SphericalSurface.hxx>
#include <Geom_ToroidalSurface.hxx>
#include <TopExp_Explorer.hxx>
#include <TopoDS.hxx>
#include <gp_Ax3.hxx>

#include "importer/occt_shape.h"
#include "importer/uv_map.h"

namespace {

using nurbsrt::Vec2;
using nurbsrt::occt::UVMap;

struct Case {
    const char* name;
    Handle(Geom_Surface) surface;
    double u0, u1, v0, v1;
    bool circular;  // a direction is a circle: the map differs from the identity
};

Handle(Geom_BSplineSurface) converted(const Case& c) {
    return GeomConvert::SurfaceToBSplineSurface(new Geom_RectangularTrimmedSurface(c.surface, c.u0, c.u1, c.v0, c.v1));
}

std::vector<Case> cases() {
    // Off the origin and tilted, so that rounding relative to coordinates shows.
    const gp_Ax3 frame(gp_Pnt(120, -40, 75), gp_Dir(0.3, 0.4, 0.866) /*axis*/, gp_Dir(1, 0, -0.3464));
    const double pi = M_PI;
    return {
        {"plane", new Geom_Plane(frame), -3, 7, -2, 5, false},
        {"cylinder quarter", new Geom_CylindricalSurface(frame, 4), 0.3, 0.3 + pi / 2, -1, 6, true},
        {"cylinder half, negative angles", new Geom_CylindricalSurface(frame, 4), -pi / 4, 3 * pi / 4, 0, 2, true},
        {"cylinder whole", new Geom_CylindricalSurface(frame, 4), 0, 2 * pi, -5, 5, true},
        {"cylinder whole, one period on", new Geom_CylindricalSurface(frame, 4), pi, 3 * pi, 0, 13, true},
        {"cone", new Geom_ConicalSurface(frame, 0.4, 2), 0.1, 5.9, 0.5, 6, true},
        {"sphere pole to pole", new Geom_SphericalSurface(frame, 3), 0, 2 * pi, -pi / 2, pi / 2, true},
        {"sphere band", new Geom_SphericalSurface(frame, 3), 1, 2.5, -1.2, 0.4, true},
        {"torus", new Geom_ToroidalSurface(frame, 10, 2), 0.5, 4, pi / 2, 3 * pi / 2, true},
        {"torus whole", new Geom_ToroidalSurface(frame, 10, 2), 0, 2 * pi, 0, 2 * pi, true},
    };
}

TEST(UVMap, MappedParametersGiveTheSamePointAndInvert) {
    for (const Case& c : cases()) {
        SCOPED_TRACE(c.name);
        const Handle(Geom_BSplineSurface) bs = converted(c);
        ASSERT_FALSE(bs.IsNull());
        const std::optional<UVMap> map = UVMap::between(c.surface, bs, c.u0, c.u1, c.v0, c.v1);
        ASSERT_TRUE(map.has_value());
        double s0, s1, t0, t1;
        bs->Bounds(s0, s1, t0, t1);
        // Size of the face: the points are compared to 1e-12 of it (rounding
        // of the rational evaluation, with coordinates ~100x the size).
        const double size = c.surface->Value(c.u0, c.v0).Distance(c.surface->Value(c.u1, c.v1)) + 10;
        std::mt19937_64 rng(7);
        std::uniform_real_distribution<double> U(c.u0, c.u1), V(c.v0, c.v1);
        double worst_point = 0, worst_round_trip = 0, largest_change = 0;
        for (int k = 0; k < 2000; ++k) {
            const Vec2 f{U(rng), V(rng)};
            const Vec2 s = map->to_surface(f);
            EXPECT_GE(s.x, s0 - 1e-9);
            EXPECT_LE(s.x, s1 + 1e-9);
            EXPECT_GE(s.y, t0 - 1e-9);
            EXPECT_LE(s.y, t1 + 1e-9);
            worst_point = std::max(worst_point, bs->Value(s.x, s.y).Distance(c.surface->Value(f.x, f.y)));
            const Vec2 back = map->to_face(s);
            worst_round_trip = std::max({worst_round_trip, std::fabs(back.x - f.x), std::fabs(back.y - f.y)});
            // Against the linear map between the boxes: what a plain rescaling would get wrong.
            const double lin_u = s0 + (f.x - c.u0) * (s1 - s0) / (c.u1 - c.u0);
            const double lin_v = t0 + (f.y - c.v0) * (t1 - t0) / (c.v1 - c.v0);
            largest_change = std::max({largest_change, std::fabs(s.x - lin_u), std::fabs(s.y - lin_v)});
        }
        EXPECT_LE(worst_point, 1e-12 * size * 100);
        EXPECT_LE(worst_round_trip, 1e-12);
        if (c.circular)
            EXPECT_GT(largest_change, 1e-3) << "a circle's rational parameter is not its angle";
        else
            EXPECT_LE(largest_change, 1e-12);
        // Points just outside the box (pcurves stray by their tolerance) map onto the surface too.
        const Vec2 out = map->to_surface({c.u1 + 1e-7, c.v0 - 1e-7});
        EXPECT_LE(bs->Value(out.x, out.y).Distance(c.surface->Value(c.u1 + 1e-7, c.v0 - 1e-7)), 1e-9 * size);
    }
}

TEST(UVMap, SurfacesThatDoNotCorrespondGetNoMap) {
    const std::vector<Case> all = cases();
    const Case& cyl = all[1];
    // The conversion of another box: the ends do not correspond.
    Case other = cyl;
    other.u1 += 0.5;
    EXPECT_FALSE(UVMap::between(cyl.surface, converted(other), cyl.u0, cyl.u1, cyl.v0, cyl.v1).has_value());
    // Another surface altogether (a sphere's conversion for a cylinder).
    const Case& sphere = all[7];
    EXPECT_FALSE(UVMap::between(cyl.surface, converted(sphere), cyl.u0, cyl.u1, cyl.v0, cyl.v1).has_value());
    // An empty box.
    EXPECT_FALSE(UVMap::between(cyl.surface, converted(cyl), cyl.u0, cyl.u0, cyl.v0, cyl.v1).has_value());
}

// convert_face takes the fast path for analytic faces: their map is not the
// identity, the face keeps its own pcurves, and the box maps inside the
// surface's range.
TEST(UVMap, ConvertFaceConvertsAnalyticSurfacesAlone) {
    for (const TopoDS_Shape& shape : {BRepPrimAPI_MakeCylinder(gp_Ax2(gp_Pnt(5, 6, 7), gp_Dir(0, 1, 1)), 3, 8).Shape(),
                                      BRepPrimAPI_MakeSphere(gp_Pnt(-4, 2, 9), 5).Shape()}) {
        int mapped = 0, faces = 0;
        for (TopExp_Explorer ex(shape, TopAbs_FACE); ex.More(); ex.Next(), ++faces) {
            const nurbsrt::occt::ConvertedFace cf = nurbsrt::occt::convert_face(TopoDS::Face(ex.Current()));
            ASSERT_FALSE(cf.surface.IsNull());
            if (!cf.map.identity()) ++mapped;
        }
        // Every curved face (the cylinder's side, the sphere) goes the fast way;
        // planes too (their map is affine).
        EXPECT_EQ(mapped, faces);
    }
    // A closed face whose box exceeds the period by rounding (as written by
    // some CAD systems): Convert_CylinderToBSplineSurface refuses that box, so
    // it is cut to one period, and the face still takes the fast path.
    const double start = -4.8316906031686813e-13;
    const TopoDS_Face closed = BRepBuilderAPI_MakeFace(new Geom_CylindricalSurface(gp_Ax3(gp::XOY()), 2.5), start,
                                                       start + 2 * M_PI + 9e-13, -1, 4, 1e-7);
    const nurbsrt::occt::ConvertedFace cf = nurbsrt::occt::convert_face(closed);
    ASSERT_FALSE(cf.surface.IsNull());
    EXPECT_FALSE(cf.map.identity());
    const Vec2 s = cf.map.to_surface({1.0, 2.0});
    EXPECT_LE(cf.surface->Value(s.x, s.y).Distance(gp_Pnt(2.5 * std::cos(1.0), 2.5 * std::sin(1.0), 2.0)), 1e-12);
}

}  // namespace
