// The tessellating peer of `nurbsrt bench`: a CAD file meshed with OCCT's
// BRepMesh at a given deflection, as a plain triangle mesh (what a mesh-based
// renderer draws instead of the exact surfaces). OCCT-free header: file in,
// triangle mesh out.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "core/scene/scene_ops.h"
#include "core/scene/triangle_mesh.h"

namespace nurbsrt {

struct Tessellation {
    TriangleMesh mesh;                // every face's triangles, instance transforms and placements applied
    double mesh_ms = 0;               // BRepMesh_IncrementalMesh on the whole shape (wall clock)
    double extract_ms = 0;            // copying the triangulations (and the placed copies) out of OCCT
    int faces_without_triangles = 0;  // faces BRepMesh left empty (drawn as holes)
};

class Tessellator {
public:
    // Reads `path` (STEP/IGES by content). `placements`: one copy of the mesh per
    // transform (empty: the file as it is); the model is meshed once, as an
    // instancing renderer would. Throws nurbsrt::Error.
    explicit Tessellator(const std::string& path, const std::vector<Affine>& placements = {});
    ~Tessellator();
    Tessellator(const Tessellator&) = delete;
    Tessellator& operator=(const Tessellator&) = delete;

    // Removes any previous triangulation and meshes the whole shape with linear
    // deflection `deflection` (model units) and angular deflection `angle_rad`.
    // `parallel`: BRepMesh meshes faces on several threads.
    Tessellation mesh(double deflection, double angle_rad, bool parallel);
    double read_ms() const;

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

}  // namespace nurbsrt
