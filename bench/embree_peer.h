// Optional second tessellating peer: Embree (Debian's libembree-dev, Embree 3)
// ray casts the contract's pixel rays against a triangle mesh. Built when CMake
// finds Embree (option NURBSRT_WITH_EMBREE, on by default, off when absent);
// otherwise embree_available() is false and the bench reports rasterization only.
#pragma once

#include <vector>

#include "renderer/camera.h"
#include "core/scene/triangle_mesh.h"

namespace nurbsrt::bench {

struct EmbreeFrame {
    std::vector<float> t;  // row-major, row 0 = top; +inf where the ray misses
    double build_ms = 0;   // device, geometry and BVH (rtcCommitScene)
    double render_ms = 0;  // one ray per pixel
};

bool embree_available();
// Throws nurbsrt::Error(internal) when Embree is not built in or fails.
EmbreeFrame embree_render(const TriangleMesh& mesh, const Camera& camera, int threads);

}  // namespace nurbsrt::bench
