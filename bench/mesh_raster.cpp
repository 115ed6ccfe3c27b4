// Depth-only triangle-mesh rasterizer (see mesh_raster.h).
#include "bench/mesh_raster.h"

#include <GL/gl.h>
#include <GL/glext.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "core/error.h"
#include "renderer/map/gl_context.h"

namespace nurbsrt {
namespace {

const char* kVertexShader = R"(#version 450 core
layout(location = 0) in vec4 a_clip;
layout(location = 1) in float a_depth;
out float v_depth;
void main() {
    v_depth = a_depth;
    gl_Position = a_clip;
}
)";

// Perspective-correct interpolation (GL's default) of the depth along f.
const char* kFragmentShader = R"(#version 450 core
in float v_depth;
layout(location = 0) out float o_depth;
void main() { o_depth = v_depth; }
)";

struct Vertex {
    float clip[4];
    float depth;
};

[[noreturn]] void fail(const std::string& what) { throw Error(ErrorCode::internal, "mesh rasterizer: " + what); }

}  // namespace

struct MeshRasterizer::Impl {
    GlContext gl;
    GLuint program = 0, vao = 0, vbo = 0, ebo = 0;
    GLuint fbo = 0, tex_depth = 0, rb_depth = 0;
    int fb_w = 0, fb_h = 0;

    Impl() {
        program = gl.link_program(kVertexShader, kFragmentShader, "mesh rasterizer");
        glGenVertexArrays(1, &vao);
        glGenBuffers(1, &vbo);
        glGenBuffers(1, &ebo);
        glBindVertexArray(vao);
        glBindBuffer(GL_ARRAY_BUFFER, vbo);
        glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, ebo);
        glEnableVertexAttribArray(0);
        glVertexAttribPointer(0, 4, GL_FLOAT, GL_FALSE, sizeof(Vertex),
                              reinterpret_cast<void*>(offsetof(Vertex, clip)));
        glEnableVertexAttribArray(1);
        glVertexAttribPointer(1, 1, GL_FLOAT, GL_FALSE, sizeof(Vertex),
                              reinterpret_cast<void*>(offsetof(Vertex, depth)));
    }

    ~Impl() {
        gl.make_current();
        release_fbo();
        glDeleteBuffers(1, &vbo);
        glDeleteBuffers(1, &ebo);
        glDeleteVertexArrays(1, &vao);
        glDeleteProgram(program);
    }

    void release_fbo() {
        if (!fbo) return;
        glDeleteFramebuffers(1, &fbo);
        glDeleteTextures(1, &tex_depth);
        glDeleteRenderbuffers(1, &rb_depth);
        fbo = tex_depth = rb_depth = 0;
    }

    void ensure_fbo(int w, int h) {
        if (fbo && fb_w == w && fb_h == h) return;
        release_fbo();
        glGenFramebuffers(1, &fbo);
        glBindFramebuffer(GL_FRAMEBUFFER, fbo);
        glGenTextures(1, &tex_depth);
        glBindTexture(GL_TEXTURE_2D, tex_depth);
        glTexStorage2D(GL_TEXTURE_2D, 1, GL_R32F, w, h);
        glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, tex_depth, 0);
        glGenRenderbuffers(1, &rb_depth);
        glBindRenderbuffer(GL_RENDERBUFFER, rb_depth);
        glRenderbufferStorage(GL_RENDERBUFFER, GL_DEPTH_COMPONENT32F, w, h);
        glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, rb_depth);
        const GLenum buf = GL_COLOR_ATTACHMENT0;
        glDrawBuffers(1, &buf);
        if (glCheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE) fail("framebuffer incomplete");
        fb_w = w;
        fb_h = h;
    }
};

MeshRasterizer::MeshRasterizer() : impl_(std::make_unique<Impl>()) {}
MeshRasterizer::~MeshRasterizer() = default;

