// convert_file to the mesh and JSON outputs, checked against independent readers.
//
// What is checked, and against what:
//  * Names:    extension/name -> ConversionFormat, content types, file extensions.
//  * Stl:      the binary STL re-read by OCCT's RWStl has the reported triangle count, its
//              size is 84 + 50 n bytes, and its node box matches the exact (geometric, not
//              mesh) box of the model within the mesh deflection; no triangle of its float
//              corners has no area, none is there twice; the sphere's pole triangles
//              (BRepMesh gives the pole one node per triangle there) are counted as left out.
//  * Glb:      RWGltf_CafReader reads the glb back; with the documented conversion undone
//              (SetSystemLengthUnit(0.001), Zup) its mesh box matches the model's within the
//              deflection; read without conversion it is the model box mapped to glTF's
//              Y-up metres ((x, y, z) mm -> (x, z, -y) / 1000). The assembly keeps its
//              instances (named nodes with their converted translations) and its colour.
//  * Json:     the dump parses, has one patch per face, and a patch rebuilt from its JSON
//              knots/control points evaluates (core/scene/nurbs.h) bit-identically to the
//              imported Scene's patch; non-finite numbers become null, never invalid JSON.
//  * Isolated: convert_isolated carries the new report fields back from the worker.
#include <gtest/gtest.h>

#include <BRepBndLib.hxx>
#include <BRepMesh_IncrementalMesh.hxx>
#include <IMeshTools_Parameters.hxx>
#include <BRep_Tool.hxx>
#include <Bnd_Box.hxx>
#include <Message_ProgressRange.hxx>
#include <Poly_Triangulation.hxx>
#include <RWGltf_CafReader.hxx>
#include <RWMesh_CoordinateSystem.hxx>
#include <RWStl.hxx>
#include <TDocStd_Document.hxx>
#include <TopExp.hxx>
#include <TopLoc_Location.hxx>
#include <TopTools_IndexedMapOfShape.hxx>
#include <TopoDS.hxx>
#include <XCAFApp_Application.hxx>
#include <gp_Vec.hxx>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <string>

#include <nlohmann/json.hpp>

#include "importer/importer.h"
#include "importer/isolated.h"
#include "importer/occt_shape.h"
#include "options/render_request.h"
#include "core/error.h"
#include "core/scene/nurbs.h"
#include "core/io/scene_json.h"
#include "tests/support/fixtures.h"

