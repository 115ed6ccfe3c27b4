// The per-format halves of convert_file (importer/convert/convert.cpp dispatches on the
// output extension). importer/*.cpp only: the mesh helper takes OCCT types.
#pragma once

#include <array>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "importer/importer.h"
#include "importer/occt_shape.h"

class TopoDS_Shape;

namespace nurbsrt::occt {

// Reads `in_path` with its XDE document (colours, names, assembly) for an export
// to `target` (the output format's name), filling r.in_format, r.faces and
// r.in_units and r.read_ms; throws occt_failure when the reader gives no document. The caller
// closes the document (DocumentCloser). `changes_document`: a read of the caller's own,
// not the SharedRead's (whose document the file's later outputs are written from).
OcctModel read_for_export(const std::string& in_path, const std::string& target, ConvertReport& r,
                          bool changes_document = false);

// STEP, IGES or BREP through OCCT's writers (exact geometry, topology kept);
// STEP and IGES in options.units or the source's unit, with options' schema / mode.
void write_cad(const std::string& in_path, const std::string& out_path, const ConvertOptions& options,
               ConvertReport& r);
// Binary STL of the whole model, meshed by mesh_for_export at options.deflection.
void write_stl(const std::string& in_path, const std::string& out_path, const ConvertOptions& options,
               ConvertReport& r);
// Binary glTF 2.0 (.glb) from the XDE document: colours, names and assembly
// instances kept; Y-up, metres (see convert_gltf.cpp).
void write_glb(const std::string& in_path, const std::string& out_path, const ConvertOptions& options,
               ConvertReport& r);
// VRML 2.0 (.wrl) from the XDE document: colours and the assembly's placements
// kept; coordinates in mm (see convert_vrml.cpp).
void write_vrml(const std::string& in_path, const std::string& out_path, const ConvertOptions& options,
                ConvertReport& r);

// Wavefront OBJ (.obj) and its materials (.mtl, same stem, beside it) from the
// XDE document: one object per part instance, colours as materials; mm.
void write_obj(const std::string& in_path, const std::string& out_path, const ConvertOptions& options,
               ConvertReport& r);

// Meshes every face of `shape` with BRepMesh for export: linear deflection
// options.deflection (0: ImportOptions{}.mesh_relative_deflection) times the
// diagonal of the faces' bounding box, angular deflection
// options.angular_deflection; both recorded in r (what the report says was asked).
// Fills r.mesh_ms, r.triangles (over all face occurrences, instances counted
// separately) and r.unmeshed_faces (faces left without a triangulation, which
// mesh outputs cannot contain, a warning). Triangles of no area at float precision or
// repeating another of their face are taken out of the faces' triangulations
// (the writers read those) and counted in r.degenerate_triangles.
// With `cache` (the model's MeasuresCache): a shape that already carries an
// export mesh made at the same parameters (a shared read's earlier mesh
// output) is not meshed again: its counts are taken over and r.mesh_shared
// set; one made at other parameters is replaced. Records the mesh made.
// Returns the deflection used.
double mesh_for_export(const TopoDS_Shape& shape, ConvertReport& r, const ConvertOptions& options = {},
                       MeasuresCache* cache = nullptr);
// The same for the shapes an XDE document holds (the writers that take a
// document read the triangulations from them); parts placed twice share their
// faces, so are meshed once.
// Returns the meshed compound of the document's free shapes.
TopoDS_Shape mesh_document_for_export(const Handle(TDocStd_Document) & doc, ConvertReport& r,
                                      const ConvertOptions& options, MeasuresCache* cache = nullptr);

// --- the fidelity report (fidelity.cpp) ----------------------------------------
// A shape as OCCT measures it: distinct (located) sub-shapes, the volume of its
// solids and the area of its faces (BRepGProp), the box of its faces' exact
// geometry, and validity (BRepCheck_Analyzer).
struct GeometryMeasures {
    int solids = 0, shells = 0, faces = 0, edges = 0;
    double volume = 0, area = 0;
    std::array<double, 6> box{};       // min x y z, max x y z
    std::array<double, 3> centroid{};  // of the solids' volume (none without solids)
    bool valid = true;
};
GeometryMeasures measure_geometry(const TopoDS_Shape& shape);
// measure_geometry of the model's shape, once per read (OcctModel::measures).
const GeometryMeasures& measure_source(const OcctModel& model);
// The triangles of the faces' triangulations (placed, every occurrence): their
// area, the volume they enclose and its centroid (divergence theorem), their
// box, and their edges as a reader of the written file joins them (vertices
// equal at float precision, as STL, glb and OBJ store them): edges of one
// triangle (open: a hole or an open shell) and of more than two (non-manifold),
// and the triangles that have a non-manifold edge.
struct MeshMeasures {
    long long triangles = 0;
    double area = 0, volume = 0;
    std::array<double, 6> box{};
    std::array<double, 3> centroid{};
    long long open_edges = 0, non_manifold_edges = 0, non_manifold_triangles = 0;
};
MeshMeasures measure_mesh(const TopoDS_Shape& shape);
nlohmann::ordered_json geometry_json(const GeometryMeasures& m);
// Relative differences of the output from the source; adds a warning for each
// topology count that changed, for a volume, area or box beyond the exact
// formats' tolerance, and for an invalid output of a valid source.
nlohmann::ordered_json compare_geometry(const GeometryMeasures& in, const GeometryMeasures& out,
                                        std::vector<std::string>& warnings);
// A mesh output against its source: triangles, area, volume, box and their
// relative differences.
nlohmann::ordered_json mesh_json(const GeometryMeasures& in, const MeshMeasures& mesh, const ConvertReport& r);
// The deviation of a face's export mesh from the face (mesh_deviation.cpp): the
// distance of every vertex from the surface at its (u, v), and of every
// triangle's centroid from its closest point on the trimmed face (Newton from
// the triangle's (u, v) centroid; where that point is trimmed away, the face's
// boundary, counted in `outside_trim`). Empty without a triangulation with (u, v).
std::vector<double> face_mesh_deviations(const TopoDS_Face& face, long long& outside_trim);
// Max, p99 and mean of those over the distinct faces of `meshed` (a part placed
// n times has its faces, and their mesh, once: measured once, counted in
// `face_instances`), in mm and relative to `diagonal`; null when nothing was meshed.
nlohmann::ordered_json mesh_deviation_json(const TopoDS_Shape& meshed, double diagonal);
// The source's part of a report: format, declared units, geometry.
nlohmann::ordered_json source_json(const OcctModel& model, const GeometryMeasures& m);
// The whole report of a mesh output: `meshed` is the shape whose faces carry
// the triangulations written. Adds a warning to r.warnings for a mesh farther
// from the exact faces, or an area or enclosed volume more different from
// theirs, than the tolerances of fidelity.cpp.
std::string mesh_fidelity(const OcctModel& model, const TopoDS_Shape& meshed, ConvertReport& r);

}  // namespace nurbsrt::occt
