// convert_file to STEP and IGES keeps what the XDE document carries: face
// colours, names and (STEP only) the assembly structure.
//
// The fixture is a coloured assembly built here with XCAFDoc_ShapeTool and
// XCAFDoc_ColorTool and written with STEPCAFControl_Writer: a plate part (box,
// 6 faces, two of them coloured per face) placed twice, and a pin part
// (cylinder, 3 faces, coloured as a whole) in a named sub-assembly, every part,
// assembly and component named. Each conversion result is read back with
// OCCT's XDE readers, independently of the project's reader, and compared:
//  * StepToStep:     same coloured face occurrences (same colours), same names
//                    and the same product tree (assemblies, components, parts,
//                    instance counts); no warnings.
//  * StepToIgesToStep: IGES keeps the coloured faces (same colours); the tree
//                    becomes one root named as the top assembly, the report
//                    says so and quotes exactly the names that were lost (OCCT's
//                    IGES writer keeps some instance names as names of the
//                    flat compound's solids); back in STEP those members are
//                    parts of an assembly again, under their IGES names.
//  * Real models (../shared/models, skipped visibly when absent): the CAx-IF
//    AS1 assembly keeps its coloured faces through STEP->STEP and
//    STEP->IGES->STEP, the AS1 IGES file through IGES->STEP.
#include <gtest/gtest.h>

#include <BRepPrimAPI_MakeBox.hxx>
#include <BRepPrimAPI_MakeCylinder.hxx>
#include <IFSelect_ReturnStatus.hxx>
#include <IGESCAFControl_Reader.hxx>
#include <Quantity_Color.hxx>
#include <STEPCAFControl_Reader.hxx>
#include <STEPCAFControl_Writer.hxx>
#include <TDF_ChildIterator.hxx>
#include <TDF_Label.hxx>
#include <TDF_LabelSequence.hxx>
#include <TDataStd_Name.hxx>
#include <TDocStd_Document.hxx>
#include <TopExp_Explorer.hxx>
#include <TopoDS.hxx>
#include <XCAFApp_Application.hxx>
#include <XCAFDoc_ColorTool.hxx>
#include <XCAFDoc_DocumentTool.hxx>
#include <XCAFDoc_ShapeTool.hxx>
#include <XCAFPrs_DocumentExplorer.hxx>
#include <gp_Trsf.hxx>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <set>
#include <string>
#include <vector>

#include "importer/importer.h"
#include "tests/support/fixtures.h"

