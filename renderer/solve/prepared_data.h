// The renderer's side of a PreparedScene (prepared_scene.h): per face, what the
// pixel solves need (trim grid, span tables, patches, parameter box, tolerance
// bands, adjacency), and the preliminary map's merged mesh. Built by prepare()
// (prepared_scene.cpp), then only read.
#pragma once

#include <cstdint>
#include <vector>

#include "core/scene/scene.h"
#include "core/scene/trim.h"
#include "renderer/prepared_scene.h"
#include "renderer/solve/newton.h"

namespace nurbsrt {

// Camera-independent per-face data of the pixel solves.
struct PreparedFace {
    TrimTester trim;
    SurfaceSpans spans;      // per-span basis tables of the face's surface (span_basis.h)
    SurfacePatches patches;  // its power-form patches over them (surface_patches.h)
    UvBox box;               // parameter box with seams (face_uv_box)
    double near_uv = 0;      // trim-tolerance band for crack filling (pixel_solver.h, Solver::solve)
    double trim_uv = 0;      // the trim test's uncertainty: the exact boundary lies within it of the loops
    // Faces that touch this one (their map meshes share a vertex, see prepare()),
    // ascending ids. The rescue and the nearer-sheet pass try them where a face
    // too thin for the map to rasterize lies between the pixel's neighbours' faces.
    std::vector<uint32_t> adjacent;
    // Box of the face's map mesh (the rescue's screen search over all faces).
    BBox mesh_box;
    // The face lies in one plane (planar_control_net): a light ray leaving it
    // cannot cross it again (the shadow rays' own-face retry).
    bool planar = false;
};

// The preliminary map's mesh: all faces' FaceMesh vertices that have a (u, v),
// in face order, and their triangles with indices into these arrays (malformed
// triangles dropped). Positions stay in double: a frame transforms them to clip
// space relative to the eye before rounding to float (preliminary_map.h).
struct MapMesh {
    std::vector<Vec3> xyz;
    std::vector<float> uv;          // 2 per vertex
    std::vector<uint32_t> face;     // Face::index per vertex
    std::vector<uint32_t> indices;  // 3 per triangle
    size_t triangles() const { return indices.size() / 3; }
};

struct PreparedData {
    std::vector<PreparedFace> faces;
    MapMesh map;
};

inline const std::vector<PreparedFace>& PreparedScene::faces() const { return data_->faces; }
inline const MapMesh& PreparedScene::map_mesh() const { return data_->map; }

}  // namespace nurbsrt
