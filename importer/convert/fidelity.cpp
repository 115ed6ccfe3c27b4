// The fidelity report of a conversion (convert_writers.h): the source and the
// output measured alike, by OCCT, and compared; differences past the
// tolerances below become warnings.
#include <algorithm>
#include <array>
#include <cstdint>
#include <map>
#include <tuple>
#include <cmath>
#include <optional>
#include <vector>

#include <tbb/parallel_for.h>

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

double distance(const std::array<double, 3>& a, const std::array<double, 3>& b) {
    return std::sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) + (a[2] - b[2]) * (a[2] - b[2]));
}

// A mesh's edges as a reader of the written file joins them: vertices equal
// at float precision (what STL, glb and OBJ store) are one vertex.
class MeshEdges {
public:
    void add(const gp_Pnt& a, const gp_Pnt& b, const gp_Pnt& c) {
        const uint32_t v[3] = {vertex(a), vertex(b), vertex(c)};
        for (int i = 0; i < 3; ++i) {
            const uint32_t p = v[i], q = v[(i + 1) % 3];
            edges_.push_back({std::min(p, q), std::max(p, q), triangle_});
        }
        ++triangle_;
    }
    void count(MeshMeasures& m) {
        std::sort(edges_.begin(), edges_.end());
        std::vector<bool> non_manifold(triangle_, false);
        for (size_t i = 0; i < edges_.size();) {
            size_t j = i;
            while (j < edges_.size() && edges_[j].a == edges_[i].a && edges_[j].b == edges_[i].b) ++j;
            if (j - i == 1) ++m.open_edges;
            if (j - i > 2) {
                ++m.non_manifold_edges;
                for (size_t k = i; k < j; ++k) non_manifold[edges_[k].triangle] = true;
            }
            i = j;
        }
        m.non_manifold_triangles = std::count(non_manifold.begin(), non_manifold.end(), true);
    }

private:
    struct Edge {
        uint32_t a, b, triangle;
        bool operator<(const Edge& o) const { return std::tie(a, b, triangle) < std::tie(o.a, o.b, o.triangle); }
    };
    uint32_t vertex(const gp_Pnt& p) {
        const std::array<float, 3> key = {static_cast<float>(p.X()), static_cast<float>(p.Y()),
                                          static_cast<float>(p.Z())};
        return ids_.try_emplace(key, static_cast<uint32_t>(ids_.size())).first->second;
    }
    std::map<std::array<float, 3>, uint32_t> ids_;
    std::vector<Edge> edges_;
    uint32_t triangle_ = 0;
};

}  // namespace

GeometryMeasures measure_geometry(const TopoDS_Shape& s) {
    GeometryMeasures m;
    m.solids = count(s, TopAbs_SOLID);
    m.shells = count(s, TopAbs_SHELL);
    m.faces = count(s, TopAbs_FACE);
    m.edges = count(s, TopAbs_EDGE);
    // Volume of the solids only: the "volume" of open shells is no property of the model.
    gp_XYZ moment(0, 0, 0);
    for (TopExp_Explorer ex(s, TopAbs_SOLID); ex.More(); ex.Next()) {
        GProp_GProps v;
        BRepGProp::VolumeProperties(ex.Current(), v);
        m.volume += std::abs(v.Mass());
        moment += std::abs(v.Mass()) * v.CentreOfMass().XYZ();
    }
    if (m.volume > 0) m.centroid = {moment.X() / m.volume, moment.Y() / m.volume, moment.Z() / m.volume};
    GProp_GProps a;
    BRepGProp::SurfaceProperties(s, a);
    m.area = a.Mass();
    // Faces only, from their geometry: wireframe and shape tolerances would blur the comparison.
    // (BRepBndLib::AddOptimal searches each face's surface for its extremes:
    // the faces side by side, their boxes joined in order.)
    TopTools_IndexedMapOfShape faces;
    TopExp::MapShapes(s, TopAbs_FACE, faces);
    std::vector<Bnd_Box> boxes(static_cast<size_t>(faces.Extent()));
    tbb::parallel_for(size_t(0), boxes.size(), [&](size_t i) {
        BRepBndLib::AddOptimal(faces(static_cast<int>(i) + 1), boxes[i], Standard_False, Standard_False);
    });
    Bnd_Box box;
    for (const Bnd_Box& b : boxes) box.Add(b);
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
    gp_XYZ moment(0, 0, 0);
    MeshEdges edges;
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
            // Signed volume of the tetrahedron to the origin (divergence theorem),
            // and its first moment (the tetrahedron's centroid is (a + b + c) / 4).
            const double v = gp_Vec(a.XYZ()).Dot(gp_Vec(b.XYZ()).Crossed(gp_Vec(c.XYZ()))) / 6;
            m.volume += v;
            moment += v * (a.XYZ() + b.XYZ() + c.XYZ()) / 4;
            edges.add(a, b, c);
            ++m.triangles;
            for (const gp_Pnt* p : {&a, &b, &c}) box.Add(*p);
        }
    }
    if (m.volume != 0) m.centroid = {moment.X() / m.volume, moment.Y() / m.volume, moment.Z() / m.volume};
    m.volume = std::abs(m.volume);
    m.box = to_array(box);
    edges.count(m);
    return m;
}

