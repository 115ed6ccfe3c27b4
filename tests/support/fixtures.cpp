#include "tests/support/fixtures.h"

#include <BRepAlgoAPI_Cut.hxx>
#include <BRepAlgoAPI_Fuse.hxx>
#include <BRepBuilderAPI_MakePolygon.hxx>
#include <BRepBuilderAPI_Transform.hxx>
#include <BRepOffsetAPI_ThruSections.hxx>
#include <BRepBuilderAPI_MakeEdge.hxx>
#include <BRep_Builder.hxx>
#include <TopoDS_Compound.hxx>
#include <gp_Circ.hxx>
#include <gp_Pln.hxx>
#include <BRepBuilderAPI_MakeFace.hxx>
#include <BRepBuilderAPI_MakeWire.hxx>
#include <BRepCheck_Analyzer.hxx>
#include <BRepClass_FaceClassifier.hxx>
#include <BRepFilletAPI_MakeFillet.hxx>
#include <BRepLib.hxx>
#include <BRep_Tool.hxx>
#include <Geom_Curve.hxx>
#include <gp_Ax1.hxx>
#include <BRepPrimAPI_MakeBox.hxx>
#include <BRepPrimAPI_MakeCone.hxx>
#include <BRepPrimAPI_MakeCylinder.hxx>
#include <BRepPrimAPI_MakeSphere.hxx>
#include <BRepPrimAPI_MakeTorus.hxx>
#include <Geom2d_Circle.hxx>
#include <Geom2d_Ellipse.hxx>
#include <Geom_BSplineSurface.hxx>
#include <IGESControl_Controller.hxx>
#include <IGESControl_Writer.hxx>
#include <Message.hxx>
#include <Message_Messenger.hxx>
#include <Message_PrinterOStream.hxx>
#include <Precision.hxx>
#include <Quantity_Color.hxx>
#include <STEPCAFControl_Writer.hxx>
#include <STEPControl_Reader.hxx>
#include <STEPControl_Writer.hxx>
#include <ShapeFix_Face.hxx>
#include <Standard_Failure.hxx>
#include <TColStd_Array1OfInteger.hxx>
#include <TColStd_Array1OfReal.hxx>
#include <TColStd_Array2OfReal.hxx>
#include <TColgp_Array2OfPnt.hxx>
#include <TDataStd_Name.hxx>
#include <TDocStd_Document.hxx>
#include <TopExp_Explorer.hxx>
#include <TopTools_ListOfShape.hxx>
#include <TopoDS.hxx>
#include <XCAFApp_Application.hxx>
#include <XCAFDoc_ColorTool.hxx>
#include <XCAFDoc_DocumentTool.hxx>
#include <XCAFDoc_ShapeTool.hxx>
#include <gp_Ax2.hxx>
#include <gp_Ax2d.hxx>
#include <gp_Trsf.hxx>

#include <stdlib.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <functional>
#include <map>
#include <mutex>
#include <stdexcept>

