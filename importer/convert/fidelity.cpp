// The fidelity report of a conversion (convert_writers.h): the source and the
// output measured alike, by OCCT, and compared; differences past the
// tolerances below become warnings.
#include <algorithm>
#include <cmath>

#include <BRepBndLib.hxx>
#include <BRepCheck_Analyzer.hxx>
#include <BRepGProp.hxx>
#include <BRep_Tool.hxx>
#include <Bnd_Box.hxx>
#include <GProp_GProps.hxx>
#include <Poly_Triangulation.hxx>
#include <Standard_Failure.hxx>
#include <TopExp.hxx>
#include <TopExp_Explorer.hxx>
#include <TopLoc_Location.hxx>
#include <TopTools_IndexedMapOfShape.hxx>
#include <TopoDS.hxx>

#include "importer/convert/convert_writers.h"

namespace nurbsrt::occt {
namespace {

// Exact formats write coordinates with 15 to 17 significant digits: a volume,
// area or box that moves by more than this, relative to its size, is a changed
// model (the same bound the round trips of the tests hold to).
constexpr double kExactTolerance = 1e-6;
// A mesh's chords cut inside curved faces: at the default deflection (0.002 of
// the diagonal) the sphere's mesh measured 0.5% less area and 1% less volume,
// the most of the test fixtures. Five times that is a mesh far coarser than
// the default, or faces missing, doubled or turned inside out.
constexpr double kMeshMeasureTolerance = 0.05;
// A mesh vertex or centroid this far from its exact face, relative to the
// model's diagonal, is a step a whole-model view shows (10 pixels of a
// 1000-pixel image); at the default deflection the fixtures measured at most
// 0.0033 (the sphere's centroids), the CAx-IF as1 assembly 8e-5.
constexpr double kMeshDeviationTolerance = 0.01;

int count(const TopoDS_Shape& s, TopAbs_ShapeEnum type) {
    TopTools_IndexedMapOfShape map;
    TopExp::MapShapes(s, type, map);
    return map.Extent();
}

nlohmann::ordered_json box_json(const std::array<double, 6>& b) {
    return {{"min", {b[0], b[1], b[2]}}, {"max", {b[3], b[4], b[5]}}};
}

double diagonal(const std::array<double, 6>& b) {
    return std::sqrt((b[3] - b[0]) * (b[3] - b[0]) + (b[4] - b[1]) * (b[4] - b[1]) + (b[5] - b[2]) * (b[5] - b[2]));
}

// |a - b| / max(|a|, |b|), 0 when they are equal (both 0 included).
double relative(double a, double b) {
    if (a == b) return 0.0;
    return std::abs(a - b) / std::max(std::abs(a), std::abs(b));
}

// The largest move of a box corner coordinate, relative to the source's diagonal.
double box_difference(const std::array<double, 6>& a, const std::array<double, 6>& b) {
    double d = 0;
    for (size_t i = 0; i < 6; ++i) d = std::max(d, std::abs(a[i] - b[i]));
    const double diag = diagonal(a);
    return diag > 0 ? d / diag : d;
}

std::array<double, 6> to_array(const Bnd_Box& box) {
    std::array<double, 6> b{};
    if (!box.IsVoid()) box.Get(b[0], b[1], b[2], b[3], b[4], b[5]);
    return b;
}

}  // namespace

GeometryMeasures measure_geometry(const TopoDS_Shape& s) {
    GeometryMeasures m;
    m.solids = count(s, TopAbs_SOLID);
    m.shells = count(s, TopAbs_SHELL);
    m.faces = count(s, TopAbs_FACE);
    m.edges = count(s, TopAbs_EDGE);
    // Volume of the solids only: the "volume" of open shells is no property of the model.
    for (TopExp_Explorer ex(s, TopAbs_SOLID); ex.More(); ex.Next()) {
        GProp_GProps v;
        BRepGProp::VolumeProperties(ex.Current(), v);
        m.volume += std::abs(v.Mass());
    }
    GProp_GProps a;
    BRepGProp::SurfaceProperties(s, a);
    m.area = a.Mass();
    // Faces only, from their geometry: wireframe and shape tolerances would blur the comparison.
    Bnd_Box box;
    for (TopExp_Explorer ex(s, TopAbs_FACE); ex.More(); ex.Next())
        BRepBndLib::AddOptimal(ex.Current(), box, Standard_False, Standard_False);
    m.box = to_array(box);
    try {
        m.valid = BRepCheck_Analyzer(s).IsValid() == Standard_True;
    } catch (const Standard_Failure&) {
        m.valid = false;  // the checker itself failed on it: not a shape to vouch for
    }
    return m;
}

const GeometryMeasures& measure_source(const OcctModel& model) {
    if (!model.measures->source)
        model.measures->source = std::make_shared<GeometryMeasures>(measure_geometry(model.shape));
    return *model.measures->source;
}

MeshMeasures measure_mesh(const TopoDS_Shape& s) {
    MeshMeasures m;
    Bnd_Box box;
    TopTools_IndexedMapOfShape faces;
    TopExp::MapShapes(s, TopAbs_FACE, faces);
    for (int i = 1; i <= faces.Extent(); ++i) {
        const TopoDS_Face& face = TopoDS::Face(faces(i));
        TopLoc_Location loc;
        const Handle(Poly_Triangulation) t = BRep_Tool::Triangulation(face, loc);
        if (t.IsNull()) continue;
        const gp_Trsf placement = loc.Transformation();
        const bool reversed = face.Orientation() == TopAbs_REVERSED;
        for (int k = 1; k <= t->NbTriangles(); ++k) {
            int n[3];
            t->Triangle(k).Get(n[0], n[1], n[2]);
            if (reversed) std::swap(n[1], n[2]);  // the outward order, as the writers write it
            const gp_Pnt a = t->Node(n[0]).Transformed(placement), b = t->Node(n[1]).Transformed(placement),
                         c = t->Node(n[2]).Transformed(placement);
            const gp_Vec cross = gp_Vec(a, b).Crossed(gp_Vec(a, c));
            m.area += cross.Magnitude() / 2;
            // Signed volume of the tetrahedron to the origin (divergence theorem).
            m.volume += gp_Vec(a.XYZ()).Dot(gp_Vec(b.XYZ()).Crossed(gp_Vec(c.XYZ()))) / 6;
            ++m.triangles;
            for (const gp_Pnt* p : {&a, &b, &c}) box.Add(*p);
        }
    }
    m.volume = std::abs(m.volume);
    m.box = to_array(box);
    return m;
}

nlohmann::ordered_json geometry_json(const GeometryMeasures& m) {
    return {{"solids", m.solids}, {"shells", m.shells}, {"faces", m.faces},       {"edges", m.edges},
            {"volume", m.volume}, {"area", m.area},     {"box", box_json(m.box)}, {"valid", m.valid}};
}

nlohmann::ordered_json compare_geometry(const GeometryMeasures& in, const GeometryMeasures& out,
                                        std::vector<std::string>& warnings) {
    const double volume = relative(in.volume, out.volume), area = relative(in.area, out.area),
                 box = box_difference(in.box, out.box);
    auto changed = [&](const char* what, int a, int b) {
        if (a != b)
            warnings.push_back(std::string("the output holds ") + std::to_string(b) + " " + what + ", the source " +
                               std::to_string(a));
    };
    changed("solid(s)", in.solids, out.solids);
    changed("shell(s)", in.shells, out.shells);
    changed("edge(s)", in.edges, out.edges);
    auto moved = [&](const char* what, double d) {
        if (d > kExactTolerance)
            warnings.push_back(std::string("the output's ") + what + " differs from the source's by " +
                               std::to_string(d) + " (relative; exact formats keep it within " +
                               std::to_string(kExactTolerance) + ")");
    };
    if (in.solids > 0 && out.solids > 0) moved("volume", volume);
    moved("area", area);
    moved("bounding box", box);
    if (in.valid && !out.valid)
        warnings.push_back("the output is not a valid shape (BRepCheck_Analyzer); the source is");
    return {{"volume", volume}, {"area", area}, {"box", box}, {"tolerance", kExactTolerance}};
}

nlohmann::ordered_json mesh_json(const GeometryMeasures& in, const MeshMeasures& mesh, const ConvertReport& r) {
    nlohmann::ordered_json j = {{"triangles", mesh.triangles},
                                {"degenerate_triangles_left_out", r.degenerate_triangles},
                                {"unmeshed_faces", r.unmeshed_faces},
                                {"area", mesh.area},
                                {"box", box_json(mesh.box)}};
    // The enclosed volume means something only for closed solids.
    if (in.solids > 0) j["volume"] = mesh.volume;
    nlohmann::ordered_json d = {{"area", relative(in.area, mesh.area)}, {"box", box_difference(in.box, mesh.box)}};
    if (in.solids > 0) d["volume"] = relative(in.volume, mesh.volume);
    return {{"mesh", j}, {"relative_differences", d}};
}

nlohmann::ordered_json source_json(const OcctModel& model, const GeometryMeasures& m) {
    return {{"format", format_name(model.format)}, {"units", model.units}, {"geometry", geometry_json(m)}};
}

std::string mesh_fidelity(const OcctModel& model, const TopoDS_Shape& meshed, ConvertReport& r) {
    const GeometryMeasures& in = measure_source(model);
    nlohmann::ordered_json f = {{"source", source_json(model, in)}};
    const nlohmann::ordered_json m = mesh_json(in, measure_mesh(meshed), r);
    // Measured in the model's mm, whatever unit the file is written in.
    f["output"] = {{"format", conversion_format_name(r.output)}, {"units", r.out_units}, {"mesh_in_mm", m["mesh"]}};
    f["relative_differences"] = m["relative_differences"];
    f["relative_differences"]["tolerance"] = kMeshMeasureTolerance;
    const std::string fmt = conversion_format_name(r.output);
    for (const char* what : {"area", "volume"})
        if (const nlohmann::ordered_json& d = m["relative_differences"]; d.contains(what)) {
            if (const double rel = d[what].get<double>(); rel > kMeshMeasureTolerance)
                r.warnings.push_back(std::string("the ") + fmt + " mesh's " + what +
                                     " differs from the exact faces' by " + std::to_string(rel) +
                                     " (relative; a mesh's chords keep it within " +
                                     std::to_string(kMeshMeasureTolerance) + ")");
        }
    const nlohmann::ordered_json deviation = mesh_deviation_json(meshed, diagonal(in.box));
    if (deviation.is_object()) {
        if (const double rel = deviation["relative_to_diagonal"]["max"].get<double>(); rel > kMeshDeviationTolerance)
            r.warnings.push_back(std::string("the ") + fmt + " mesh lies up to " +
                                 std::to_string(deviation["max"].get<double>()) + " mm (" + std::to_string(rel) +
                                 " of the diagonal) from the exact faces, beyond " +
                                 std::to_string(kMeshDeviationTolerance));
    }
    // What was asked of BRepMesh, beside what it achieved.
    f["output"]["asked"] = {{"deflection", r.mesh_relative_deflection},
                            {"deflection_mm", r.mesh_deflection_mm},
                            {"angular_deflection", r.mesh_angular_deflection}};
    f["output"]["deviation_in_mm"] = deviation;
    return f.dump();
}

}  // namespace nurbsrt::occt
