// convert_file to the formats written by OCCT's own writers besides STEP/IGES
// defaults: BREP (read and write), VRML, STEP AP242 and IGES in faces mode,
// each result read back by OCCT independently of the project's reader.
//  * Brep:     STEP -> BREP -> STEP keeps faces, solids, volume and area (BRepGProp,
//              relative 1e-9: the same exact geometry); the BREP is OCCT's text
//              (BRepTools::Read reads it); the assembly's colours, names and tree,
//              which BREP cannot carry, are each reported; a BREP file imports
//              (format by content) like any other, for renders and info.
//  * Vrml:     a VRML 2.0 file whose points span the model's exact box within the
//              mesh deflection, with the part's colour as a diffuse colour.
//  * Schema:   AP242 writes AP242's schema in the header (AP214 by default), and reads back.
//  * IgesMode: faces mode writes trimmed surfaces (144) and no solid (186); brep mode a solid.
//  * Obj:      OCCT's RWObj_CafReader reads the .obj and its .mtl back: the triangles
//              the report counts, one group per part instance (the assembly's two
//              brackets, named), the part's colour as its material, the model's box.
#include <gtest/gtest.h>

#include <BRepBndLib.hxx>
#include <BRep_Tool.hxx>
#include <Message_ProgressRange.hxx>
#include <Poly_Triangulation.hxx>
#include <Quantity_Color.hxx>
#include <RWMesh_CoordinateSystem.hxx>
#include <RWObj_CafReader.hxx>
#include <TDocStd_Document.hxx>
#include <TopExp_Explorer.hxx>
#include <TopLoc_Location.hxx>
#include <TopoDS.hxx>
#include <XCAFApp_Application.hxx>
#include <XCAFDoc_DocumentTool.hxx>
#include <XCAFDoc_ShapeTool.hxx>
#include <XCAFDoc_VisMaterialTool.hxx>
#include <TDF_LabelSequence.hxx>
#include <XCAFPrs_DocumentExplorer.hxx>
#include <XCAFDoc_VisMaterial.hxx>
#include <XCAFPrs_Style.hxx>
#include <BRepGProp.hxx>
#include <BRepTools.hxx>
#include <BRep_Builder.hxx>
#include <Bnd_Box.hxx>
#include <GProp_GProps.hxx>
#include <STEPControl_Reader.hxx>
#include <TopExp.hxx>
#include <TopTools_IndexedMapOfShape.hxx>

#include <cmath>
#include <fstream>
#include <limits>
#include <regex>
#include <set>
#include <sstream>
#include <string>

#include "core/error.h"
#include "importer/importer.h"
#include "importer/isolated.h"
#include "tests/support/fixtures.h"