nlohmann::ordered_json geometry_json(const GeometryMeasures& m) {
    nlohmann::ordered_json j = {{"solids", m.solids}, {"shells", m.shells}, {"faces", m.faces},      {"edges", m.edges},
                                {"volume", m.volume}, {"area", m.area},     {"box", box_json(m.box)}};
    if (m.solids > 0) j["volume_centroid"] = m.centroid;
    j["valid"] = m.valid;
    return j;
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
    if (in.solids > 0 && out.solids > 0) {
        moved("volume", volume);
        moved("volume centroid", distance(in.centroid, out.centroid) / std::max(diagonal(in.box), 1e-300));
    }
    moved("area", area);
    moved("bounding box", box);
    if (in.valid && !out.valid)
        warnings.push_back("the output is not a valid shape (BRepCheck_Analyzer); the source is");
    nlohmann::ordered_json d = {{"volume", volume}, {"area", area}, {"box", box}};
    // The centroid's move relative to the diagonal (solids only).
    if (in.solids > 0 && out.solids > 0)
        d["volume_centroid"] = distance(in.centroid, out.centroid) / std::max(diagonal(in.box), 1e-300);
    d["tolerance"] = kExactTolerance;
    return d;
}

nlohmann::ordered_json mesh_json(const GeometryMeasures& in, const MeshMeasures& mesh, const ConvertReport& r) {
    nlohmann::ordered_json j = {{"triangles", mesh.triangles},
                                {"degenerate_triangles_left_out", r.degenerate_triangles},
                                {"unmeshed_faces", r.unmeshed_faces},
                                {"open_edges", mesh.open_edges},
                                {"non_manifold_edges", mesh.non_manifold_edges},
                                {"non_manifold_triangles", mesh.non_manifold_triangles},
                                {"area", mesh.area},
                                {"box", box_json(mesh.box)}};
    // The enclosed volume means something only for closed solids.
    if (in.solids > 0) {
        j["volume"] = mesh.volume;
        j["volume_centroid"] = mesh.centroid;
    }
    nlohmann::ordered_json d = {{"area", relative(in.area, mesh.area)}, {"box", box_difference(in.box, mesh.box)}};
    if (in.solids > 0) {
        d["volume"] = relative(in.volume, mesh.volume);
        d["volume_centroid"] = distance(in.centroid, mesh.centroid) / std::max(diagonal(in.box), 1e-300);
    }
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
    // A mesh taken over from an earlier output of the read was measured then.
    std::optional<MeasuresCache::ExportMesh>& made = model.measures->export_mesh;
    const nlohmann::ordered_json deviation = r.mesh_shared && made && !made->deviation.empty()
                                                 ? nlohmann::ordered_json::parse(made->deviation)
                                                 : mesh_deviation_json(meshed, diagonal(in.box));
    if (made && made->deviation.empty()) made->deviation = deviation.dump();
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
