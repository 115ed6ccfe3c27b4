// A plain triangle mesh in model space: what a tessellating renderer draws
// instead of the exact surfaces (the benchmark's tessellating peer: the importer
// meshes a model with BRepMesh, bench/mesh_raster.h rasterizes it).
#pragma once

#include <cstdint>
#include <vector>

#include "core/vec.h"

namespace nurbsrt {

struct TriangleMesh {
    std::vector<Vec3> xyz;
    std::vector<uint32_t> triangles;  // 3 indices per triangle, into xyz
    size_t triangle_count() const { return triangles.size() / 3; }
};

}  // namespace nurbsrt