namespace {

using Rgb = std::array<double, 3>;
constexpr Rgb kPlateTop{0.9, 0.1, 0.1};
constexpr Rgb kPlateSide{0.1, 0.8, 0.2};
constexpr Rgb kPin{0.1, 0.2, 0.9};
constexpr int kPlateFaces = 6, kPinFaces = 3;
// Faces: 2 plates + 1 pin; coloured: 2 per plate (top, one side), the whole pin.
constexpr int kFixtureFaces = 2 * kPlateFaces + kPinFaces;
constexpr int kFixtureColouredFaces = 2 * 2 + kPinFaces;

std::string out_path(const std::string& name) { return nurbsrt::test::fixture_dir() + "/xde-" + name; }

Quantity_Color to_quantity(const Rgb& c) { return Quantity_Color(c[0], c[1], c[2], Quantity_TOC_RGB); }

TDF_Label named(const TDF_Label& l, const char* name) {
    TDataStd_Name::Set(l, TCollection_ExtendedString(name));
    return l;
}

TopLoc_Location translation(double x, double y, double z) {
    gp_Trsf t;
    t.SetTranslation(gp_Vec(x, y, z));
    return TopLoc_Location(t);
}

// The fixture described at the top, written once per process.
std::string coloured_assembly() {
    static const std::string path = [] {
        const std::string p = out_path("coloured_assembly.step");
        Handle(XCAFApp_Application) app = XCAFApp_Application::GetApplication();
        Handle(TDocStd_Document) doc;
        app->NewDocument("MDTV-XCAF", doc);
        Handle(XCAFDoc_ShapeTool) shapes = XCAFDoc_DocumentTool::ShapeTool(doc->Main());
        Handle(XCAFDoc_ColorTool) colors = XCAFDoc_DocumentTool::ColorTool(doc->Main());

        const TopoDS_Shape box = BRepPrimAPI_MakeBox(30.0, 20.0, 5.0).Shape();
        const TDF_Label plate = named(shapes->AddShape(box, Standard_False), "plate");
        // BRepPrimAPI_MakeBox's faces in explorer order: x-, x+, y-, y+, z-, z+.
        std::vector<TopoDS_Face> faces;
        for (TopExp_Explorer ex(box, TopAbs_FACE); ex.More(); ex.Next()) faces.push_back(TopoDS::Face(ex.Current()));
        colors->SetColor(shapes->AddSubShape(plate, faces[5]), to_quantity(kPlateTop), XCAFDoc_ColorSurf);
        colors->SetColor(shapes->AddSubShape(plate, faces[0]), to_quantity(kPlateSide), XCAFDoc_ColorSurf);

        const TDF_Label pin =
            named(shapes->AddShape(BRepPrimAPI_MakeCylinder(3.0, 15.0).Shape(), Standard_False), "pin");
        colors->SetColor(pin, to_quantity(kPin), XCAFDoc_ColorSurf);

        const TDF_Label pins = named(shapes->NewShape(), "pin_group");
        named(shapes->AddComponent(pins, pin, translation(15, 10, 5)), "pin_1");
        const TDF_Label top = named(shapes->NewShape(), "fixture_top");
        named(shapes->AddComponent(top, plate, translation(0, 0, 0)), "plate_lower");
        named(shapes->AddComponent(top, plate, translation(0, 0, 40)), "plate_upper");
        named(shapes->AddComponent(top, pins, translation(0, 0, 0)), "pins_1");
        shapes->UpdateAssemblies();

        STEPCAFControl_Writer w;
        w.SetColorMode(Standard_True);
        w.SetNameMode(Standard_True);
        const bool ok = w.Transfer(doc, STEPControl_AsIs) && w.Write(p.c_str()) == IFSelect_RetDone;
        app->Close(doc);
        if (!ok) throw std::runtime_error("coloured assembly: STEP write failed");
        return p;
    }();
    return path;
}

std::string name_of(const TDF_Label& l) {
    Handle(TDataStd_Name) n;
    if (!l.FindAttribute(TDataStd_Name::GetID(), n)) return {};
    return TCollection_AsciiString(n->Get()).ToCString();
}

// What a file holds, read with OCCT's XDE readers.
struct Xde {
    int faces = 0;                    // face occurrences
    std::vector<Rgb> coloured;        // colour of each coloured face occurrence, sorted
    std::set<std::string> names;      // all names on shape labels (parts, assemblies, components)
    std::set<std::string> sub_names;  // names on sub-shape labels of parts (a flat IGES
                                      // compound's solids carry the instance names there)
    std::set<std::string> all_names() const {
        std::set<std::string> all = names;
        all.insert(sub_names.begin(), sub_names.end());
        return all;
    }
    std::string tree;                    // the product tree, children sorted
    int assemblies = 0, components = 0;  // over the expanded tree
};

bool colour_of(const Handle(XCAFDoc_ColorTool) & colors, const TDF_Label& l, Quantity_Color& c) {
    return colors->GetColor(l, XCAFDoc_ColorSurf, c) || colors->GetColor(l, XCAFDoc_ColorGen, c);
}

std::string describe(const TDF_Label& def, Xde& x) {
    std::string name = name_of(def);
    if (!name.empty()) x.names.insert(name);
    if (!XCAFDoc_ShapeTool::IsAssembly(def)) {
        for (TDF_ChildIterator ci(def); ci.More(); ci.Next())
            if (std::string n = name_of(ci.Value()); !n.empty()) x.sub_names.insert(n);
        return name;
    }
    ++x.assemblies;
    TDF_LabelSequence comps;
    XCAFDoc_ShapeTool::GetComponents(def, comps, Standard_False);
    std::vector<std::string> children;
    for (const TDF_Label& comp : comps) {
        ++x.components;
        const std::string cname = name_of(comp);
        if (!cname.empty()) x.names.insert(cname);
        TDF_Label ref;
        XCAFDoc_ShapeTool::GetReferredShape(comp, ref);
        children.push_back(cname + ":" + describe(ref, x));
    }
    std::sort(children.begin(), children.end());
    std::string s = name + "{";
    for (const std::string& c : children) s += c + ";";
    return s + "}";
}

Xde read_xde(const std::string& path) {
    Handle(XCAFApp_Application) app = XCAFApp_Application::GetApplication();
    Handle(TDocStd_Document) doc;
    app->NewDocument("MDTV-XCAF", doc);
    const bool iges = path.size() > 4 && path.substr(path.size() - 4) == ".igs";
    bool ok = false;
    if (iges) {
        IGESCAFControl_Reader r;
        r.SetColorMode(true);
        r.SetNameMode(true);
        ok = r.ReadFile(path.c_str()) == IFSelect_RetDone && r.Transfer(doc);
    } else {
        STEPCAFControl_Reader r;
        r.SetColorMode(true);
        r.SetNameMode(true);
        ok = r.ReadFile(path.c_str()) == IFSelect_RetDone && r.Transfer(doc);
    }
    Xde x;
    if (!ok) {
        app->Close(doc);
        ADD_FAILURE() << "XDE cannot read " << path;
        return x;
    }
    Handle(XCAFDoc_ShapeTool) shapes = XCAFDoc_DocumentTool::ShapeTool(doc->Main());
    Handle(XCAFDoc_ColorTool) colors = XCAFDoc_DocumentTool::ColorTool(doc->Main());
    TDF_LabelSequence roots;
    shapes->GetFreeShapes(roots);
    std::vector<std::string> trees;
    for (const TDF_Label& root : roots) trees.push_back(describe(root, x));
    std::sort(trees.begin(), trees.end());
    for (const std::string& t : trees) x.tree += t + "\n";

    // Each face occurrence: its own colour (a face sub-shape label of the
    // part), else the colour the occurrence inherits (part, instance, parents).
    for (XCAFPrs_DocumentExplorer ex(doc, XCAFPrs_DocumentExplorerFlags_OnlyLeafNodes); ex.More(); ex.Next()) {
        const XCAFPrs_DocumentNode& node = ex.Current();
        const TopoDS_Shape part = XCAFDoc_ShapeTool::GetShape(node.RefLabel);
        for (TopExp_Explorer fe(part, TopAbs_FACE); fe.More(); fe.Next()) {
            ++x.faces;
            Quantity_Color c;
            TDF_Label sub;
            bool has = shapes->FindSubShape(node.RefLabel, fe.Current(), sub) && colour_of(colors, sub, c);
            if (!has && node.Style.IsSetColorSurf()) {
                c = node.Style.GetColorSurf();
                has = true;
            }
            if (has) x.coloured.push_back({c.Red(), c.Green(), c.Blue()});
        }
    }
    std::sort(x.coloured.begin(), x.coloured.end());
    app->Close(doc);
    return x;
}

// The same colours within 8-bit resolution, face by face (both sorted).
void expect_same_colours(const Xde& a, const Xde& b, const std::string& what) {
    ASSERT_EQ(a.coloured.size(), b.coloured.size()) << what;
    for (size_t i = 0; i < a.coloured.size(); ++i)
        for (int k = 0; k < 3; ++k)
            EXPECT_NEAR(a.coloured[i][k], b.coloured[i][k], 1.0 / 255) << what << ", coloured face " << i;
}

bool mentions(const std::vector<std::string>& warnings, const std::string& s) {
    return std::any_of(warnings.begin(), warnings.end(),
                       [&](const std::string& w) { return w.find(s) != std::string::npos; });
}

std::string joined(const std::vector<std::string>& w) {
    std::string s;
    for (const std::string& x : w) s += "\n  " + x;
    return s;
}

// Every name of `in` missing from `out` is quoted in a warning, and no name
// `out` still has is (the fixture's losses fit in one warning's list). "FACE"
// is no name of the file: OCCT's IGES reader gives it to the labels it makes
// for coloured faces (XCAFDoc_ShapeTool's auto-naming after the shape type).
void expect_lost_names_listed(const Xde& in, const Xde& out, const std::vector<std::string>& warnings,
                              const std::string& what) {
    const std::set<std::string> kept = out.all_names();
    for (const std::string& n : in.all_names()) {
        if (n == "FACE") continue;
        if (kept.count(n))
            EXPECT_FALSE(mentions(warnings, "'" + n + "'")) << what << ": " << n << joined(warnings);
        else
            EXPECT_TRUE(mentions(warnings, "'" + n + "'")) << what << ": " << n << joined(warnings);
    }
}

TEST(ConvertXde, FixtureHasWhatItClaims) {
    const Xde in = read_xde(coloured_assembly());
    EXPECT_EQ(in.faces, kFixtureFaces);
    EXPECT_EQ(static_cast<int>(in.coloured.size()), kFixtureColouredFaces);
    EXPECT_EQ(in.assemblies, 2);
    EXPECT_EQ(in.components, 4);
    EXPECT_EQ(in.tree, "fixture_top{pins_1:pin_group{pin_1:pin;};plate_lower:plate;plate_upper:plate;}\n");
}

TEST(ConvertXde, StepToStepKeepsColoursNamesAndTree) {
    const std::string in = coloured_assembly();
    const std::string out = out_path("step-step.step");
    const nurbsrt::ConvertReport r = nurbsrt::convert_file(in, out);
    const Xde a = read_xde(in), b = read_xde(out);
    EXPECT_EQ(b.faces, a.faces);
    expect_same_colours(a, b, "STEP -> STEP");
    EXPECT_EQ(b.tree, a.tree);
    EXPECT_EQ(b.names, a.names);
    EXPECT_EQ(b.assemblies, a.assemblies);
    EXPECT_EQ(b.components, a.components);
    EXPECT_TRUE(r.warnings.empty()) << joined(r.warnings);
}

TEST(ConvertXde, StepToIgesToStepKeepsColouredFacesAndTheMembersNames) {
    const std::string in = coloured_assembly();
    const std::string igs = out_path("step-iges.igs");
    const std::string back = out_path("step-iges-step.step");
    const nurbsrt::ConvertReport r1 = nurbsrt::convert_file(in, igs);
    const nurbsrt::ConvertReport r2 = nurbsrt::convert_file(igs, back);
    const Xde a = read_xde(in), mid = read_xde(igs), b = read_xde(back);
    EXPECT_EQ(mid.faces, a.faces);
    EXPECT_EQ(b.faces, a.faces);
    expect_same_colours(a, mid, "STEP -> IGES");
    expect_same_colours(a, b, "STEP -> IGES -> STEP");
    EXPECT_EQ(mid.components, 0) << "IGES has no assembly structure";
    // The flattened tree is one IGES root named as the top assembly; its
    // members' names (OCCT's IGES writer names the instances' solids) make
    // IGES -> STEP an assembly again, one named part per member.
    EXPECT_EQ(mid.tree, "fixture_top\n");
    ASSERT_FALSE(mid.sub_names.empty());
    EXPECT_EQ(b.assemblies, 1);
    EXPECT_EQ(b.components, 3) << b.tree;
    for (const std::string& n : mid.sub_names) EXPECT_TRUE(b.names.count(n)) << n << " lost: " << b.tree;
    // 3 part instances: the plate twice, the pin once.
    EXPECT_TRUE(mentions(r1.warnings, "IGES has no assembly structure: 3 part instance(s)")) << joined(r1.warnings);
    EXPECT_FALSE(mentions(r1.warnings, "colour")) << joined(r1.warnings);
    // Names: each report lists exactly the names its output lost.
    expect_lost_names_listed(a, mid, r1.warnings, "STEP -> IGES");
    expect_lost_names_listed(mid, b, r2.warnings, "IGES -> STEP");
}

// A real coloured assembly: what OCCT's XDE reads from the input must arrive
// in the conversions' outputs (colours per face; the tree in STEP).
void check_real_model(const std::string& relative) {
    const std::string in = nurbsrt::test::shared_model(relative);
    if (in.empty()) GTEST_SKIP() << "../shared/models is absent: skipping " << relative;
    const Xde a = read_xde(in);
    ASSERT_GT(a.coloured.size(), 0u) << relative << " has no coloured faces";
    const std::string stem = nurbsrt::test::sanitize_test_name(relative);
    const std::string step = out_path(stem + ".step"), igs = out_path(stem + ".igs");
    const nurbsrt::ConvertReport r1 = nurbsrt::convert_file(in, step);
    const nurbsrt::ConvertReport r2 = nurbsrt::convert_file(in, igs);
    const Xde s = read_xde(step), i = read_xde(igs);
    std::printf("%s: %d faces, %zu coloured, %d components; -> STEP %zu coloured; -> IGES %zu coloured%s%s\n",
                relative.c_str(), a.faces, a.coloured.size(), a.components, s.coloured.size(), i.coloured.size(),
                joined(r1.warnings).c_str(), joined(r2.warnings).c_str());
    EXPECT_EQ(s.faces, a.faces);
    EXPECT_EQ(i.faces, a.faces);
    expect_same_colours(a, s, relative + " -> STEP");
    expect_same_colours(a, i, relative + " -> IGES");
    if (a.components > 0) {
        EXPECT_EQ(s.tree, a.tree);
        EXPECT_TRUE(mentions(r2.warnings, "IGES has no assembly structure")) << joined(r2.warnings);
    }
}

TEST(ConvertXde, RealStepAssemblyAs1KeepsColours) { check_real_model("step/as1-oc-214.stp"); }

// The AS1 assembly in IGES (as OCCT writes it: one flat compound whose solids
// carry the instance names) back to STEP: every name of a member is a part
// again. Names OCCT's reader makes up for unnamed shapes (their type, as
// "FACE" for a coloured face's label) are no names of the file.
TEST(ConvertXde, RealAs1IgesToStepKeepsPartNames) {
    const std::string in = nurbsrt::test::shared_model("step/as1-oc-214.stp");
    if (in.empty()) GTEST_SKIP() << "../shared/models is absent: skipping the AS1 assembly";
    const std::string igs = out_path("as1-names.igs"), back = out_path("as1-names-back.step");
    nurbsrt::convert_file(in, igs);
    const nurbsrt::ConvertReport r = nurbsrt::convert_file(igs, back);
    const Xde mid = read_xde(igs), b = read_xde(back);
    std::set<std::string> member_names;
    for (const std::string& n : mid.sub_names)
        if (n != "FACE") member_names.insert(n);
    // bolt_1, l-bracket_1, nut_1, nut_2, nut_3, plate_1, rod_1
    EXPECT_EQ(member_names.size(), 7u) << joined(std::vector<std::string>(member_names.begin(), member_names.end()));
    for (const std::string& n : member_names) EXPECT_TRUE(b.names.count(n)) << n << " lost: " << b.tree;
    EXPECT_FALSE(mentions(r.warnings, "name")) << joined(r.warnings);
    EXPECT_EQ(b.faces, mid.faces);
}
TEST(ConvertXde, RealStepAssemblyBoxSidesKeepsColours) { check_real_model("step/box_sides.STEP"); }

}  // namespace
