// Internal OCCT-level interface of the importer. Includes OCCT headers, so only
// importer/*.cpp, tests and benchmarks (which use OCCT as the independent
// reference) may include it; never include it from a widely used header.
#pragma once

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <Geom_BSplineSurface.hxx>
#include <TDocStd_Document.hxx>
#include <TopTools_IndexedMapOfShape.hxx>
#include <TopoDS_Face.hxx>
#include <TopoDS_Shape.hxx>

#include "importer/importer.h"
#include "importer/uv_map.h"

namespace nurbsrt::occt {

// Colour/name found for a face through XDE (face, then its solid/instance label).
struct FaceAttributes {
    bool has_color = false;
    Color color;
    std::string name;
    uint32_t body = 0;  // index into OcctModel::bodies
};

struct GeometryMeasures;  // importer/convert/convert_writers.h

// A read's measures of its own shape (the fidelity report's source half),
// taken by the first conversion that needs them (measure_source) and shared by
// every copy of the model a SharedRead serves: measured once per read.
struct MeasuresCache {
    std::shared_ptr<const GeometryMeasures> source;
    // The export mesh the shared shape carries (mesh_for_export) and what
    // making and measuring it found: the next mesh output of the same read
    // asking the same parameters takes it over, as BRepMesh would make the
    // same triangulation again (and its deviation is the same).
    struct ExportMesh {
        double deflection = 0, angle = 0;  // absolute, as BRepMesh was given them
        int face_instances = 0;            // of the shape meshed
        long long triangles = 0, degenerate_triangles = 0;
        int unmeshed_faces = 0;
        std::string deviation;  // mesh_deviation_json's text; "" until measured
    };
    std::optional<ExportMesh> export_mesh;
};

// A file as OCCT reads it: all transferred roots in one shape, and the faces
// in the order of the face-index contract (faces.FindKey(i) is face i, 1-based).
struct OcctModel {
    CadFormat format = CadFormat::unknown;
    std::string units;                       // declared length unit of the file
    TopoDS_Shape shape;                      // compound of all transferred roots
    TopTools_IndexedMapOfShape faces;        // TopExp::MapShapes(shape, TopAbs_FACE, faces)
    std::vector<FaceAttributes> attributes;  // attributes[i-1] for face i (empty when not read)
    std::vector<Body> bodies;
    std::vector<Part> parts;  // the XDE assembly tree (read_attributes only), depth first
    std::vector<std::string> warnings;
    double read_ms = 0;
    // The XDE document (colours, names, assembly structure), only when
    // read_model was asked to keep it; the caller closes it
    // (XCAFApp_Application::GetApplication()->Close) when done.
    Handle(TDocStd_Document) document;
    std::shared_ptr<MeasuresCache> measures = std::make_shared<MeasuresCache>();
};

// Reads STEP or IGES (format by content). Serialized by a process-wide mutex
// (concurrent reads corrupt OCCT's heap: its STEP/IGES readers share global state). OCCT's console output goes
// to our log, never to stdout. Throws nurbsrt::Error. keep_document (implies
// read_attributes) hands the XDE document to the caller in OcctModel::document.
OcctModel read_model(const std::string& path, bool read_attributes, bool keep_document = false);

// One face converted for the renderer. `surface`: its B-spline surface made
// non-periodic and clamped, with the face's location (instance transform)
// applied, so that `surface->D1(u,v)` is the reference for
// nurbsrt::evaluate_d1 on Scene::faces[i-1].surface at the same (u,v).
// `face`: the face whose pcurves bound it, with its own copies of the edges
// (same orientation and location as the input). Its (u,v) are the surface's
// through `map`: the identity when the face's surface already was a B-spline
// (the face is copied) or was converted with its edges
// (BRepBuilderAPI_NurbsConvert); for an analytic surface converted alone
// (GeomConvert) `face` is the input's and `map` takes its (u,v) to the
// surface's (uv_map.h).
struct ConvertedFace {
    TopoDS_Face face;
    Handle(Geom_BSplineSurface) surface;
    UVMap map;
};
ConvertedFace convert_face(const TopoDS_Face& face);

}  // namespace nurbsrt::occt
