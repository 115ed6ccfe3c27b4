// Meshing for the mesh outputs (STL, glb, VRML, OBJ): see convert_writers.h.
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <set>

#include <BRepBndLib.hxx>
#include <BRepMesh_IncrementalMesh.hxx>
#include <BRepTools.hxx>
#include <BRep_Builder.hxx>
#include <BRep_Tool.hxx>
#include <Bnd_Box.hxx>
#include <IMeshTools_Parameters.hxx>
#include <Poly_Triangulation.hxx>
#include <Standard_Failure.hxx>
#include <TopExp.hxx>
#include <TopLoc_Location.hxx>
#include <TopTools_IndexedMapOfShape.hxx>
#include <TDF_LabelSequence.hxx>
#include <TopoDS.hxx>
#include <TopoDS_Compound.hxx>
#include <XCAFDoc_DocumentTool.hxx>
#include <XCAFDoc_ShapeTool.hxx>

#include "importer/convert/convert_writers.h"
#include "importer/internal.h"
#include "core/error.h"

namespace nurbsrt::occt {
namespace {

// A triangle has no area in a file of float coordinates when its height over
// its longest edge is within the spacing of floats at its coordinates'
// magnitude (the written vertices cannot tell it from a line): the shading
// normal of such a triangle is noise and mesh checkers count it as an error.
bool degenerate_at_float_precision(const gp_Pnt& a, const gp_Pnt& b, const gp_Pnt& c) {
    const gp_Vec ab(a, b), ac(a, c), bc(b, c);
    const double longest = std::sqrt(std::max({ab.SquareMagnitude(), ac.SquareMagnitude(), bc.SquareMagnitude()}));
    if (longest == 0.0) return true;
    double magnitude = 0.0;
    for (const gp_Pnt* p : {&a, &b, &c})
        magnitude = std::max({magnitude, std::abs(p->X()), std::abs(p->Y()), std::abs(p->Z())});
    const double height = ab.Crossed(ac).Magnitude() / longest;
    return height <= static_cast<double>(std::numeric_limits<float>::epsilon()) * std::max(magnitude, longest);
}

// Takes out of `face`'s triangulation (in place: the writers read it from the
// face) the triangles of no area (repeated node, or degenerate at float
// precision, placed as the face is) and those repeating an earlier one of the
// face; returns how many.
long long drop_degenerate_triangles(const TopoDS_Face& face) {
    TopLoc_Location loc;
    const Handle(Poly_Triangulation) t = BRep_Tool::Triangulation(face, loc);
    if (t.IsNull()) return 0;
    const gp_Trsf placement = loc.Transformation();
    std::set<std::array<int, 3>> seen;
    int kept = 0;
    for (int i = 1; i <= t->NbTriangles(); ++i) {
        const Poly_Triangle tri = t->Triangle(i);
        int n[3];
        tri.Get(n[0], n[1], n[2]);
        if (n[0] == n[1] || n[1] == n[2] || n[0] == n[2]) continue;
        if (std::min({n[0], n[1], n[2]}) < 1 || std::max({n[0], n[1], n[2]}) > t->NbNodes()) continue;
        if (degenerate_at_float_precision(t->Node(n[0]).Transformed(placement), t->Node(n[1]).Transformed(placement),
                                          t->Node(n[2]).Transformed(placement)))
            continue;
        std::array<int, 3> key{n[0], n[1], n[2]};
        std::sort(key.begin(), key.end());
        if (!seen.insert(key).second) continue;
        t->SetTriangle(++kept, tri);
    }
    const long long dropped = t->NbTriangles() - kept;
    if (kept == 0)  // an array cannot be empty: the face has no mesh (an unmeshed face)
        BRep_Builder().UpdateFace(face, Handle(Poly_Triangulation)());
    else if (dropped > 0)
        t->ResizeTriangles(kept, /*theToCopyOld=*/Standard_True);
    return dropped;
}

// BRepMesh at `params`, then the degenerate triangles out, counted in `r`.
void mesh_anew(const TopoDS_Shape& shape, const TopTools_IndexedMapOfShape& faces, const IMeshTools_Parameters& params,
               ConvertReport& r) {
    try {
        BRepMesh_IncrementalMesh mesher(shape, params);
    } catch (const Standard_Failure& f) {
        throw Error(ErrorCode::occt_failure, "BRepMesh: " + failure_text(f));
    }
    r.triangles = 0;
    r.unmeshed_faces = 0;
    r.degenerate_triangles = 0;
    for (int i = 1; i <= faces.Extent(); ++i) {
        r.degenerate_triangles += drop_degenerate_triangles(TopoDS::Face(faces(i)));
        TopLoc_Location loc;
        const Handle(Poly_Triangulation) t = BRep_Tool::Triangulation(TopoDS::Face(faces(i)), loc);
        if (t.IsNull() || t->NbTriangles() == 0)
            ++r.unmeshed_faces;
        else
            r.triangles += t->NbTriangles();
    }
}

}  // namespace

double mesh_for_export(const TopoDS_Shape& shape, ConvertReport& r, const ConvertOptions& options,
                       MeasuresCache* cache) {
    const auto t0 = std::chrono::steady_clock::now();
    TopTools_IndexedMapOfShape faces;
    TopExp::MapShapes(shape, TopAbs_FACE, faces);
    // Faces only, as for the import's own mesh: wireframe entities (unbounded
    // lines, construction geometry) must not inflate the box that sets the deflection.
    Bnd_Box box;
    for (int i = 1; i <= faces.Extent(); ++i) BRepBndLib::Add(faces(i), box, Standard_False);
    const double diag = box.IsVoid() ? 0.0 : std::sqrt(box.SquareExtent());
    const ImportOptions defaults;
    IMeshTools_Parameters params;
    const double relative = options.deflection > 0 ? options.deflection : defaults.mesh_relative_deflection;
    params.Deflection = diag > 0 && std::isfinite(diag) ? relative * diag : 1e-3;
    params.Angle = options.angular_deflection;
    r.mesh_relative_deflection = relative;
    r.mesh_deflection_mm = params.Deflection;
    r.mesh_angular_deflection = params.Angle;
    params.InParallel = Standard_True;
    const bool shared = cache && cache->export_mesh && cache->export_mesh->deflection == params.Deflection &&
                        cache->export_mesh->angle == params.Angle &&
                        cache->export_mesh->face_instances == faces.Extent();
    if (shared) {
        const MeasuresCache::ExportMesh& e = *cache->export_mesh;
        r.triangles = e.triangles;
        r.unmeshed_faces = e.unmeshed_faces;
        r.degenerate_triangles = e.degenerate_triangles;
        r.mesh_shared = true;
    } else {
        if (cache && cache->export_mesh) {
            BRepTools::Clean(shape);  // another output's mesh, at other parameters
            cache->export_mesh.reset();
        }
        mesh_anew(shape, faces, params, r);
        if (cache)
            cache->export_mesh = MeasuresCache::ExportMesh{params.Deflection,
                                                           params.Angle,
                                                           faces.Extent(),
                                                           r.triangles,
                                                           r.degenerate_triangles,
                                                           r.unmeshed_faces,
                                                           ""};
    }
    r.mesh_ms = ms_since(t0);
    // A face missing from the output is a loss like any other: a warning,
    // which strict refuses (the CLI and the service alike).
    if (r.unmeshed_faces > 0 && r.triangles > 0)
        r.warnings.push_back(std::to_string(r.unmeshed_faces) + " of " + std::to_string(faces.Extent()) +
                             " face(s) could not be meshed and are missing from the " +
                             conversion_format_name(r.output) + " output");
    if (r.triangles == 0)
        throw Error(ErrorCode::occt_failure,
                    "BRepMesh produced no triangles for any of the " + std::to_string(faces.Extent()) + " faces");
    return params.Deflection;
}

}  // namespace nurbsrt::occt

namespace nurbsrt::occt {

TopoDS_Shape mesh_document_for_export(const Handle(TDocStd_Document) & doc, ConvertReport& r,
                                      const ConvertOptions& options, MeasuresCache* cache) {
    const Handle(XCAFDoc_ShapeTool) shapes = XCAFDoc_DocumentTool::ShapeTool(doc->Main());
    TDF_LabelSequence roots;
    shapes->GetFreeShapes(roots);
    TopoDS_Compound all;
    BRep_Builder builder;
    builder.MakeCompound(all);
    for (const TDF_Label& label : roots) builder.Add(all, XCAFDoc_ShapeTool::GetShape(label));
    mesh_for_export(all, r, options, cache);
    return all;
}

}  // namespace nurbsrt::occt
