// The fidelity report of convert_file: what it measures is measured again here,
// independently, with OCCT's own readers and BRepGProp on the files as written.
//  * Exact:  STEP -> IGES of a coloured assembly: the report's output volume and
//            area are those of the IGES file read by IGESControl_Reader (1e-9
//            relative), the source's those of the STEP file; the differences
//            are within the exact formats' 1e-6; counts and colours kept.
//  * Lossy:  IGES in faces mode has no solid or shell: the report counts them
//            and turns each change into a warning (what --strict refuses).
//  * Mesh:   the STL's report gives the area of the triangles as written (their
//            float corners, read with RWStl) within float rounding, and the
//            difference from the exact area it states is the one measured here.
#include <gtest/gtest.h>

#include <map>
#include <utility>

#include <BRepGProp.hxx>
#include <GProp_GProps.hxx>
#include <IGESControl_Reader.hxx>
#include <Message_ProgressRange.hxx>
#include <Poly_Triangulation.hxx>
#include <RWStl.hxx>
#include <STEPControl_Reader.hxx>
#include <TopExp_Explorer.hxx>

#include <cmath>
#include <string>

#include <nlohmann/json.hpp>

#include "importer/convert/convert_writers.h"
#include "importer/importer.h"
#include "core/error.h"
#include "tests/support/fixtures.h"