namespace nurbsrt::test {
namespace {

namespace fs = std::filesystem;

// The process's fixture directory; removed at exit (static destructor).
struct FixtureDir {
    std::string path;
    FixtureDir() {
        // OCCT readers/writers print progress to stdout; keep test output readable.
        Message::DefaultMessenger()->RemovePrinters(STANDARD_TYPE(Message_PrinterOStream));
        std::string templ = (fs::temp_directory_path() / "nurbsrt-fixtures-XXXXXX").string();
        if (!::mkdtemp(templ.data())) throw std::runtime_error("mkdtemp failed for " + templ);
        path = templ;
    }
    ~FixtureDir() {
        std::error_code ec;
        fs::remove_all(path, ec);
    }
};

FixtureDir& dir() {
    static FixtureDir d;
    return d;
}

std::mutex g_mutex;                          // fixtures may be requested from helper threads
std::map<std::string, std::string> g_cache;  // name -> path

void write_step(const TopoDS_Shape& shape, const std::string& path) {
    STEPControl_Writer w;
    if (w.Transfer(shape, STEPControl_AsIs) != IFSelect_RetDone || w.Write(path.c_str()) != IFSelect_RetDone)
        throw std::runtime_error("fixture: STEP write failed: " + path);
}

// Generates `name` once; `make` writes the file at the path it is given.
std::string cached(const std::string& name, const std::string& file,
                   const std::function<void(const std::string&)>& make) {
    std::lock_guard<std::mutex> lock(g_mutex);
    auto it = g_cache.find(name);
    if (it != g_cache.end()) return it->second;
    const std::string path = (fs::path(dir().path) / file).string();
    try {
        make(path);
    } catch (const Standard_Failure& e) {
        throw std::runtime_error("fixture " + name + ": OCCT failure: " + e.GetMessageString());
    }
    g_cache.emplace(name, path);
    return path;
}

std::string step_fixture(const std::string& name, const std::function<TopoDS_Shape()>& make) {
    return cached(name, name + ".step", [&](const std::string& path) {
        const TopoDS_Shape s = make();
        if (s.IsNull() || !BRepCheck_Analyzer(s).IsValid())
            throw std::runtime_error("fixture " + name + ": invalid shape");
        write_step(s, path);
    });
}

TopoDS_Shape make_box_with_holes() {
    TopoDS_Shape box = BRepPrimAPI_MakeBox(60.0, 40.0, 20.0).Shape();
    // Holes longer than the box so that the cut leaves clean through-holes.
    const TopoDS_Shape h1 = BRepPrimAPI_MakeCylinder(gp_Ax2(gp_Pnt(15, 20, -1), gp::DZ()), 5.0, 22.0).Shape();
    const TopoDS_Shape h2 = BRepPrimAPI_MakeCylinder(gp_Ax2(gp_Pnt(42, 20, -1), gp::DZ()), 7.0, 22.0).Shape();
    BRepAlgoAPI_Cut c1(box, h1);
    BRepAlgoAPI_Cut c2(c1.Shape(), h2);
    if (!c2.IsDone()) throw std::runtime_error("box_with_holes: cut failed");
    return c2.Shape();
}

TopoDS_Shape make_filleted_box() {
    const TopoDS_Shape box = BRepPrimAPI_MakeBox(40.0, 30.0, 20.0).Shape();
    BRepFilletAPI_MakeFillet f(box);
    for (TopExp_Explorer ex(box, TopAbs_EDGE); ex.More(); ex.Next()) f.Add(4.0, TopoDS::Edge(ex.Current()));
    f.Build();
    if (!f.IsDone()) throw std::runtime_error("filleted_box: fillet failed");
    return f.Shape();
}

// filleted_box with a through-hole of radius 6 along Z, cut after the fillets
// (the hole's rims are sharp edges on the flat tops, the box's edges blends).
TopoDS_Shape make_holed_filleted_box() {
    const TopoDS_Shape hole = BRepPrimAPI_MakeCylinder(gp_Ax2(gp_Pnt(20, 15, -1), gp::DZ()), 6.0, 22.0).Shape();
    BRepAlgoAPI_Cut cut(make_filleted_box(), hole);
    if (!cut.IsDone()) throw std::runtime_error("holed_filleted_box: cut failed");
    return cut.Shape();
}

// Fillet radius per edge direction of filleted_box_blend (x, y, z): three
// different radii meet at every corner, so OCCT builds a free-form vertex blend
// there instead of a sphere.
constexpr double kBlendRadii[3] = {2.0, 3.5, 5.0};

TopoDS_Shape make_filleted_box_blend() {
    const TopoDS_Shape box = BRepPrimAPI_MakeBox(40.0, 30.0, 20.0).Shape();
    BRepFilletAPI_MakeFillet f(box);
    for (TopExp_Explorer ex(box, TopAbs_EDGE); ex.More(); ex.Next()) {
        const TopoDS_Edge& e = TopoDS::Edge(ex.Current());
        double first = 0, last = 0;
        const Handle(Geom_Curve) c = BRep_Tool::Curve(e, first, last);
        const gp_Vec d(c->Value(first), c->Value(last));
        const int axis = std::fabs(d.X()) > 0.5 ? 0 : std::fabs(d.Y()) > 0.5 ? 1 : 2;
        f.Add(kBlendRadii[axis], e);
    }
    f.Build();
    if (!f.IsDone()) throw std::runtime_error("filleted_box_blend: fillet failed");
    return f.Shape();
}

// blade_fan: a hub with kBlades thin twisted blades. Each blade is lofted
// (BRepOffsetAPI_ThruSections, smooth: B-spline side faces) through rectangular
// sections kBladeChord x kBladeThickness whose chord turns by kBladeTwistDeg from
// root to tip, then all are fused with the hub, so every blade root is a trimmed
// edge on the hub. At 512 pixels the blades are 2-3 pixels thick edge-on.
constexpr int kBlades = 7;
constexpr double kHubRadius = 8.0, kHubHeight = 8.0;
constexpr double kBladeRoot = 6.0, kBladeTip = 38.0;  // radial extent (the root inside the hub)
constexpr double kBladeChord = 9.0, kBladeThickness = 0.6, kBladeTwistDeg = 50.0;

TopoDS_Shape make_blade() {
    BRepOffsetAPI_ThruSections loft(Standard_True, Standard_False);
    constexpr int kSections = 4;
    for (int s = 0; s < kSections; ++s) {
        const double f = static_cast<double>(s) / (kSections - 1);
        const double r = kBladeRoot + f * (kBladeTip - kBladeRoot);
        const double a = (15.0 + f * kBladeTwistDeg) * M_PI / 180.0;
        // Chord in the (y, z) plane at angle a; thickness across it. The chord
        // shrinks a little towards the tip, as a fan blade's does.
        const double hc = 0.5 * kBladeChord * (1.0 - 0.3 * f), ht = 0.5 * kBladeThickness;
        const gp_Vec ch(0, hc * std::cos(a), hc * std::sin(a)), th(0, -ht * std::sin(a), ht * std::cos(a));
        const gp_Pnt o(r, 0, 0);
        BRepBuilderAPI_MakePolygon p(o.Translated(ch + th), o.Translated(-ch + th), o.Translated(-ch - th),
                                     o.Translated(ch - th), Standard_True);
        loft.AddWire(p.Wire());
    }
    loft.Build();
    if (!loft.IsDone()) throw std::runtime_error("blade_fan: loft failed");
    return loft.Shape();
}

TopoDS_Shape make_blade_fan() {
    const TopoDS_Shape hub =
        BRepPrimAPI_MakeCylinder(gp_Ax2(gp_Pnt(0, 0, -0.5 * kHubHeight), gp::DZ()), kHubRadius, kHubHeight).Shape();
    const TopoDS_Shape blade = make_blade();
    TopTools_ListOfShape args, tools;
    args.Append(hub);
    for (int k = 0; k < kBlades; ++k) {
        gp_Trsf rot;
        rot.SetRotation(gp_Ax1(gp::Origin(), gp::DZ()), 2.0 * M_PI * k / kBlades);
        tools.Append(BRepBuilderAPI_Transform(blade, rot, Standard_True).Shape());
    }
    BRepAlgoAPI_Fuse fuse;
    fuse.SetArguments(args);
    fuse.SetTools(tools);
    fuse.Build();
    if (!fuse.IsDone()) throw std::runtime_error("blade_fan: fuse failed");
    return fuse.Shape();
}

// thin_ring (see the header): where the ring runs diagonally, the map shows it
// at every second or third pixel only, and the pixels between show the plate
// behind it (iges/marsCapsule.igs front had 68 such pixels).
TopoDS_Shape make_thin_ring() {
    const TopoDS_Shape plate = BRepPrimAPI_MakeBox(2 * kThinRingCentre, 4.0, 2 * kThinRingCentre).Shape();
    const gp_Ax2 axis(gp_Pnt(kThinRingCentre, -kThinRingGap, kThinRingCentre), gp_Dir(0, 1, 0));
    auto circle = [&](double r) {
        return BRepBuilderAPI_MakeWire(BRepBuilderAPI_MakeEdge(gp_Circ(axis, r)).Edge()).Wire();
    };
    BRepBuilderAPI_MakeFace ring(gp_Pln(axis.Location(), axis.Direction()), circle(kThinRingRadius + kThinRingWidth));
    ring.Add(TopoDS::Wire(circle(kThinRingRadius).Reversed()));
    if (!ring.IsDone()) throw std::runtime_error("thin_ring: face failed");
    ShapeFix_Face fix(ring.Face());
    fix.Perform();
    TopoDS_Compound both;
    BRep_Builder b;
    b.MakeCompound(both);
    b.Add(both, plate);
    b.Add(both, fix.Face());
    return both;
}

// The free-form net: 6 x 5 poles over x in [0, 20], y in [0, 12], with a smooth
// non-planar height field (values are fixed; no randomness).
Handle(Geom_BSplineSurface) make_freeform_surface(bool rational) {
    TColgp_Array2OfPnt poles(1, 6, 1, 5);
    TColStd_Array2OfReal weights(1, 6, 1, 5);
    for (int i = 1; i <= 6; ++i)
        for (int j = 1; j <= 5; ++j) {
            const double z = 3.0 * std::sin(0.9 * i) * std::cos(0.7 * j) + 0.2 * i * j;
            poles(i, j) = gp_Pnt(4.0 * (i - 1), 3.0 * (j - 1), z);
            // Weights in [0.4, 2.5], varying in both directions.
            weights(i, j) = 0.4 + 2.1 * (0.5 + 0.5 * std::sin(1.3 * i + 0.8 * j));
        }
    // u: degree 3, knots 0, 8 (double), 20 -> 4 + 2 + 4 = 10 = 6 + 3 + 1.
    TColStd_Array1OfReal uk(1, 3);
    TColStd_Array1OfInteger um(1, 3);
    uk(1) = 0.0;
    uk(2) = 8.0;
    uk(3) = 20.0;
    um(1) = 4;
    um(2) = 2;
    um(3) = 4;
    // v: degree 3, knots -1, 0.5, 3 -> 4 + 1 + 4 = 9 = 5 + 3 + 1.
    TColStd_Array1OfReal vk(1, 3);
    TColStd_Array1OfInteger vm(1, 3);
    vk(1) = -1.0;
    vk(2) = 0.5;
    vk(3) = 3.0;
    vm(1) = 4;
    vm(2) = 1;
    vm(3) = 4;
    if (rational) return new Geom_BSplineSurface(poles, weights, uk, vk, um, vm, 3, 3);
    return new Geom_BSplineSurface(poles, uk, vk, um, vm, 3, 3);
}

// A face on `surf` (natural boundary) with `hole` (a closed 2D curve in its
// parameter space) as an inner trim loop. Self-checked with BRepClass: the
// hole's centre must classify OUT and a point near the box corner IN.
TopoDS_Face make_face_with_hole(const Handle(Geom_BSplineSurface) & surf, const Handle(Geom2d_Curve) & hole,
                                const gp_Pnt2d& hole_centre) {
    const TopoDS_Face outer = BRepBuilderAPI_MakeFace(surf, Precision::Confusion()).Face();
    TopoDS_Edge e = BRepBuilderAPI_MakeEdge(hole, surf).Edge();
    BRepLib::BuildCurves3d(e);
    const TopoDS_Wire w = BRepBuilderAPI_MakeWire(e).Wire();
    BRepBuilderAPI_MakeFace mf(outer);
    mf.Add(TopoDS::Wire(w.Reversed()));  // inner loop runs clockwise in (u,v)
    ShapeFix_Face fix(mf.Face());        // fixes the orientation should the guess be wrong
    fix.Perform();
    const TopoDS_Face face = fix.Face();
    double u0, u1, v0, v1;
    surf->Bounds(u0, u1, v0, v1);
    const gp_Pnt2d corner(u0 + 0.01 * (u1 - u0), v0 + 0.01 * (v1 - v0));
    if (BRepClass_FaceClassifier(face, hole_centre, 1e-9).State() != TopAbs_OUT ||
        BRepClass_FaceClassifier(face, corner, 1e-9).State() != TopAbs_IN)
        throw std::runtime_error("freeform fixture: hole is not a hole");
    return face;
}

TopoDS_Shape make_assembly_part() {
    const TopoDS_Shape box = BRepPrimAPI_MakeBox(30.0, 20.0, 10.0).Shape();
    const TopoDS_Shape hole = BRepPrimAPI_MakeCylinder(gp_Ax2(gp_Pnt(15, 10, -1), gp::DZ()), 4.0, 12.0).Shape();
    BRepAlgoAPI_Cut cut(box, hole);
    if (!cut.IsDone()) throw std::runtime_error("assembly part: cut failed");
    return cut.Shape();
}

void write_assembly(const std::string& path) {
    Handle(XCAFApp_Application) app = XCAFApp_Application::GetApplication();
    Handle(TDocStd_Document) doc;
    app->NewDocument("MDTV-XCAF", doc);
    Handle(XCAFDoc_ShapeTool) shapes = XCAFDoc_DocumentTool::ShapeTool(doc->Main());
    Handle(XCAFDoc_ColorTool) colors = XCAFDoc_DocumentTool::ColorTool(doc->Main());

    const TDF_Label part = shapes->AddShape(make_assembly_part(), Standard_False);
    TDataStd_Name::Set(part, TCollection_ExtendedString(kAssemblyPartName));
    colors->SetColor(part, Quantity_Color(kAssemblyColor.r, kAssemblyColor.g, kAssemblyColor.b, Quantity_TOC_RGB),
                     XCAFDoc_ColorSurf);

    const TDF_Label assy = shapes->NewShape();
    TDataStd_Name::Set(assy, TCollection_ExtendedString("two_brackets"));
    for (int k = 0; k < 2; ++k) {
        gp_Trsf t;
        t.SetTranslation(gp_Vec(kAssemblyOffsets[k].x, kAssemblyOffsets[k].y, kAssemblyOffsets[k].z));
        const TDF_Label comp = shapes->AddComponent(assy, part, TopLoc_Location(t));
        TDataStd_Name::Set(comp, TCollection_ExtendedString(kAssemblyInstanceNames[k]));
    }
    shapes->UpdateAssemblies();

    STEPCAFControl_Writer w;
    w.SetColorMode(Standard_True);
    w.SetNameMode(Standard_True);
    const bool ok = w.Transfer(doc, STEPControl_AsIs) && w.Write(path.c_str()) == IFSelect_RetDone;
    app->Close(doc);
    if (!ok) throw std::runtime_error("assembly: STEP write failed");
}

struct Named {
    const char* name;
    std::string (*make)();
};
const Named kFixtures[] = {
    {"box_with_holes", box_with_holes},
    {"filleted_box", filleted_box},
    {"cylinder", cylinder},
    {"sphere", sphere},
    {"cone", cone},
    {"torus", torus},
    {"freeform_bspline", freeform_bspline},
    {"freeform_rational", freeform_rational},
    {"assembly", assembly},
    {"filleted_box_blend", filleted_box_blend},
    {"blade_fan", blade_fan},
    {"thin_ring", thin_ring},
};
// Fixtures that also get an IGES copy ("<name>_iges").
const char* const kIgesFixtures[] = {"box_with_holes", "filleted_box",     "cylinder",         "sphere",
                                     "torus",          "freeform_bspline", "freeform_rational"};

}  // namespace

std::string fixture_dir() { return dir().path; }

std::string box_with_holes() { return step_fixture("box_with_holes", make_box_with_holes); }
std::string filleted_box() { return step_fixture("filleted_box", make_filleted_box); }
std::string filleted_box_blend() { return step_fixture("filleted_box_blend", make_filleted_box_blend); }
std::string holed_filleted_box() { return step_fixture("holed_filleted_box", make_holed_filleted_box); }
std::string blade_fan() { return step_fixture("blade_fan", make_blade_fan); }
std::string thin_ring() { return step_fixture("thin_ring", make_thin_ring); }
std::string cylinder() {
    return step_fixture("cylinder", [] { return BRepPrimAPI_MakeCylinder(10.0, 30.0).Shape(); });
}
std::string sphere() {
    return step_fixture("sphere", [] { return BRepPrimAPI_MakeSphere(15.0).Shape(); });
}
std::string cone() {
    return step_fixture("cone", [] { return BRepPrimAPI_MakeCone(12.0, 4.0, 25.0).Shape(); });
}
std::string torus() {
    return step_fixture("torus", [] { return BRepPrimAPI_MakeTorus(20.0, 6.0).Shape(); });
}
std::string elongated_rod() {
    return step_fixture("elongated_rod", [] {
        return BRepPrimAPI_MakeCylinder(gp_Ax2(gp_Pnt(0, 0, 0), gp_Dir(1.0, 0.25, 0.1)), 4.0, 120.0).Shape();
    });
}
std::string freeform_bspline() {
    return step_fixture("freeform_bspline", [] {
        Handle(Geom2d_Circle) c = new Geom2d_Circle(gp_Ax2d(gp_Pnt2d(10.0, 1.0), gp_Dir2d(1, 0)), 1.2);
        return make_face_with_hole(make_freeform_surface(false), c, gp_Pnt2d(10.0, 1.0));
    });
}
std::string freeform_rational() {
    return step_fixture("freeform_rational", [] {
        Handle(Geom2d_Ellipse) e = new Geom2d_Ellipse(gp_Ax2d(gp_Pnt2d(6.0, 1.5), gp_Dir2d(1, 0)), 3.0, 0.8);
        return make_face_with_hole(make_freeform_surface(true), e, gp_Pnt2d(6.0, 1.5));
    });
}
std::string assembly() { return cached("assembly", "assembly.step", write_assembly); }
std::string cube10() {
    return step_fixture("cube10", [] {
        return BRepPrimAPI_MakeBox(gp_Pnt(kCube10Corner.x, kCube10Corner.y, kCube10Corner.z), 10.0, 10.0, 10.0).Shape();
    });
}

std::string dense_bspline(int degree, int poles) {
    if (degree < 1 || degree > Geom_BSplineSurface::MaxDegree() || poles <= degree)
        throw std::invalid_argument("dense_bspline: need 1 <= degree <= 25 and poles > degree");
    const std::string name = "dense_bspline_" + std::to_string(degree) + "_" + std::to_string(poles);
    return step_fixture(name, [&] {
        TColgp_Array2OfPnt net(1, poles, 1, poles);
        const double step = 100.0 / (poles - 1);
        for (int i = 1; i <= poles; ++i)
            for (int j = 1; j <= poles; ++j)
                net(i, j) = gp_Pnt(step * (i - 1), step * (j - 1), 8.0 * std::sin(0.21 * i) * std::cos(0.17 * j));
        // Clamped uniform knots: end multiplicity degree+1, interior 1, so
        // poles - degree + 1 distinct values (Piegl & Tiller eq. 2.13).
        const int distinct = poles - degree + 1;
        TColStd_Array1OfReal knots(1, distinct);
        TColStd_Array1OfInteger mults(1, distinct);
        for (int k = 1; k <= distinct; ++k) {
            knots(k) = double(k - 1) / (distinct - 1);
            mults(k) = (k == 1 || k == distinct) ? degree + 1 : 1;
        }
        Handle(Geom_BSplineSurface) s = new Geom_BSplineSurface(net, knots, knots, mults, mults, degree, degree);
        return TopoDS_Shape(BRepBuilderAPI_MakeFace(s, Precision::Confusion()).Face());
    });
}

std::string to_iges(const std::string& step_path) {
    const std::string name = "iges:" + step_path;
    const std::string file = fs::path(step_path).stem().string() + "_" +
                             std::to_string(std::hash<std::string>{}(step_path) % 100000) + ".igs";
    return cached(name, file, [&](const std::string& path) {
        STEPControl_Reader r;
        if (r.ReadFile(step_path.c_str()) != IFSelect_RetDone || r.TransferRoots() == 0)
            throw std::runtime_error("to_iges: cannot read " + step_path);
        IGESControl_Controller::Init();
        IGESControl_Writer w("MM", 1);  // 1 = BRep mode (MSBO/shell/face entities)
        if (!w.AddShape(r.OneShape())) throw std::runtime_error("to_iges: AddShape failed");
        w.ComputeModel();
        if (!w.Write(path.c_str())) throw std::runtime_error("to_iges: write failed: " + path);
    });
}

std::vector<std::string> fixture_names() {
    std::vector<std::string> names;
    for (const Named& f : kFixtures) names.push_back(f.name);
    for (const char* n : kIgesFixtures) names.push_back(std::string(n) + "_iges");
    return names;
}

std::string fixture_by_name(const std::string& name) {
    if (name == "cube10") return cube10();
    for (const Named& f : kFixtures)
        if (name == f.name) return f.make();
    const std::string suffix = "_iges";
    if (name.size() > suffix.size() && name.compare(name.size() - suffix.size(), suffix.size(), suffix) == 0) {
        const std::string base = name.substr(0, name.size() - suffix.size());
        for (const char* n : kIgesFixtures)
            if (base == n) return to_iges(fixture_by_name(base));
    }
    throw std::invalid_argument("unknown fixture: " + name);
}

std::string shared_models_dir() {
    std::string d;
    if (const char* env = std::getenv("NURBSRT_MODELS"); env && *env)
        d = env;
    else
        d = std::string(NURBSRT_SOURCE_DIR) + "/../shared/models";
    std::error_code ec;
    if (!fs::is_directory(d, ec)) return "";
    return fs::weakly_canonical(d, ec).string();
}

std::vector<std::string> shared_model_files(const std::string& subdir) {
    std::vector<std::string> out;
    const std::string root = shared_models_dir();
    if (root.empty()) return out;
    std::error_code ec;
    for (const auto& entry : fs::directory_iterator(fs::path(root) / subdir, ec)) {
        if (!entry.is_regular_file()) continue;
        std::string ext = entry.path().extension().string();
        for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
        if (ext == ".stp" || ext == ".step" || ext == ".igs" || ext == ".iges") out.push_back(entry.path().string());
    }
    std::sort(out.begin(), out.end());
    return out;
}

std::string shared_model(const std::string& relative) {
    const std::string root = shared_models_dir();
    return root.empty() ? "" : root + "/" + relative;
}

std::string sanitize_test_name(const std::string& s) {
    std::string out;
    for (char c : s) out += std::isalnum(static_cast<unsigned char>(c)) ? c : '_';
    return out;
}

}  // namespace nurbsrt::test