namespace {

using nlohmann::json;
using nurbsrt::ConversionFormat;

std::string out_path(const std::string& fixture, const std::string& ext) {
    return nurbsrt::test::fixture_dir() + "/convert-" + fixture + ext;
}

std::string read_bytes(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    std::ostringstream ss;
    ss << in.rdbuf();
    return ss.str();
}

struct Box3 {
    double lo[3], hi[3];
    double diagonal() const {
        return std::sqrt((hi[0] - lo[0]) * (hi[0] - lo[0]) + (hi[1] - lo[1]) * (hi[1] - lo[1]) +
                         (hi[2] - lo[2]) * (hi[2] - lo[2]));
    }
};

Box3 to_box(const Bnd_Box& b) {
    Box3 r{};
    b.Get(r.lo[0], r.lo[1], r.lo[2], r.hi[0], r.hi[1], r.hi[2]);
    return r;
}

// The model's exact box: faces only, from their geometry (not a mesh), without
// the shape tolerance (which would inflate it by up to the edge tolerances).
Box3 exact_box(const std::string& path) {
    const nurbsrt::occt::OcctModel m = nurbsrt::occt::read_model(path, false);
    Bnd_Box b;
    for (int i = 1; i <= m.faces.Extent(); ++i)
        BRepBndLib::AddOptimal(m.faces(i), b, /*useTriangulation=*/Standard_False,
                               /*useShapeTolerance=*/Standard_False);
    return to_box(b);
}

// The deflection convert_file meshes with (ImportOptions' default, relative to the diagonal).
double deflection_of(const Box3& b) { return nurbsrt::ImportOptions{}.mesh_relative_deflection * b.diagonal(); }

void expect_box_near(const Box3& got, const Box3& want, double tol, const std::string& what) {
    for (int k = 0; k < 3; ++k) {
        EXPECT_NEAR(got.lo[k], want.lo[k], tol) << what << " min axis " << k;
        EXPECT_NEAR(got.hi[k], want.hi[k], tol) << what << " max axis " << k;
    }
}

// Node box of every triangulation in `shape` (locations applied), and the triangle count.
Box3 mesh_box(const TopoDS_Shape& shape, long long& triangles) {
    TopTools_IndexedMapOfShape faces;
    TopExp::MapShapes(shape, TopAbs_FACE, faces);
    Bnd_Box b;
    triangles = 0;
    for (int i = 1; i <= faces.Extent(); ++i) {
        TopLoc_Location loc;
        const Handle(Poly_Triangulation) t = BRep_Tool::Triangulation(TopoDS::Face(faces(i)), loc);
        if (t.IsNull()) continue;
        triangles += t->NbTriangles();
        for (int n = 1; n <= t->NbNodes(); ++n) b.Add(t->Node(n).Transformed(loc.Transformation()));
    }
    return to_box(b);
}

const char* const kMeshFixtures[] = {"box_with_holes", "sphere", "filleted_box", "assembly", "torus_iges"};

TEST(ConvertNames, ExtensionsNamesAndContentTypes) {
    EXPECT_EQ(nurbsrt::conversion_format_from_extension("a/b.STL"), ConversionFormat::stl);
    EXPECT_EQ(nurbsrt::conversion_format_from_extension("b.glb"), ConversionFormat::glb);
    EXPECT_EQ(nurbsrt::conversion_format_from_extension("b.Json"), ConversionFormat::nurbs_json);
    EXPECT_EQ(nurbsrt::conversion_format_from_extension("b.stp"), ConversionFormat::step);
    EXPECT_EQ(nurbsrt::conversion_format_from_extension("b.iges"), ConversionFormat::iges);
    EXPECT_EQ(nurbsrt::conversion_format_from_extension("b.gltf"), ConversionFormat::unknown);
    EXPECT_EQ(nurbsrt::conversion_format_from_extension("stl"), ConversionFormat::unknown);
    EXPECT_EQ(nurbsrt::conversion_format_from_name("igs"), ConversionFormat::iges);
    EXPECT_EQ(nurbsrt::conversion_format_from_name("json"), ConversionFormat::nurbs_json);
    EXPECT_EQ(nurbsrt::conversion_format_from_name("STL"), ConversionFormat::unknown);  // names are lowercase
    EXPECT_STREQ(nurbsrt::conversion_format_content_type(ConversionFormat::glb), "model/gltf-binary");
    EXPECT_STREQ(nurbsrt::conversion_format_content_type(ConversionFormat::stl), "model/stl");
    EXPECT_STREQ(nurbsrt::conversion_format_content_type(ConversionFormat::nurbs_json), "application/json");
    EXPECT_STREQ(nurbsrt::conversion_format_content_type(ConversionFormat::vrml), "model/vrml");
    EXPECT_EQ(nurbsrt::conversion_format_from_extension("b.BREP"), ConversionFormat::brep);
    EXPECT_EQ(nurbsrt::conversion_format_from_extension("b.wrl"), ConversionFormat::vrml);
    EXPECT_EQ(nurbsrt::conversion_format_from_name("wrl"), ConversionFormat::vrml);
    EXPECT_EQ(nurbsrt::conversion_format_names(), "step, iges, stl, glb, json, brep, vrml, obj");
    EXPECT_STREQ(nurbsrt::conversion_format_content_type(ConversionFormat::obj), "model/obj");
    EXPECT_STREQ(nurbsrt::conversion_format_companion(ConversionFormat::obj), ".mtl");
    EXPECT_EQ(nurbsrt::conversion_format_companion(ConversionFormat::stl), nullptr);
    // Every format's written extension, short name and alias lead back to it.
    for (ConversionFormat f :
         {ConversionFormat::step, ConversionFormat::iges, ConversionFormat::stl, ConversionFormat::glb,
          ConversionFormat::nurbs_json, ConversionFormat::brep, ConversionFormat::vrml, ConversionFormat::obj}) {
        EXPECT_EQ(nurbsrt::conversion_format_from_extension(std::string("x") + nurbsrt::conversion_format_extension(f)),
                  f);
        EXPECT_EQ(nurbsrt::conversion_format_from_name(nurbsrt::conversion_format_short_name(f)), f);
    }
    EXPECT_EQ(nurbsrt::cad_format_of(ConversionFormat::stl), nurbsrt::CadFormat::unknown);
    EXPECT_EQ(nurbsrt::cad_format_of(ConversionFormat::iges), nurbsrt::CadFormat::iges);
    EXPECT_EQ(nurbsrt::cad_format_of(ConversionFormat::brep), nurbsrt::CadFormat::brep);
    EXPECT_EQ(nurbsrt::format_from_extension("a.brp"), nurbsrt::CadFormat::brep);
    EXPECT_TRUE(nurbsrt::conversion_format_declares_units(ConversionFormat::step));
    EXPECT_FALSE(nurbsrt::conversion_format_declares_units(ConversionFormat::brep));
}

// Which option applies to which format, the fixed units and the mesh formats:
// one table (importer/format.cpp) that the CLI, the service and convert_file read.
TEST(ConvertNames, OptionsUnitsAndMeshesByFormat) {
    using nurbsrt::ConversionOption;
    using nurbsrt::LengthUnit;
    const ConversionFormat all[] = {ConversionFormat::step, ConversionFormat::iges,       ConversionFormat::stl,
                                    ConversionFormat::glb,  ConversionFormat::nurbs_json, ConversionFormat::brep,
                                    ConversionFormat::vrml, ConversionFormat::obj};
    for (ConversionFormat f : all) {
        const bool step = f == ConversionFormat::step, iges = f == ConversionFormat::iges;
        EXPECT_EQ(nurbsrt::conversion_option_refusal(ConversionOption::units, f).empty(), step || iges);
        EXPECT_EQ(nurbsrt::conversion_option_refusal(ConversionOption::step_schema, f).empty(), step);
        EXPECT_EQ(nurbsrt::conversion_option_refusal(ConversionOption::iges_mode, f).empty(), iges);
        EXPECT_EQ(nurbsrt::conversion_format_declares_units(f), step || iges);
        EXPECT_EQ(nurbsrt::conversion_format_fixed_unit(f) == LengthUnit::unknown, step || iges);
        EXPECT_EQ(nurbsrt::conversion_format_is_mesh(f), f == ConversionFormat::stl || f == ConversionFormat::glb ||
                                                             f == ConversionFormat::vrml || f == ConversionFormat::obj);
    }
    EXPECT_EQ(nurbsrt::conversion_format_fixed_unit(ConversionFormat::glb), LengthUnit::m);
    EXPECT_EQ(nurbsrt::conversion_format_fixed_unit(ConversionFormat::brep), LengthUnit::mm);
    EXPECT_EQ(nurbsrt::conversion_option_refusal(ConversionOption::units, ConversionFormat::stl),
              "applies to STEP and IGES outputs only");
    EXPECT_EQ(nurbsrt::conversion_option_refusal(ConversionOption::iges_mode, ConversionFormat::step),
              "applies to IGES outputs only");
    EXPECT_STREQ(nurbsrt::conversion_option_name(ConversionOption::step_schema), "step_schema");
    // The service's request model refuses by the same rule, naming the option.
    try {
        nurbsrt::parse_conversion_request(R"({"format":"glb","step_schema":"ap242"})");
        FAIL() << "no error";
    } catch (const nurbsrt::Error& e) {
        EXPECT_NE(std::string(e.what()).find("option 'step_schema' applies to STEP outputs only, not glb"),
                  std::string::npos)
            << e.what();
    }
    // And convert_file, for the one option it cannot tell from a default.
    nurbsrt::ConvertOptions inch;
    inch.units = LengthUnit::inch;
    EXPECT_THROW(nurbsrt::convert_file(nurbsrt::test::box_with_holes(), out_path("inch", ".glb"), inch),
                 nurbsrt::Error);
    EXPECT_EQ(nurbsrt::parse_conversion_request(R"({"format":"step","units":"inch"})").options.units, LengthUnit::inch);
}

TEST(ConvertNames, UnknownExtensionIsUnsupported) {
    try {
        nurbsrt::convert_file(nurbsrt::test::box_with_holes(), out_path("x", ".3mf"));
        FAIL() << "no error";
    } catch (const nurbsrt::Error& e) {
        EXPECT_EQ(e.code(), nurbsrt::ErrorCode::unsupported_format);
    }
}

class ConvertMesh : public ::testing::TestWithParam<const char*> {};

TEST_P(ConvertMesh, StlReadsBackWithTheModelBox) {
    const std::string in = nurbsrt::test::fixture_by_name(GetParam());
    const std::string out = out_path(GetParam(), ".stl");
    const nurbsrt::ConvertReport r = nurbsrt::convert_file(in, out);
    EXPECT_EQ(r.output, ConversionFormat::stl);
    EXPECT_EQ(r.out_format, nurbsrt::CadFormat::unknown);
    EXPECT_EQ(r.unmeshed_faces, 0);
    ASSERT_GT(r.triangles, 0);

    // Binary layout: 80-byte header, uint32 count, 50 bytes per triangle.
    const std::string bytes = read_bytes(out);
    ASSERT_GE(bytes.size(), 84u);
    uint32_t count = 0;
    std::memcpy(&count, bytes.data() + 80, 4);
    EXPECT_EQ(count, static_cast<uint32_t>(r.triangles));
    EXPECT_EQ(bytes.size(), 84u + 50u * count);

    const Handle(Poly_Triangulation) t = RWStl::ReadFile(out.c_str(), Message_ProgressRange());
    ASSERT_FALSE(t.IsNull());
    // No triangle of no area (its float corners, as written, span none) and
    // none twice: RWStl, which drops the first kind, reads them all.
    std::set<std::array<float, 9>> seen;
    for (uint32_t k = 0; k < count; ++k) {
        std::array<float, 9> v;
        std::memcpy(v.data(), bytes.data() + 84 + 50 * size_t(k) + 12, sizeof v);  // after the normal
        for (float x : v) ASSERT_TRUE(std::isfinite(x)) << "triangle " << k;
        const gp_Vec ab(v[3] - double(v[0]), v[4] - double(v[1]), v[5] - double(v[2]));
        const gp_Vec ac(v[6] - double(v[0]), v[7] - double(v[1]), v[8] - double(v[2]));
        EXPECT_GT(ab.Crossed(ac).Magnitude(), 0.0) << "triangle " << k << " has no area";
        // The same triangle from any corner.
        std::array<std::array<float, 3>, 3> corners{{{v[0], v[1], v[2]}, {v[3], v[4], v[5]}, {v[6], v[7], v[8]}}};
        std::sort(corners.begin(), corners.end());
        std::array<float, 9> key;
        for (int c = 0; c < 3; ++c) std::copy(corners[c].begin(), corners[c].end(), key.begin() + 3 * c);
        EXPECT_TRUE(seen.insert(key).second) << "triangle " << k << " repeats another";
    }
    EXPECT_EQ(t->NbTriangles(), static_cast<int>(count));
    Bnd_Box b;
    for (int n = 1; n <= t->NbNodes(); ++n) b.Add(t->Node(n));
    const Box3 want = exact_box(in);
    // STL stores float32: add its rounding to the deflection.
    expect_box_near(to_box(b), want, deflection_of(want) + 1e-5 * want.diagonal(), "STL");
}

TEST_P(ConvertMesh, GlbReadsBackWithTheModelBoxInGltfAxes) {
    const std::string in = nurbsrt::test::fixture_by_name(GetParam());
    const std::string out = out_path(GetParam(), ".glb");
    const nurbsrt::ConvertReport r = nurbsrt::convert_file(in, out);
    EXPECT_EQ(r.output, ConversionFormat::glb);
    EXPECT_EQ(r.unmeshed_faces, 0);
    ASSERT_GT(r.triangles, 0);
    const Box3 want = exact_box(in);
    const double tol = deflection_of(want) + 1e-5 * want.diagonal();

    // Read back twice: converting glTF's metres/Y-up back to the model's mm/Z-up, and as stored.
    for (const bool back_to_model : {true, false}) {
        Handle(TDocStd_Document) doc;
        XCAFApp_Application::GetApplication()->NewDocument("MDTV-XCAF", doc);
        RWGltf_CafReader reader;
        reader.SetDocument(doc);
        if (back_to_model) {
            reader.SetSystemLengthUnit(0.001);
            reader.SetSystemCoordinateSystem(RWMesh_CoordinateSystem_Zup);
        } else {
            reader.SetSystemLengthUnit(1.0);
            reader.SetSystemCoordinateSystem(RWMesh_CoordinateSystem_glTF);
        }
        ASSERT_TRUE(reader.Perform(out.c_str(), Message_ProgressRange()));
        long long triangles = 0;
        const Box3 got = mesh_box(reader.SingleShape(), triangles);
        XCAFApp_Application::GetApplication()->Close(doc);
        EXPECT_EQ(triangles, r.triangles);
        if (back_to_model) {
            expect_box_near(got, want, tol, "glb in model axes");
        } else {
            // (x, y, z) mm -> (x, z, -y) / 1000 m
            const Box3 gltf{{want.lo[0] / 1000, want.lo[2] / 1000, -want.hi[1] / 1000},
                            {want.hi[0] / 1000, want.hi[2] / 1000, -want.lo[1] / 1000}};
            expect_box_near(got, gltf, tol / 1000, "glb as stored");
        }
    }
}

INSTANTIATE_TEST_SUITE_P(Fixtures, ConvertMesh, ::testing::ValuesIn(kMeshFixtures),
                         [](const auto& info) { return std::string(info.param); });

// The sphere's poles: BRepMesh, run here as convert_file runs it (deflection
// relative to the faces' box), gives each pole triangle two corners at the
// pole. The STL leaves those out (the test above finds none) and the report
// counts every triangle it left out.
TEST(ConvertStl, TrianglesOfNoAreaAreLeftOutAndCounted) {
    const std::string in = nurbsrt::test::sphere();
    const nurbsrt::ConvertReport r = nurbsrt::convert_file(in, out_path("sphere-degenerate", ".stl"));
    const nurbsrt::occt::OcctModel m = nurbsrt::occt::read_model(in, false);
    Bnd_Box box;
    for (int i = 1; i <= m.faces.Extent(); ++i) BRepBndLib::Add(m.faces(i), box, Standard_False);
    IMeshTools_Parameters params;
    params.Deflection = nurbsrt::ImportOptions{}.mesh_relative_deflection * std::sqrt(box.SquareExtent());
    params.Angle = nurbsrt::ImportOptions{}.mesh_angular_deflection;
    BRepMesh_IncrementalMesh mesher(m.shape, params);
    long long all = 0, pole = 0;
    for (int i = 1; i <= m.faces.Extent(); ++i) {
        TopLoc_Location loc;
        const Handle(Poly_Triangulation) t = BRep_Tool::Triangulation(TopoDS::Face(m.faces(i)), loc);
        ASSERT_FALSE(t.IsNull());
        all += t->NbTriangles();
        for (int k = 1; k <= t->NbTriangles(); ++k) {
            int a, b, c;
            t->Triangle(k).Get(a, b, c);
            const gp_Pnt pa = t->Node(a), pb = t->Node(b), pc = t->Node(c);
            pole += pa.IsEqual(pb, 0.0) || pb.IsEqual(pc, 0.0) || pa.IsEqual(pc, 0.0);
        }
    }
    ASSERT_GT(pole, 0) << "the sphere's mesh has no pole triangles to leave out";
    EXPECT_GE(r.degenerate_triangles, pole);
    EXPECT_EQ(r.triangles + r.degenerate_triangles, all);
}

// The glb's JSON chunk (glTF 2.0 container: 12-byte header, then chunks).
json glb_json(const std::string& bytes) {
    uint32_t magic = 0, version = 0, length = 0, chunk_length = 0, chunk_type = 0;
    EXPECT_GE(bytes.size(), 20u);
    std::memcpy(&magic, bytes.data(), 4);
    std::memcpy(&version, bytes.data() + 4, 4);
    std::memcpy(&length, bytes.data() + 8, 4);
    std::memcpy(&chunk_length, bytes.data() + 12, 4);
    std::memcpy(&chunk_type, bytes.data() + 16, 4);
    EXPECT_EQ(magic, 0x46546C67u);  // "glTF"
    EXPECT_EQ(version, 2u);
    EXPECT_EQ(length, bytes.size());
    EXPECT_EQ(chunk_type, 0x4E4F534Au);  // "JSON"
    return json::parse(bytes.substr(20, chunk_length));
}

TEST(ConvertGlb, AssemblyKeepsInstancesNamesAndColour) {
    const std::string out = out_path("assembly-attrs", ".glb");
    nurbsrt::convert_file(nurbsrt::test::assembly(), out);
    const json g = glb_json(read_bytes(out));
    // Each instance is a node carrying its placement, converted like the points:
    // (x, y, z) mm -> (x, z, -y) / 1000 m.
    for (int k = 0; k < 2; ++k) {
        const char* instance = nurbsrt::test::kAssemblyInstanceNames[k];
        const auto node = std::find_if(g.at("nodes").begin(), g.at("nodes").end(),
                                       [&](const json& n) { return n.value("name", "") == instance; });
        ASSERT_NE(node, g.at("nodes").end()) << instance << ": " << g.at("nodes").dump();
        EXPECT_TRUE(node->contains("mesh")) << node->dump();
        const nurbsrt::test::Offset o = nurbsrt::test::kAssemblyOffsets[k];
        const json t = node->value("translation", json::array({0.0, 0.0, 0.0}));
        EXPECT_NEAR(t.at(0).get<double>(), o.x / 1000, 1e-12) << node->dump();
        EXPECT_NEAR(t.at(1).get<double>(), o.z / 1000, 1e-12) << node->dump();
        EXPECT_NEAR(t.at(2).get<double>(), -o.y / 1000, 1e-12) << node->dump();
    }
    bool colour_found = false;
    for (const json& m : g.at("materials")) {
        const json& c = m.at("pbrMetallicRoughness").at("baseColorFactor");
        colour_found |= std::abs(c[0].get<double>() - nurbsrt::test::kAssemblyColor.r) < 1e-3 &&
                        std::abs(c[1].get<double>() - nurbsrt::test::kAssemblyColor.g) < 1e-3 &&
                        std::abs(c[2].get<double>() - nurbsrt::test::kAssemblyColor.b) < 1e-3;
    }
    EXPECT_TRUE(colour_found) << g.at("materials").dump();
    // Painted parts, not chrome: metallic 0 in every material (glTF's default is 1),
    // and every primitive has one (without, viewers take glTF's default material).
    for (const json& m : g.at("materials")) {
        const json& pbr = m.at("pbrMetallicRoughness");
        EXPECT_EQ(pbr.value("metallicFactor", 1.0), 0.0) << m.dump();
        EXPECT_NEAR(pbr.value("roughnessFactor", 1.0), 0.5, 1e-6) << m.dump();
    }
    for (const json& mesh : g.at("meshes"))
        for (const json& p : mesh.at("primitives")) EXPECT_TRUE(p.contains("material")) << mesh.dump();
}

// A patch rebuilt from its JSON only (no nurbsrt code involved in reading).
nurbsrt::NurbsSurface surface_from_json(const json& s) {
    nurbsrt::NurbsSurface r;
    r.degree_u = s.at("degree_u");
    r.degree_v = s.at("degree_v");
    r.num_u = s.at("num_u");
    r.num_v = s.at("num_v");
    r.rational = s.at("rational");
    r.knots_u = s.at("knots_u").get<std::vector<double>>();
    r.knots_v = s.at("knots_v").get<std::vector<double>>();
    for (const json& p : s.at("control_points"))
        r.cp.push_back({p.at(0).get<double>(), p.at(1).get<double>(), p.at(2).get<double>(), p.at(3).get<double>()});
    return r;
}

class ConvertJson : public ::testing::TestWithParam<const char*> {};

TEST_P(ConvertJson, PatchesEvaluateLikeTheScene) {
    const std::string in = nurbsrt::test::fixture_by_name(GetParam());
    const std::string out = out_path(GetParam(), ".json");
    const nurbsrt::ConvertReport r = nurbsrt::convert_file(in, out);
    EXPECT_EQ(r.output, ConversionFormat::nurbs_json);
    const json doc = json::parse(read_bytes(out));
    const nurbsrt::Scene scene = nurbsrt::import_file(in);

    EXPECT_EQ(doc.at("format"), nurbsrt::kSceneJsonFormat);
    EXPECT_EQ(doc.at("units"), "mm");
    ASSERT_EQ(doc.at("faces").size(), scene.faces.size());
    EXPECT_EQ(doc.at("patches").get<size_t>(), scene.faces.size());
    EXPECT_EQ(r.faces, static_cast<int>(scene.faces.size()));
    EXPECT_DOUBLE_EQ(doc.at("bbox").at("min").at(0).get<double>(), scene.bbox.lo.x);
    EXPECT_DOUBLE_EQ(doc.at("bbox").at("max").at(2).get<double>(), scene.bbox.hi.z);

    for (size_t k = 0; k < scene.faces.size(); ++k) {
        const nurbsrt::Face& f = scene.faces[k];
        const json& jf = doc.at("faces").at(k);
        EXPECT_EQ(jf.at("index").get<uint32_t>(), f.index);
        EXPECT_EQ(jf.at("reversed").get<bool>(), f.reversed);
        EXPECT_EQ(jf.at("trim_loops").size(), f.loops.size());
        const nurbsrt::NurbsSurface s = surface_from_json(jf.at("surface"));
        ASSERT_EQ(s.cp.size(), static_cast<size_t>(s.num_u) * s.num_v);
        ASSERT_EQ(s.knots_u.size(), static_cast<size_t>(s.num_u + s.degree_u + 1));
        ASSERT_EQ(s.knots_v.size(), static_cast<size_t>(s.num_v + s.degree_v + 1));
        const double u0 = jf.at("u_range").at(0), u1 = jf.at("u_range").at(1);
        const double v0 = jf.at("v_range").at(0), v1 = jf.at("v_range").at(1);
        for (double a : {0.0, 0.31, 0.5, 0.77, 1.0})
            for (double b : {0.0, 0.13, 0.5, 0.9, 1.0}) {
                const double u = u0 + a * (u1 - u0), v = v0 + b * (v1 - v0);
                const nurbsrt::Vec4 got = nurbsrt::evaluate(s, u, v);
                const nurbsrt::Vec4 want = nurbsrt::evaluate(f.surface, u, v);
                // JSON numbers round-trip exactly (shortest repr. that reads back identically).
                EXPECT_EQ(got.x, want.x) << "face " << f.index << " at " << u << "," << v;
                EXPECT_EQ(got.y, want.y);
                EXPECT_EQ(got.z, want.z);
                EXPECT_EQ(got.w, want.w);
            }
    }
}

INSTANTIATE_TEST_SUITE_P(Fixtures, ConvertJson,
                         ::testing::Values("box_with_holes", "sphere", "freeform_rational", "assembly",
                                           "freeform_bspline_iges"),
                         [](const auto& info) { return std::string(info.param); });

TEST(ConvertJson, NonFiniteNumbersBecomeNull) {
    nurbsrt::Scene scene;  // empty bbox (infinite bounds) and a NaN control point
    scene.format = "STEP";
    nurbsrt::Face f;
    f.index = 1;
    f.surface.degree_u = f.surface.degree_v = 1;
    f.surface.num_u = f.surface.num_v = 2;
    f.surface.knots_u = f.surface.knots_v = {0, 0, 1, 1};
    f.surface.cp = {{0, 0, 0, 1}, {std::nan(""), 0, 0, 1}, {0, HUGE_VAL, 0, 1}, {1, 1, 0, 1}};
    scene.faces.push_back(f);
    const std::string text = nurbsrt::scene_to_json(scene);
    EXPECT_EQ(text.find("nan"), std::string::npos);
    EXPECT_EQ(text.find("inf"), std::string::npos);
    const json doc = json::parse(text);  // throws on invalid JSON
    EXPECT_TRUE(doc.at("bbox").is_null());
    EXPECT_TRUE(doc.at("faces")[0]["surface"]["control_points"][1][0].is_null());
    EXPECT_TRUE(doc.at("faces")[0]["surface"]["control_points"][2][1].is_null());
    EXPECT_EQ(doc.at("faces")[0]["surface"]["control_points"][3][0].get<double>(), 1.0);
}

TEST(ConvertIsolated, ReportsCrossTheProcessBoundary) {
    nurbsrt::IsolationLimits limits;
    limits.time_limit_s = 120;
    limits.worker_executable = NURBSRT_BINARY;
    const std::string in = nurbsrt::test::box_with_holes();
    const nurbsrt::ConvertReport direct = nurbsrt::convert_file(in, out_path("iso-direct", ".stl"));
    const nurbsrt::ConvertReport stl = nurbsrt::convert_isolated(in, out_path("iso", ".stl"), limits);
    EXPECT_EQ(stl.output, ConversionFormat::stl);
    EXPECT_EQ(stl.in_format, nurbsrt::CadFormat::step);
    EXPECT_EQ(stl.triangles, direct.triangles);
    EXPECT_EQ(stl.faces, 8);
    EXPECT_GT(stl.mesh_ms, 0);
    const nurbsrt::ConvertReport glb = nurbsrt::convert_isolated(in, out_path("iso", ".glb"), limits);
    EXPECT_EQ(glb.output, ConversionFormat::glb);
    EXPECT_EQ(glb.triangles, direct.triangles);
    const nurbsrt::ConvertReport js = nurbsrt::convert_isolated(in, out_path("iso", ".json"), limits);
    EXPECT_EQ(js.output, ConversionFormat::nurbs_json);
    EXPECT_EQ(js.triangles, 0);
    const nurbsrt::ConvertReport igs = nurbsrt::convert_isolated(in, out_path("iso", ".igs"), limits);
    EXPECT_EQ(igs.output, ConversionFormat::iges);
    EXPECT_EQ(igs.out_format, nurbsrt::CadFormat::iges);
    EXPECT_GT(igs.verify_ms, 0);  // the read-back check, a stage of its own
    EXPECT_GT(stl.verify_ms, 0);  // the mesh measured against the exact faces
    EXPECT_EQ(js.verify_ms, 0);
    // The fidelity report crosses whole (one line of compact JSON).
    EXPECT_EQ(stl.fidelity.substr(0, 11), "{\"source\":{");
    EXPECT_NE(igs.fidelity.find("\"attributes\""), std::string::npos);
    EXPECT_EQ(igs.in_units, "mm");
    EXPECT_EQ(igs.out_units, "mm");
    EXPECT_EQ(stl.out_units, "mm");
    EXPECT_EQ(glb.out_units, "m");
    // The options cross too, and the sphere's left-out pole triangles are counted.
    nurbsrt::ConvertOptions cm;
    cm.units = nurbsrt::LengthUnit::cm;
    EXPECT_EQ(nurbsrt::convert_isolated(in, out_path("iso-cm", ".step"), limits, nullptr, cm).out_units, "cm");
    const std::string sphere = nurbsrt::test::sphere();
    const nurbsrt::ConvertReport poles = nurbsrt::convert_isolated(sphere, out_path("iso-sphere", ".stl"), limits);
    EXPECT_GT(poles.degenerate_triangles, 0);
    EXPECT_EQ(poles.degenerate_triangles,
              nurbsrt::convert_file(sphere, out_path("iso-sphere-direct", ".stl")).degenerate_triangles);
}

// The child's stages and the parent's share (IsolationTimings) are the whole
// call, by construction (no timing threshold: a loaded machine cannot fail
// it): they add up to the call's total, which lies within the wall time seen
// from outside; what the service's conversion timings add up from.
TEST(ConvertIsolated, StagesAndIsolationAreTheWholeCall) {
    nurbsrt::IsolationLimits limits;
    limits.time_limit_s = 120;
    limits.worker_executable = NURBSRT_BINARY;
    const std::string in = nurbsrt::test::box_with_holes();
    for (const char* ext : {".stl", ".step"}) {
        nurbsrt::IsolationTimings t;
        const auto t0 = std::chrono::steady_clock::now();
        const nurbsrt::ConvertReport r = nurbsrt::convert_isolated(in, out_path("iso-timed", ext), limits, &t);
        const double wall = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
        const double sum =
            t.prescan_ms + t.isolation_ms + t.transfer_ms + r.read_ms + r.mesh_ms + r.write_ms + r.verify_ms;
        EXPECT_NEAR(sum, t.total_ms, 1e-9 * t.total_ms) << ext;
        EXPECT_LE(t.total_ms, wall) << ext;
        EXPECT_GT(t.isolation_ms, 0) << ext;  // starting a process is never free
        EXPECT_GE(t.prescan_ms, 0) << ext;
        EXPECT_GE(t.transfer_ms, 0) << ext;
        EXPECT_GT(r.read_ms, 0) << ext;
    }
}

}  // namespace