namespace {

using nlohmann::json;

std::string out_path(const std::string& name) { return nurbsrt::test::fixture_dir() + "/fidelity-" + name; }

struct Props {
    double volume = 0, area = 0;
};

Props props_of(const TopoDS_Shape& s) {
    Props p;
    for (TopExp_Explorer ex(s, TopAbs_SOLID); ex.More(); ex.Next()) {
        GProp_GProps v;
        BRepGProp::VolumeProperties(ex.Current(), v);
        p.volume += std::abs(v.Mass());
    }
    GProp_GProps a;
    BRepGProp::SurfaceProperties(s, a);
    p.area = a.Mass();
    return p;
}

template <class Reader>
Props props_of_file(const std::string& path) {
    Reader r;
    EXPECT_EQ(r.ReadFile(path.c_str()), IFSelect_RetDone) << path;
    r.TransferRoots();
    return props_of(r.OneShape());
}

bool mentions(const std::vector<std::string>& warnings, const std::string& s) {
    for (const std::string& w : warnings)
        if (w.find(s) != std::string::npos) return true;
    return false;
}

constexpr double kSameMeasure = 1e-9;  // the same shape measured twice by BRepGProp

TEST(ConvertFidelity, ExactOutputsAreMeasuredAsOcctReadsThem) {
    const std::string in = nurbsrt::test::assembly(), out = out_path("assembly.igs");
    const nurbsrt::ConvertReport r = nurbsrt::convert_file(in, out);
    ASSERT_FALSE(r.fidelity.empty());
    const json f = json::parse(r.fidelity);
    const json &src = f["source"]["geometry"], &dst = f["output"]["geometry"];
    const Props a = props_of_file<STEPControl_Reader>(in), b = props_of_file<IGESControl_Reader>(out);
    ASSERT_GT(a.volume, 0);
    EXPECT_NEAR(src["volume"].get<double>(), a.volume, kSameMeasure * a.volume);
    EXPECT_NEAR(src["area"].get<double>(), a.area, kSameMeasure * a.area);
    EXPECT_NEAR(dst["volume"].get<double>(), b.volume, kSameMeasure * b.volume);
    EXPECT_NEAR(dst["area"].get<double>(), b.area, kSameMeasure * b.area);
    EXPECT_NEAR(f["relative_differences"]["volume"].get<double>(), std::abs(a.volume - b.volume) / a.volume, 1e-12);
    EXPECT_LT(f["relative_differences"]["volume"].get<double>(), 1e-6);
    EXPECT_LT(f["relative_differences"]["area"].get<double>(), 1e-6);
    EXPECT_LT(f["relative_differences"]["box"].get<double>(), 1e-6);
    EXPECT_EQ(src["solids"], 2);
    EXPECT_EQ(dst["solids"], 2);
    EXPECT_EQ(src["faces"], dst["faces"]);
    EXPECT_EQ(src["edges"], dst["edges"]);
    EXPECT_TRUE(src["valid"].get<bool>());
    EXPECT_TRUE(dst["valid"].get<bool>());
    EXPECT_EQ(f["attributes"]["colours"]["faces_losing_colour"], 0);
    EXPECT_EQ(f["attributes"]["assembly"]["source"]["instances"], 2);
    EXPECT_EQ(f["source"]["units"], "mm");
    EXPECT_EQ(f["output"]["units"], "mm");
}

TEST(ConvertFidelity, WhatChangesIsCountedAndWarned) {
    nurbsrt::ConvertOptions faces;
    faces.iges_mode = nurbsrt::IgesMode::faces;
    const nurbsrt::ConvertReport r =
        nurbsrt::convert_file(nurbsrt::test::box_with_holes(), out_path("faces.igs"), faces);
    const json f = json::parse(r.fidelity);
    EXPECT_EQ(f["source"]["geometry"]["solids"], 1);
    EXPECT_EQ(f["output"]["geometry"]["solids"], 0);
    EXPECT_EQ(f["output"]["geometry"]["shells"], 0);
    EXPECT_TRUE(mentions(r.warnings, "the output holds 0 solid(s), the source 1"));
    EXPECT_TRUE(mentions(r.warnings, "the output holds 0 shell(s), the source 1"));
    // The faces' geometry itself is unchanged.
    EXPECT_LT(f["relative_differences"]["area"].get<double>(), 1e-6);
}

// Each threshold that turns a fidelity difference into a warning, with a
// fixture that crosses it. Mesh: a coarse deflection (0.1 of the diagonal)
// puts the free-form face's mesh 0.02 of the diagonal from it, and cuts 6.6%
// of the fan's volume (measured); the default deflection keeps both within
// their tolerances.
TEST(ConvertFidelity, CoarseMeshIsWarned) {
    nurbsrt::ConvertOptions coarse;
    coarse.deflection = nurbsrt::kMaxConversionDeflection;
    const std::string freeform = nurbsrt::test::freeform_bspline(), fan = nurbsrt::test::blade_fan();
    const nurbsrt::ConvertReport far = nurbsrt::convert_file(freeform, out_path("coarse.stl"), coarse);
    const json f = json::parse(far.fidelity);
    EXPECT_GT(f["output"]["deviation_in_mm"]["relative_to_diagonal"]["max"].get<double>(), 0.01);
    EXPECT_TRUE(mentions(far.warnings, "the STL mesh lies up to ")) << far.warnings.size();
    const nurbsrt::ConvertReport cut = nurbsrt::convert_file(fan, out_path("coarse.glb"), coarse);
    const json g = json::parse(cut.fidelity);
    EXPECT_GT(g["relative_differences"]["volume"].get<double>(), 0.05);
    EXPECT_EQ(g["relative_differences"]["tolerance"].get<double>(), 0.05);
    EXPECT_TRUE(mentions(cut.warnings, "the GLB mesh's volume differs from the exact faces' by"));
    for (const std::string& in : {freeform, fan}) {
        const nurbsrt::ConvertReport fine = nurbsrt::convert_file(in, out_path("fine.stl"));
        EXPECT_TRUE(fine.warnings.empty()) << in << ": " << fine.warnings.front();
    }
    // deflection is a mesh option: refused for an exact output, and out of range.
    EXPECT_THROW(nurbsrt::convert_file(fan, out_path("coarse.step"), coarse), nurbsrt::Error);
    coarse.deflection = 0.5;
    EXPECT_THROW(nurbsrt::convert_file(fan, out_path("too-coarse.stl"), coarse), nurbsrt::Error);
    // So is angular_deflection, in [kMinAngularDeflection, kMaxAngularDeflection].
    nurbsrt::ConvertOptions angle;
    angle.angular_deflection = 0.2;
    EXPECT_THROW(nurbsrt::convert_file(fan, out_path("angle.step"), angle), nurbsrt::Error);
    angle.angular_deflection = nurbsrt::kMaxAngularDeflection * 1.01;
    EXPECT_THROW(nurbsrt::convert_file(fan, out_path("angle.stl"), angle), nurbsrt::Error);
}

// The report states what was asked of BRepMesh beside what it achieved: the
// default angle, and a finer one, which BRepMesh follows with more triangles.
TEST(ConvertFidelity, MeshReportStatesTheDeflectionsAsked) {
    const std::string freeform = nurbsrt::test::freeform_bspline();
    nurbsrt::ConvertOptions fine;
    fine.angular_deflection = 0.05;
    const nurbsrt::ConvertReport a = nurbsrt::convert_file(freeform, out_path("angle-default.stl"));
    const nurbsrt::ConvertReport b = nurbsrt::convert_file(freeform, out_path("angle-fine.stl"), fine);
    const json fa = json::parse(a.fidelity)["output"], fb = json::parse(b.fidelity)["output"];
    EXPECT_EQ(fa["asked"]["angular_deflection"].get<double>(), nurbsrt::kDefaultAngularDeflection);
    EXPECT_EQ(fb["asked"]["angular_deflection"].get<double>(), 0.05);
    EXPECT_EQ(fa["asked"]["deflection"].get<double>(), nurbsrt::ImportOptions{}.mesh_relative_deflection);
    EXPECT_GT(fa["asked"]["deflection_mm"].get<double>(), 0);
    EXPECT_LT(a.triangles, b.triangles);
    EXPECT_GT(fb["deviation_in_mm"]["points"].get<double>(), fa["deviation_in_mm"]["points"].get<double>());
}

// Exact outputs: a volume or area moved past 1e-6 relative, and a valid
// source written invalid, measured on generated measures (no OCCT writer
// loses these on a sound file).
TEST(ConvertFidelity, ExactDifferencesAndValidityLostAreWarned) {
    nurbsrt::occt::GeometryMeasures in;
    in.solids = in.shells = 1;
    in.faces = 6;
    in.edges = 12;
    in.volume = 1000;
    in.area = 600;
    in.box = {0, 0, 0, 10, 10, 10};
    std::vector<std::string> none;
    nurbsrt::occt::compare_geometry(in, in, none);
    EXPECT_TRUE(none.empty());
    nurbsrt::occt::GeometryMeasures out = in;
    out.volume *= 1 + 1e-5;
    out.area *= 1 + 1e-5;
    out.valid = false;
    std::vector<std::string> w;
    const json d = nurbsrt::occt::compare_geometry(in, out, w);
    EXPECT_NEAR(d["volume"].get<double>(), 1e-5, 1e-9);
    EXPECT_TRUE(mentions(w, "the output's volume differs from the source's by"));
    EXPECT_TRUE(mentions(w, "the output's area differs from the source's by"));
    EXPECT_TRUE(mentions(w, "the output is not a valid shape (BRepCheck_Analyzer); the source is"));
    // Within the exact formats' tolerance: no warning.
    out = in;
    out.volume *= 1 + 1e-7;
    std::vector<std::string> within;
    nurbsrt::occt::compare_geometry(in, out, within);
    EXPECT_TRUE(within.empty());
}

TEST(ConvertFidelity, MeshAreaIsTheWrittenTrianglesArea) {
    const std::string in = nurbsrt::test::filleted_box(), out = out_path("filleted.stl");
    const nurbsrt::ConvertReport r = nurbsrt::convert_file(in, out);
    const json f = json::parse(r.fidelity);
    const Handle(Poly_Triangulation) t = RWStl::ReadFile(out.c_str(), Message_ProgressRange());
    ASSERT_FALSE(t.IsNull());
    double area = 0;
    for (int k = 1; k <= t->NbTriangles(); ++k) {
        int a, b, c;
        t->Triangle(k).Get(a, b, c);
        area += gp_Vec(t->Node(a), t->Node(b)).Crossed(gp_Vec(t->Node(a), t->Node(c))).Magnitude() / 2;
    }
    const json& mesh = f["output"]["mesh_in_mm"];
    EXPECT_EQ(mesh["triangles"].get<long long>(), r.triangles);
    // float32 corners: a relative rounding of about 1e-7 per coordinate.
    EXPECT_NEAR(mesh["area"].get<double>(), area, 1e-5 * area);
    const double exact = f["source"]["geometry"]["area"].get<double>();
    EXPECT_NEAR(f["relative_differences"]["area"].get<double>(), std::abs(exact - area) / exact, 1e-5);
    // A mesh of chords lies inside the convex fillets: less area, and less than 1 %.
    EXPECT_LT(area, exact);
    EXPECT_LT(f["relative_differences"]["area"].get<double>(), 0.01);
    EXPECT_TRUE(mesh.contains("volume"));
}

// The edge counts and the volume's centroid of a mesh output, against the
// written STL as OCCT's reader joins it (RWStl merges equal nodes).
double box_extent_squared(const json& box) {
    double sq = 0;
    for (int i = 0; i < 3; ++i) sq += std::pow(box["max"][i].get<double>() - box["min"][i].get<double>(), 2);
    return sq;
}

struct StlEdges {
    long long open = 0, non_manifold = 0;
    gp_XYZ centroid;
};

StlEdges edges_of_stl(const std::string& path) {
    const Handle(Poly_Triangulation) t = RWStl::ReadFile(path.c_str(), Message_ProgressRange());
    EXPECT_FALSE(t.IsNull());
    std::map<std::pair<int, int>, int> uses;
    gp_XYZ moment(0, 0, 0);
    double volume = 0;
    for (int k = 1; k <= t->NbTriangles(); ++k) {
        int n[3];
        t->Triangle(k).Get(n[0], n[1], n[2]);
        for (int i = 0; i < 3; ++i) ++uses[std::minmax(n[i], n[(i + 1) % 3])];
        const gp_XYZ a = t->Node(n[0]).XYZ(), b = t->Node(n[1]).XYZ(), c = t->Node(n[2]).XYZ();
        const double v = a.Dot(b.Crossed(c)) / 6;
        volume += v;
        moment += v * (a + b + c) / 4;
    }
    StlEdges e;
    for (const auto& [edge, n] : uses) {
        e.open += n == 1;
        e.non_manifold += n > 2;
    }
    e.centroid = moment / volume;
    return e;
}

TEST(ConvertFidelity, MeshEdgesAndVolumeCentroidAreMeasured) {
    // A closed solid: no open or non-manifold edge, and its mesh's volume
    // centroid near the exact one (BRepGProp), as the STL's own is.
    const std::string in = nurbsrt::test::filleted_box(), out = out_path("filleted-edges.stl");
    const json f = json::parse(nurbsrt::convert_file(in, out).fidelity);
    const json& mesh = f["output"]["mesh_in_mm"];
    const StlEdges stl = edges_of_stl(out);
    EXPECT_EQ(stl.open, 0);
    EXPECT_EQ(mesh["open_edges"].get<long long>(), stl.open);
    EXPECT_EQ(mesh["non_manifold_edges"].get<long long>(), stl.non_manifold);
    EXPECT_EQ(mesh["non_manifold_triangles"].get<long long>(), 0);
    const json& exact = f["source"]["geometry"]["volume_centroid"];
    ASSERT_TRUE(exact.is_array());
    const double diag = std::sqrt(box_extent_squared(f["source"]["geometry"]["box"]));
    double moved = 0;
    for (int i = 0; i < 3; ++i) {
        // float32 corners: the STL's centroid agrees with ours to about 1e-6 of the diagonal.
        EXPECT_NEAR(mesh["volume_centroid"][i].get<double>(), stl.centroid.Coord(i + 1), 1e-6 * diag);
        moved += std::pow(mesh["volume_centroid"][i].get<double>() - exact[i].get<double>(), 2);
    }
    EXPECT_NEAR(f["relative_differences"]["volume_centroid"].get<double>(), std::sqrt(moved) / diag, 1e-12);
    EXPECT_LT(f["relative_differences"]["volume_centroid"].get<double>(), 1e-3);
    // An open B-spline sheet: its rim is open, as the STL's.
    const std::string sheet = out_path("sheet-edges.stl");
    const json g =
        json::parse(nurbsrt::convert_file(nurbsrt::test::fixture_by_name("freeform_bspline"), sheet).fidelity);
    EXPECT_GT(edges_of_stl(sheet).open, 0);
    EXPECT_EQ(g["output"]["mesh_in_mm"]["open_edges"].get<long long>(), edges_of_stl(sheet).open);
}

}  // namespace