namespace {

std::string out_path(const std::string& name) { return nurbsrt::test::fixture_dir() + "/formats-" + name; }

std::string read_text(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    std::ostringstream ss;
    ss << in.rdbuf();
    return ss.str();
}

// Volume, area and topology of a shape, by OCCT.
struct Measures {
    int faces = 0, solids = 0;
    double volume = 0, area = 0;
};

Measures measure(const TopoDS_Shape& s) {
    Measures m;
    TopTools_IndexedMapOfShape faces, solids;
    TopExp::MapShapes(s, TopAbs_FACE, faces);
    TopExp::MapShapes(s, TopAbs_SOLID, solids);
    m.faces = faces.Extent();
    m.solids = solids.Extent();
    GProp_GProps v, a;
    BRepGProp::VolumeProperties(s, v);
    BRepGProp::SurfaceProperties(s, a);
    m.volume = v.Mass();
    m.area = a.Mass();
    return m;
}

TopoDS_Shape read_step_shape(const std::string& path) {
    STEPControl_Reader r;
    EXPECT_EQ(r.ReadFile(path.c_str()), IFSelect_RetDone) << path;
    r.TransferRoots();
    return r.OneShape();
}

TopoDS_Shape read_brep_shape(const std::string& path) {
    TopoDS_Shape s;
    BRep_Builder b;
    EXPECT_TRUE(BRepTools::Read(s, path.c_str(), b)) << path;
    return s;
}

// Same exact geometry: written and read with 17 significant digits.
constexpr double kSameGeometry = 1e-9;

void expect_same(const Measures& a, const Measures& b, const std::string& what) {
    EXPECT_EQ(b.faces, a.faces) << what;
    EXPECT_EQ(b.solids, a.solids) << what;
    EXPECT_NEAR(b.volume, a.volume, kSameGeometry * std::abs(a.volume)) << what;
    EXPECT_NEAR(b.area, a.area, kSameGeometry * a.area) << what;
}

TEST(ConvertBrep, StepToBrepToStepKeepsTheExactGeometry) {
    const std::string in = nurbsrt::test::filleted_box();
    const std::string brep = out_path("filleted.brep"), back = out_path("filleted-back.step");
    const nurbsrt::ConvertReport r1 = nurbsrt::convert_file(in, brep);
    EXPECT_EQ(r1.output, nurbsrt::ConversionFormat::brep);
    EXPECT_EQ(r1.out_format, nurbsrt::CadFormat::brep);
    EXPECT_EQ(r1.out_units, "mm");
    EXPECT_GT(r1.verify_ms, 0);
    const nurbsrt::ConvertReport r2 = nurbsrt::convert_file(brep, back);
    EXPECT_EQ(r2.in_format, nurbsrt::CadFormat::brep);
    EXPECT_EQ(r2.in_units, "");  // BREP declares none
    EXPECT_EQ(r2.out_units, "mm");
    const Measures a = measure(read_step_shape(in));
    ASSERT_EQ(a.faces, 26);
    ASSERT_GT(a.volume, 0);
    expect_same(a, measure(read_brep_shape(brep)), "STEP -> BREP");
    expect_same(a, measure(read_step_shape(back)), "STEP -> BREP -> STEP");
    EXPECT_EQ(nurbsrt::detect_format(brep), nurbsrt::CadFormat::brep);
}

TEST(ConvertBrep, ReportsWhatBrepCannotCarry) {
    const nurbsrt::ConvertReport r = nurbsrt::convert_file(nurbsrt::test::assembly(), out_path("assembly.brep"));
    std::string all;
    for (const std::string& w : r.warnings) all += w + "\n";
    EXPECT_NE(all.find("BREP has no product structure: 2 part instance(s)"), std::string::npos) << all;
    EXPECT_NE(all.find("lost their colour"), std::string::npos) << all;
    EXPECT_NE(all.find("'bracket'"), std::string::npos) << all;
    EXPECT_EQ(r.faces, 2 * nurbsrt::test::kAssemblyPartFaces);
}

TEST(ConvertBrep, ABrepFileImportsLikeAnyOther) {
    const std::string brep = out_path("holes.brep");
    nurbsrt::convert_file(nurbsrt::test::box_with_holes(), brep);
    const nurbsrt::Scene scene = nurbsrt::import_file(brep);
    EXPECT_EQ(scene.format, "BREP");
    EXPECT_EQ(scene.faces.size(), 8u);
    ASSERT_EQ(scene.parts.size(), 1u);
    EXPECT_EQ(scene.parts[0].parent, -1);
    // Through the isolated worker as the service imports it.
    nurbsrt::IsolationLimits limits;
    limits.worker_executable = NURBSRT_BINARY;
    EXPECT_EQ(nurbsrt::import_isolated(brep, {}, limits).faces.size(), 8u);
}

TEST(ConvertBrep, TextThatIsNoBrepIsNotTakenForOne) {
    const std::string draw = "DBRep_DrawableShape\n\nCASCADE Topology V1, (c) Matra-Datavision\n";
    EXPECT_EQ(nurbsrt::detect_format_bytes(draw.data(), draw.size()), nurbsrt::CadFormat::brep);
    const std::string other = "CASCADE is a waterfall\n";
    EXPECT_EQ(nurbsrt::detect_format_bytes(other.data(), other.size()), nurbsrt::CadFormat::unknown);
}

// The x y z triples of every `point [ ... ]` of a VRML file.
Bnd_Box vrml_points_box(const std::string& text, int& points) {
    Bnd_Box box;
    points = 0;
    static const std::regex block(R"(point\s*\[([^\]]*)\])");
    for (std::sregex_iterator it(text.begin(), text.end(), block), end; it != end; ++it) {
        std::string list = (*it)[1].str();
        std::replace(list.begin(), list.end(), ',', ' ');
        std::istringstream in(list);
        double x, y, z;
        while (in >> x >> y >> z) {
            box.Add(gp_Pnt(x, y, z));
            ++points;
        }
    }
    return box;
}

TEST(ConvertVrml, PointsSpanTheModel) {
    const std::string in = nurbsrt::test::box_with_holes();
    const std::string out = out_path("holes.wrl");
    const nurbsrt::ConvertReport r = nurbsrt::convert_file(in, out);
    EXPECT_EQ(r.output, nurbsrt::ConversionFormat::vrml);
    EXPECT_GT(r.triangles, 0);
    EXPECT_EQ(r.unmeshed_faces, 0);
    EXPECT_EQ(r.out_units, "mm");
    const std::string text = read_text(out);
    ASSERT_EQ(text.rfind("#VRML V2.0 utf8", 0), 0u) << text.substr(0, 40);
    int points = 0;
    const Bnd_Box got = vrml_points_box(text, points);
    ASSERT_GT(points, 0);
    // The exact box of the faces (not of a mesh), and the deflection the export meshes with.
    Bnd_Box want;
    BRepBndLib::AddOptimal(read_step_shape(in), want, Standard_False, Standard_False);
    const double tol = nurbsrt::ImportOptions{}.mesh_relative_deflection * std::sqrt(want.SquareExtent()) + 1e-6;
    double g[6], w[6];
    got.Get(g[0], g[1], g[2], g[3], g[4], g[5]);
    want.Get(w[0], w[1], w[2], w[3], w[4], w[5]);
    for (int k = 0; k < 6; ++k) EXPECT_NEAR(g[k], w[k], tol) << "box coordinate " << k;
}

TEST(ConvertVrml, TheAssemblysColourIsADiffuseColour) {
    const std::string out = out_path("assembly.wrl");
    nurbsrt::convert_file(nurbsrt::test::assembly(), out);
    const std::string text = read_text(out);
    const auto c = nurbsrt::test::kAssemblyColor;
    // OCCT writes the colour in linear RGB with a few digits: find the red channel.
    std::smatch m;
    ASSERT_TRUE(
        std::regex_search(text, m, std::regex(R"(diffuseColor\s+([0-9.eE+-]+)\s+([0-9.eE+-]+)\s+([0-9.eE+-]+))")))
        << "no diffuse colour";
    EXPECT_GT(std::stod(m[1].str()), std::stod(m[2].str()))
        << "the part is red (" << c.r << ", " << c.g << ", " << c.b << "): " << m[0].str();
}

TEST(ConvertObj, ReadBackByOcctsObjReader) {
    const std::string out = out_path("assembly.obj"), mtl = out.substr(0, out.size() - 4) + ".mtl";
    const nurbsrt::ConvertReport r = nurbsrt::convert_file(nurbsrt::test::assembly(), out);
    EXPECT_EQ(r.output, nurbsrt::ConversionFormat::obj);
    EXPECT_EQ(r.out_units, "mm");
    EXPECT_TRUE(r.warnings.empty()) << r.warnings.front();
    ASSERT_TRUE(std::ifstream(mtl).good()) << "no .mtl beside the .obj";
    EXPECT_NE(read_text(out).find("mtllib " + mtl.substr(mtl.find_last_of('/') + 1)), std::string::npos);
    EXPECT_NE(r.fidelity.find("\"deviation_in_mm\":{"), std::string::npos);

    Handle(TDocStd_Document) doc;
    XCAFApp_Application::GetApplication()->NewDocument("MDTV-XCAF", doc);
    RWObj_CafReader reader;
    reader.SetDocument(doc);
    reader.SetSystemLengthUnit(0.001);
    reader.SetSystemCoordinateSystem(RWMesh_CoordinateSystem_Zup);
    reader.SetFileLengthUnit(0.001);
    reader.SetFileCoordinateSystem(RWMesh_CoordinateSystem_Zup);
    ASSERT_TRUE(reader.Perform(out.c_str(), Message_ProgressRange()));
    long long triangles = 0;
    int groups = 0;
    std::set<std::string> names;
    bool red = false;
    const auto c = nurbsrt::test::kAssemblyColor;
    for (XCAFPrs_DocumentExplorer ex(doc, XCAFPrs_DocumentExplorerFlags_OnlyLeafNodes); ex.More(); ex.Next()) {
        ++groups;
        names.insert(TCollection_AsciiString(ex.Current().Id).ToCString());
        for (TopExp_Explorer f(
                 ex.Current().Label.IsNull() ? TopoDS_Shape() : XCAFDoc_ShapeTool::GetShape(ex.Current().Label),
                 TopAbs_FACE);
             f.More(); f.Next()) {
            TopLoc_Location loc;
            const Handle(Poly_Triangulation) t = BRep_Tool::Triangulation(TopoDS::Face(f.Current()), loc);
            if (!t.IsNull()) triangles += t->NbTriangles();
        }
    }
    // The .mtl's Kd (sRGB) read back as a material's base colour (linear RGB).
    TDF_LabelSequence materials;
    XCAFDoc_DocumentTool::VisMaterialTool(doc->Main())->GetMaterials(materials);
    for (const TDF_Label& l : materials) {
        const Quantity_Color q =
            XCAFDoc_DocumentTool::VisMaterialTool(doc->Main())->GetMaterial(l)->BaseColor().GetRGB();
        red = red ||
              (std::abs(q.Red() - c.r) < 0.01 && std::abs(q.Green() - c.g) < 0.01 && std::abs(q.Blue() - c.b) < 0.01);
    }
    EXPECT_EQ(materials.Length(), 1);
    XCAFApp_Application::GetApplication()->Close(doc);
    EXPECT_EQ(triangles, r.triangles);
    // One group per part instance, named after the part (the reader joins
    // groups of one name into one shape).
    EXPECT_EQ(groups, 1);
    const std::string text = read_text(out);
    size_t instances = 0;
    for (size_t at = text.find("\ng two_brackets/bracket\n"); at != std::string::npos;
         at = text.find("\ng two_brackets/bracket\n", at + 1))
        ++instances;
    EXPECT_EQ(instances, 2u) << "one group per bracket instance";
    EXPECT_TRUE(red) << "the bracket's colour is not a material of the .mtl";
}

TEST(ConvertStepSchema, Ap242IsWrittenWhenAskedAp214ByDefault) {
    const std::string in = nurbsrt::test::box_with_holes();
    const std::string a214 = out_path("holes-214.step"), a242 = out_path("holes-242.step");
    nurbsrt::convert_file(in, a214);
    nurbsrt::ConvertOptions o;
    o.step_schema = nurbsrt::StepSchema::ap242;
    const nurbsrt::ConvertReport r = nurbsrt::convert_file(in, a242, o);
    EXPECT_TRUE(r.warnings.empty());
    EXPECT_NE(read_text(a214).find("AUTOMOTIVE_DESIGN"), std::string::npos);
    EXPECT_NE(read_text(a242).find("AP242_MANAGED_MODEL_BASED_3D_ENGINEERING"), std::string::npos);
    expect_same(measure(read_step_shape(in)), measure(read_step_shape(a242)), "STEP -> STEP AP242");
}

TEST(ConvertIgesMode, FacesModeWritesTrimmedSurfacesWithoutSolids) {
    const std::string in = nurbsrt::test::box_with_holes();
    const std::string brep = out_path("holes-brep.igs"), faces = out_path("holes-faces.igs");
    nurbsrt::convert_file(in, brep);
    nurbsrt::ConvertOptions o;
    o.iges_mode = nurbsrt::IgesMode::faces;
    const nurbsrt::ConvertReport r = nurbsrt::convert_file(in, faces, o);
    EXPECT_EQ(r.faces, 8);
    // Entity types in the Directory Entry section: columns 1-8 of its odd records.
    auto types = [](const std::string& text) {
        std::set<int> t;
        std::istringstream lines(text);
        std::string line;
        bool first = true;
        while (std::getline(lines, line))
            if (line.size() >= 73 && line[72] == 'D') {
                if (first) t.insert(std::stoi(line.substr(0, 8)));
                first = !first;
            }
        return t;
    };
    const std::set<int> f = types(read_text(faces)), b = types(read_text(brep));
    EXPECT_TRUE(f.count(144) && !f.count(186)) << "faces mode";
    EXPECT_TRUE(b.count(186) && !b.count(144)) << "brep mode";
}

TEST(ConvertOptions, CrossTheProcessBoundary) {
    nurbsrt::ConvertOptions o;
    o.step_schema = nurbsrt::StepSchema::ap242;
    o.iges_mode = nurbsrt::IgesMode::faces;
    o.units = nurbsrt::LengthUnit::inch;
    o.deflection = 0.0123;
    o.angular_deflection = 0.1 + 1e-16 * 3;  // every digit crosses
    const nurbsrt::ConvertOptions back = nurbsrt::convert_options_from_args(nurbsrt::convert_options_to_args(o));
    EXPECT_EQ(back.step_schema, o.step_schema);
    EXPECT_EQ(back.iges_mode, o.iges_mode);
    EXPECT_EQ(back.units, o.units);
    EXPECT_EQ(back.deflection, o.deflection);
    EXPECT_EQ(back.angular_deflection, o.angular_deflection);
    EXPECT_THROW(nurbsrt::convert_options_from_args({"--step-schema=ap203"}), nurbsrt::Error);
    EXPECT_THROW(nurbsrt::convert_options_from_args({"--angular-deflection=x"}), nurbsrt::Error);
    nurbsrt::IsolationLimits limits;
    limits.worker_executable = NURBSRT_BINARY;
    const std::string out = out_path("iso-242.step");
    nurbsrt::ConvertOptions ap242;
    ap242.step_schema = nurbsrt::StepSchema::ap242;
    nurbsrt::convert_isolated(nurbsrt::test::box_with_holes(), out, limits, nullptr, ap242);
    EXPECT_NE(read_text(out).find("AP242"), std::string::npos);
}

}  // namespace
