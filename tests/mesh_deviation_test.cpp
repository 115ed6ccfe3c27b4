// The mesh deviation of the fidelity report (importer/convert/mesh_deviation.cpp)
// against an independent reference: OCCT's BRepExtrema_DistShapeShape from the
// same points (every vertex and triangle centroid of the export mesh) to the
// trimmed face, which searches the whole face and its boundary. They agree
// within max(1e-7 of the model's diagonal, Precision::Confusion()) on every
// point of the fixtures' faces: planes, cylinders, spheres, a torus, fillets
// and vertex blends, free-form B-spline faces with holes (rational too). (The
// deviation is what it is: BRepMesh asked for 0.002 of the diagonal gives the
// sphere 0.0033 at its centroids; the report says so, this test only checks
// that it is measured right.)
#include <gtest/gtest.h>

#include <BRepAdaptor_Surface.hxx>
#include <BRepBndLib.hxx>
#include <BRepBuilderAPI_MakeVertex.hxx>
#include <BRepExtrema_DistShapeShape.hxx>
#include <BRep_Tool.hxx>
#include <Bnd_Box.hxx>
#include <Poly_Triangulation.hxx>
#include <Precision.hxx>
#include <TopExp.hxx>
#include <TopLoc_Location.hxx>
#include <TopTools_IndexedMapOfShape.hxx>
#include <TopoDS.hxx>

#include <algorithm>
#include <cmath>
#include <string>

#include <nlohmann/json.hpp>

#include "importer/convert/convert_writers.h"
#include "importer/occt_shape.h"
#include "importer/shared_read.h"
#include "tests/support/fixtures.h"

namespace {

double reference(const gp_Pnt& p, const TopoDS_Face& face) {
    BRepExtrema_DistShapeShape d(BRepBuilderAPI_MakeVertex(p).Vertex(), face);
    EXPECT_TRUE(d.IsDone());
    return d.Value();
}

// Compares every `stride`-th point of each face (vertices, then centroids: the
// order face_mesh_deviations gives them) with the reference; prints a line.
void expect_agrees_with_reference(const std::string& model, const std::string& label, int stride) {
    const nurbsrt::occt::OcctModel m = nurbsrt::occt::read_model(model, false);
    nurbsrt::ConvertReport r;
    nurbsrt::occt::mesh_for_export(m.shape, r);  // as the mesh outputs mesh it
    Bnd_Box box;
    BRepBndLib::Add(m.shape, box, Standard_False);
    const double diagonal = std::sqrt(box.SquareExtent());
    const double tolerance = std::max(1e-7 * diagonal, Precision::Confusion());
    double worst = 0, max_ours = 0;
    long long points = 0, beyond_base = 0;
    for (int i = 1; i <= m.faces.Extent(); ++i) {
        const TopoDS_Face& face = TopoDS::Face(m.faces(i));
        // A face's boundary is known only within its edges' and vertices'
        // tolerances (BRepCheck's definition of a valid shape): there the 3D
        // curves the reference measures to and the surface's trim may differ.
        // The fixtures' tolerances are 1e-7; some real files' are 0.5 mm.
        const double face_tolerance = std::max(
            {tolerance, BRep_Tool::MaxTolerance(face, TopAbs_EDGE), BRep_Tool::MaxTolerance(face, TopAbs_VERTEX)});
        long long outside = 0;
        const std::vector<double> ours = nurbsrt::occt::face_mesh_deviations(face, outside);
        TopLoc_Location loc;
        const Handle(Poly_Triangulation) t = BRep_Tool::Triangulation(face, loc);
        if (t.IsNull()) {
            EXPECT_TRUE(ours.empty());  // a face BRepMesh could not mesh (the report counts it)
            continue;
        }
        // The same points in the same order: vertices, then centroids.
        ASSERT_EQ(ours.size(), static_cast<size_t>(t->NbNodes() + t->NbTriangles())) << "face " << i;
        const gp_Trsf placement = loc.Transformation();
        size_t k = 0;
        auto check = [&](const gp_Pnt& p) {
            if (k % static_cast<size_t>(stride) == 0) {
                const double ref = reference(p, face);
                worst = std::max(worst, std::abs(ours[k] - ref));
                if (std::abs(ours[k] - ref) > tolerance) ++beyond_base;
                max_ours = std::max(max_ours, ours[k]);
                EXPECT_NEAR(ours[k], ref, face_tolerance)
                    << label << " face " << i << " (surface type " << BRepAdaptor_Surface(face).GetType() << ") "
                    << (k < static_cast<size_t>(t->NbNodes()) ? "vertex " : "centroid ") << k;
                ++points;
            }
            ++k;
        };
        for (int n = 1; n <= t->NbNodes(); ++n) check(t->Node(n).Transformed(placement));
        for (int j = 1; j <= t->NbTriangles(); ++j) {
            int a, b, c;
            t->Triangle(j).Get(a, b, c);
            check(gp_Pnt((t->Node(a).Transformed(placement).XYZ() + t->Node(b).Transformed(placement).XYZ() +
                          t->Node(c).Transformed(placement).XYZ()) /
                         3));
        }
    }
    std::printf(
        "%s: %lld points, max deviation %.3g mm (%.2g of the diagonal), largest disagreement with "
        "BRepExtrema %.2g mm; %lld points beyond %.2g mm, within their face's edge tolerance\n",
        label.c_str(), points, max_ours, max_ours / diagonal, worst, beyond_base, tolerance);
    EXPECT_GT(max_ours, 0.0);  // a mesh of chords is off every curved face somewhere
}

class MeshDeviation : public ::testing::TestWithParam<const char*> {};

TEST_P(MeshDeviation, AgreesWithBRepExtremaOnEveryPoint) {
    expect_agrees_with_reference(nurbsrt::test::fixture_by_name(GetParam()), GetParam(), 1);
}

// Real parts from other CAD systems: B-spline faces with many trims, seams and
// poles, an IGES solid, an assembly. Every 5th point (the reference takes about
// a millisecond a point; a stride keeps the test short and still covers each face).
TEST(MeshDeviationRealModels, AgreesWithBRepExtrema) {
    NURBSRT_REQUIRE_SHARED_MODELS();
    for (const char* m : {"step/trj8_b1-ec-214.stp", "iges/bearing.iges", "step/as1-oc-214.stp", "iges/heartValve.igs",
                          "step/screw.step"})
        expect_agrees_with_reference(nurbsrt::test::shared_model(m), m, 5);
}

INSTANTIATE_TEST_SUITE_P(Fixtures, MeshDeviation,
                         ::testing::Values("box_with_holes", "sphere", "torus", "filleted_box_blend",
                                           "freeform_bspline", "freeform_rational"),
                         [](const auto& info) { return std::string(info.param); });

}  // namespace

