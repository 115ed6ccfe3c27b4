// Depth-only rasterization of a triangle mesh with OSMesa: the hit distance t
// (renderer/camera.h) of every pixel's contract ray with the
// mesh, as a tessellating renderer sees the model. Used by `nurbsrt bench` to
// compare exact NURBS hits against meshes of several deflections.
//
// Pixel centres are the contract's pixel rays (geometry goes through
// Camera::clip, as in the preliminary map). The depth along the view direction
// is affine in model space, so GL's perspective-correct interpolation of it is
// exact at the ray's hit with the triangle's plane; it is computed per vertex
// in double relative to the eye and converted to t on the CPU.
#pragma once

#include <memory>
#include <vector>

#include "renderer/camera.h"
#include "core/scene/triangle_mesh.h"

namespace nurbsrt {

struct DepthImage {
    int width = 0, height = 0;
    std::vector<float> t;  // row-major, row 0 = top; +inf where no triangle covers the pixel centre
};

class MeshRasterizer {
public:
    MeshRasterizer();  // creates its own OSMesa context; throws Error(internal) on failure
    ~MeshRasterizer();
    MeshRasterizer(const MeshRasterizer&) = delete;
    MeshRasterizer& operator=(const MeshRasterizer&) = delete;

    // Throws Error(limit_exceeded) for an image larger than the GL limits.
    DepthImage render(const TriangleMesh& mesh, const Camera& camera);

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

}  // namespace nurbsrt
