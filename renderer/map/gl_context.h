// An offscreen OpenGL 4.5 core context with OSMesa (Mesa llvmpipe), shared by
// the preliminary map (preliminary_map.cpp) and the depth-only triangle-mesh
// rasterizer of the benchmark's tessellating peer (bench/mesh_raster.cpp). No
// libGL is linked: OSMesa exports the gl* entry points itself, and libGL's would
// take their place and break the map's shaders. GL types are
// spelled as the plain integers they are so that this header needs no GL headers.
#pragma once

#include <string>

namespace nurbsrt {

class GlContext {
public:
    GlContext();  // throws Error(internal) when OSMesa cannot make a 4.5 core context
    ~GlContext();
    GlContext(const GlContext&) = delete;
    GlContext& operator=(const GlContext&) = delete;

    // Makes the context current on the calling thread (one thread at a time).
    void make_current();
    // Makes no context current on the calling thread, so that this context may
    // next be made current on another thread (a context is current in one thread at most).
    static void release_current();
    // Compiles and links a vertex + fragment shader program; throws Error(internal)
    // with the compiler's log, prefixed by `who`.
    unsigned int link_program(const char* vertex_src, const char* fragment_src, const std::string& who);

private:
    void* ctx_ = nullptr;                  // OSMesaContext
    unsigned char dummy_[4 * 4 * 4] = {};  // default framebuffer (unused: callers draw into FBOs)
};

}  // namespace nurbsrt
