// Declarations shared between the importer's translation units (importer/*.cpp
// only). OCCT types come in through occt_shape.h; nothing outside importer/
// may include this header.
#pragma once

#include <chrono>
#include <mutex>
#include <string>
#include <vector>

#include "importer/occt_shape.h"
#include "core/scene/scene.h"

class Standard_Failure;
class TDF_Label;

namespace nurbsrt::occt {

// Routes OCCT's default messenger to stderr with an "[occt]" prefix (warnings
// and worse; chatter below that is dropped) instead of coloured stdout.
// Idempotent and thread-safe; every entry point calls it before touching OCCT.
void route_occt_messages();

// "Standard_OutOfRange: message" for an OCCT exception.
std::string failure_text(const Standard_Failure& f);

// Milliseconds since `t0` on the steady clock.
inline double ms_since(std::chrono::steady_clock::time_point t0) {
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

// The B-spline surface as Scene data: homogeneous poles u-major, flat clamped knots.
NurbsSurface to_scene_surface(const Geom_BSplineSurface& s);

// Parameter box of a converted face (BRepTools::UVBounds, in the surface's
// (u,v)) clamped to the surface's knot range; an empty or inverted box falls
// back to the full range.
struct UVBox {
    double u0 = 0, u1 = 0, v0 = 0, v1 = 0;
    double diagonal() const;
};
UVBox face_uv_box(const ConvertedFace& cf);

// Trim loops of a converted face sampled from its pcurves, in the surface's
// (u,v) (see trim_loops.cpp).
struct TrimResult {
    std::vector<TrimLoop> loops;
    double tolerance_uv = 0;
    std::vector<std::string> warnings;  // without the face number; the caller prefixes it
};
TrimResult sample_trim_loops(const ConvertedFace& cf, const UVBox& box, double relative_tolerance);

// Even-odd point-in-loops test in (u,v); no loops means inside everywhere.
bool inside_loops(const std::vector<TrimLoop>& loops, Vec2 p);

// Mesh of a converted face from its BRepMesh triangulation (UV nodes taken to
// the surface's (u,v) by the face's UVMap, and located nodes); false when the
// face has no usable triangulation.
bool mesh_from_triangulation(const ConvertedFace& cf, FaceMesh& out);

// Regular (u,v) grid over the box, triangles kept where their centroid lies
// inside the trim loops; xyz evaluated on the surface.
FaceMesh trimmed_grid_mesh(const ConvertedFace& cf, const UVBox& box, const std::vector<TrimLoop>& loops,
                           int cells_per_side);

// Meshes every face (BRepMesh per face, in parallel, under the time limits);
// faces without a usable triangulation get trimmed_grid_mesh (warning each), and
// a triangulation that leaves part of its face uncovered (nodes no triangle
// uses) is completed from a finer trimmed grid (warning each).
// face_sizes[i]: 3D bounding-box diagonal of face i (caps its deflection);
// numbers[i]: its face number in the scene (the warnings name it).
struct MeshParams {
    double deflection = 0.1;        // absolute linear deflection, model units
    double angle = 0.35;            // angular deflection, radians
    double time_limit_s = 60;       // all faces together
    double face_time_limit_s = 15;  // one face
    int grid_cells = 48;            // fallback grid cells per side
};
void mesh_faces(const std::vector<ConvertedFace>& faces, const std::vector<UVBox>& boxes,
                const std::vector<const std::vector<TrimLoop>*>& loops, const std::vector<double>& face_sizes,
                const std::vector<uint32_t>& numbers, const MeshParams& p, std::vector<FaceMesh>& meshes,
                std::vector<std::string>& warnings);

// Closes an XDE document (registered with the process-wide application until
// closed) on every exit path of its user.
struct DocumentCloser {
    Handle(TDocStd_Document) doc;
    ~DocumentCloser();
};

// The TDataStd_Name of an XDE label as UTF-8 ("" when it has none).
std::string label_name(const TDF_Label& label);

// read_model without the SharedRead (importer/shared_read.h): the file read
// anew, for a use that changes the document it is given (the served one is
// every later use's too).
OcctModel read_model_from_file(const std::string& path, bool read_attributes, bool keep_document);

// Takes the triangulations off the SharedRead's shape (BRepTools::Clean), so
// that the next use meets the shape as a lone read delivers it; nothing
// without a SharedRead. With `keep_export_mesh`, an export mesh (recorded in
// the model's MeasuresCache) stays for mesh_for_export to take over or replace.
void forget_shared_meshes(bool keep_export_mesh = false);

// Serializes STEP/IGES reading, transfer and writing process-wide (concurrent
// use corrupts OCCT's heap: the readers and writers share global state).
std::mutex& exchange_mutex();

}  // namespace nurbsrt::occt