namespace {

// An assembly's part placed twice has its faces, and their one mesh, measured
// once: the report counts the distinct faces and their instances, and its
// statistics are those of the part alone (placements are rigid).
TEST(MeshDeviationReport, MeasuresEachDistinctFaceOnce) {
    const nurbsrt::occt::OcctModel m = nurbsrt::occt::read_model(nurbsrt::test::assembly(), false);
    nurbsrt::ConvertReport r;
    nurbsrt::occt::mesh_for_export(m.shape, r);
    const nlohmann::ordered_json d = nurbsrt::occt::mesh_deviation_json(m.shape, 100.0);
    ASSERT_TRUE(d.is_object());
    EXPECT_EQ(d["distinct_faces"].get<int>(), nurbsrt::test::kAssemblyPartFaces);
    EXPECT_EQ(d["face_instances"].get<int>(), 2 * nurbsrt::test::kAssemblyPartFaces);
    // The points of one instance: every vertex and triangle of the part's faces.
    long long part_points = 0;
    TopTools_IndexedMapOfShape distinct;
    for (int i = 1; i <= m.faces.Extent(); ++i) distinct.Add(m.faces(i).Located(TopLoc_Location()));
    for (int i = 1; i <= distinct.Extent(); ++i) {
        TopLoc_Location loc;
        const Handle(Poly_Triangulation) t = BRep_Tool::Triangulation(TopoDS::Face(distinct(i)), loc);
        ASSERT_FALSE(t.IsNull());
        part_points += t->NbNodes() + t->NbTriangles();
    }
    EXPECT_EQ(d["points"].get<long long>(), part_points);
    // Measuring the first instance alone gives the same statistics.
    const nlohmann::ordered_json one = nurbsrt::occt::mesh_deviation_json(m.faces(1), 100.0);
    EXPECT_LE(one["max"].get<double>(), d["max"].get<double>());
}

// The source's measures are taken once per read: the copies a SharedRead
// serves share them, and a second conversion finds them taken.
TEST(MeshDeviationReport, SourceMeasuredOncePerSharedRead) {
    const std::string in = nurbsrt::test::box_with_holes();
    nurbsrt::SharedRead read(in);
    const nurbsrt::occt::OcctModel a = nurbsrt::occt::read_model(in, true), b = nurbsrt::occt::read_model(in, false);
    EXPECT_EQ(a.measures.get(), b.measures.get());
    EXPECT_FALSE(b.measures->source);
    nurbsrt::convert_file(in, nurbsrt::test::fixture_dir() + "/measured-once.stl");
    ASSERT_TRUE(b.measures->source);
    const nurbsrt::occt::GeometryMeasures* first = b.measures->source.get();
    nurbsrt::convert_file(in, nurbsrt::test::fixture_dir() + "/measured-once.step");
    EXPECT_EQ(b.measures->source.get(), first) << "measured again";
    EXPECT_EQ(first->faces, 8);
    // A lone read measures its own.
    const nurbsrt::occt::OcctModel alone = nurbsrt::occt::read_model(nurbsrt::test::sphere(), false);
    EXPECT_NE(alone.measures.get(), a.measures.get());
}

}  // namespace
