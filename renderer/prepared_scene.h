// Prepare once, render many: everything a frame needs of a Scene that does not
// depend on the camera, built once by prepare() and then only read by any number
// of frames, from any number of threads at once (the split of Embree's
// rtcCommitScene / rtcIntersect). Per face: the trim test's acceleration grid,
// the parameter box with its seams, the trim-tolerance band; for the preliminary
// map: every face's map mesh merged into one indexed triangle list with its
// per-vertex (u, v) and face id (a frame only transforms the positions).
//
// What stays per frame (render.cpp): the projection of the patches' coefficients
// (proposed), the preliminary map itself, the screen positions of mesh vertices
// for the rescue's start search: all depend on the camera.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

#include "renderer/newton.h"
#include "core/scene.h"
#include "core/trim.h"

namespace nurbsrt {

// Camera-independent per-face data of the pixel solves.
struct PreparedFace {
    TrimTester trim;
    SurfaceSpans spans;    // per-span basis tables of the face's surface (span_basis.h)
    SurfacePatches patches;  // its power-form patches over them (surface_patches.h)
    UvBox box;             // parameter box with seams (face_uv_box)
    double near_uv = 0;    // trim-tolerance band for crack filling (pixel_solver.h, Solver::solve)
    double trim_uv = 0;    // the trim test's uncertainty: the exact boundary lies within it of the loops
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

class PreparedScene {
public:
    PreparedScene(PreparedScene&&) = default;
    PreparedScene& operator=(PreparedScene&&) = default;
    PreparedScene(const PreparedScene&) = delete;
    PreparedScene& operator=(const PreparedScene&) = delete;

    const Scene& scene() const { return *scene_; }
    const std::vector<PreparedFace>& faces() const { return faces_; }
    const MapMesh& map_mesh() const { return map_; }
    // Unique per prepare() call in this process (never reused, unlike an
    // address): lets a GL context keep this scene's map mesh uploaded between frames.
    uint64_t id() const { return id_; }
    // Wall-clock time prepare() took, milliseconds.
    double prepare_ms() const { return prepare_ms_; }
    // Approximate heap memory of the prepared data (not counting the Scene).
    size_t memory_bytes() const;

private:
    friend struct PreparedSceneBuilder;  // prepared_scene.cpp
    PreparedScene() = default;

    const Scene* scene_ = nullptr;
    std::shared_ptr<const Scene> owner_;  // set when prepare() was given shared ownership
    std::vector<PreparedFace> faces_;
    MapMesh map_;
    uint64_t id_ = 0;
    double prepare_ms_ = 0;
};

// Builds the prepared data with up to `threads` threads (0: all hardware
// threads); the result does not depend on the thread count. Throws
// Error(invalid_argument) unless faces[i].index == i + 1.
// The first form refers to `scene`, which must outlive the result and not
// change; the second keeps the scene alive itself.
PreparedScene prepare(const Scene& scene, int threads = 0);
PreparedScene prepare(std::shared_ptr<const Scene> scene, int threads = 0);

}  // namespace nurbsrt