DepthImage MeshRasterizer::render(const TriangleMesh& mesh, const Camera& camera) {
    const int W = camera.width(), H = camera.height();
    impl_->gl.make_current();
    GLint max_size = 0;
    glGetIntegerv(GL_MAX_RENDERBUFFER_SIZE, &max_size);
    if (W > max_size || H > max_size)
        throw Error(ErrorCode::limit_exceeded, "mesh rasterizer: image larger than " + std::to_string(max_size));
    impl_->ensure_fbo(W, H);

    // Near/far planes around the mesh's depth range, as for the preliminary map.
    double zmin = HUGE_VAL, zmax = -HUGE_VAL;
    std::vector<double> depth(mesh.xyz.size());
    for (size_t k = 0; k < mesh.xyz.size(); ++k) {
        depth[k] = dot(camera.forward(), mesh.xyz[k] - camera.spec().eye);
        zmin = std::min(zmin, depth[k]);
        zmax = std::max(zmax, depth[k]);
    }
    double znear = 0, zfar = 0;
    if (!mesh.xyz.empty() && zmax > (camera.perspective() ? 0.0 : -HUGE_VAL)) {
        const double span = std::max(zmax - zmin, 1e-9 * std::max(1.0, std::abs(zmax)));
        zfar = zmax + 0.01 * span;
        znear = camera.perspective() ? std::max(zmin - 0.01 * span, 1e-6 * zfar) : zmin - 0.01 * span;
    }
    std::vector<Vertex> verts;
    if (zfar > znear) {
        verts.reserve(mesh.xyz.size());
        for (size_t k = 0; k < mesh.xyz.size(); ++k) {
            const Vec4 c = camera.clip(mesh.xyz[k], znear, zfar);
            verts.push_back({{float(c.x), float(c.y), float(c.z), float(c.w)}, float(depth[k])});
        }
    }

    glBindFramebuffer(GL_FRAMEBUFFER, impl_->fbo);
    glViewport(0, 0, W, H);
    glDisable(GL_CULL_FACE);
    glEnable(GL_DEPTH_TEST);
    glDepthFunc(GL_LESS);
    const GLfloat inf[4] = {std::numeric_limits<float>::infinity(), 0, 0, 0};
    const GLfloat one = 1.0f;
    glClearBufferfv(GL_COLOR, 0, inf);
    glClearBufferfv(GL_DEPTH, 0, &one);
    if (!verts.empty() && !mesh.triangles.empty()) {
        glUseProgram(impl_->program);
        glBindVertexArray(impl_->vao);
        glBindBuffer(GL_ARRAY_BUFFER, impl_->vbo);
        glBufferData(GL_ARRAY_BUFFER, verts.size() * sizeof(Vertex), verts.data(), GL_STREAM_DRAW);
        glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, impl_->ebo);
        glBufferData(GL_ELEMENT_ARRAY_BUFFER, mesh.triangles.size() * sizeof(uint32_t), mesh.triangles.data(),
                     GL_STREAM_DRAW);
        glDrawElements(GL_TRIANGLES, static_cast<GLsizei>(mesh.triangles.size()), GL_UNSIGNED_INT, nullptr);
    }
    std::vector<float> along(static_cast<size_t>(W) * H);
    glPixelStorei(GL_PACK_ALIGNMENT, 1);
    glReadBuffer(GL_COLOR_ATTACHMENT0);
    glReadPixels(0, 0, W, H, GL_RED, GL_FLOAT, along.data());
    if (glGetError() != GL_NO_ERROR) fail("OpenGL error while rendering");

    // GL row 0 is the bottom: flip to the contract's rows; depth along f -> t.
    DepthImage out;
    out.width = W;
    out.height = H;
    out.t.resize(along.size());
    for (int j = 0; j < H; ++j)
        for (int i = 0; i < W; ++i) {
            const float d = along[static_cast<size_t>(H - 1 - j) * W + i];
            out.t[static_cast<size_t>(j) * W + i] =
                std::isfinite(d) ? static_cast<float>(camera.hit_distance_from_depth(d, camera.pixel_screen(i, j))) : d;
        }
    return out;
}

}  // namespace nurbsrt
