// Preliminary map with OSMesa (see preliminary_map.h).
#include "renderer/preliminary_map.h"

#include <GL/gl.h>
#include <GL/glext.h>

#include <algorithm>
#include <cmath>
#include <string>

#include "renderer/error.h"
#include "renderer/gl_context.h"

namespace nurbsrt {

const char* map_precision_name(MapPrecision p) { return p == MapPrecision::rgb8 ? "rgb8" : "float32"; }

float quantize_rgb8(float u, double lo, double hi) {
    const double range = hi - lo;
    if (!(range > 0)) return static_cast<float>(lo);
    const double g = std::clamp(std::round(255.0 * (u - lo) / range), 0.0, 255.0);
    return static_cast<float>(range * g / 255.0 + lo);
}

namespace {

const char* kVertexShader = R"(#version 450 core
layout(location = 0) in vec4 a_clip;
layout(location = 1) in vec2 a_uv;
layout(location = 2) in uint a_face;
out vec2 v_uv;
flat out uint v_face;
void main() {
    v_uv = a_uv;
    v_face = a_face;
    gl_Position = a_clip;
}
)";

const char* kFragmentShader = R"(#version 450 core
in vec2 v_uv;
flat in uint v_face;
layout(location = 0) out uint o_face;
layout(location = 1) out vec2 o_uv;
void main() {
    o_face = v_face;
    o_uv = v_uv;
}
)";

[[noreturn]] void fail(const std::string& what) {
    throw Error(ErrorCode::internal, "preliminary map: " + what);
}

struct Vertex {
    float clip[4];
    float uv[2];
    uint32_t face;
};

}  // namespace

struct MapRenderer::Impl {
    GlContext gl;
    GLuint program = 0, vao = 0, vbo = 0, ebo = 0;
    GLuint fbo = 0, tex_face = 0, tex_uv = 0, rb_depth = 0;
    int fb_w = 0, fb_h = 0;

    Impl() {
        program = gl.link_program(kVertexShader, kFragmentShader, "preliminary map");
        glGenVertexArrays(1, &vao);
        glGenBuffers(1, &vbo);
        glGenBuffers(1, &ebo);
        glBindVertexArray(vao);
        glBindBuffer(GL_ARRAY_BUFFER, vbo);
        glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, ebo);
        glEnableVertexAttribArray(0);
        glVertexAttribPointer(0, 4, GL_FLOAT, GL_FALSE, sizeof(Vertex), reinterpret_cast<void*>(offsetof(Vertex, clip)));
        glEnableVertexAttribArray(1);
        glVertexAttribPointer(1, 2, GL_FLOAT, GL_FALSE, sizeof(Vertex), reinterpret_cast<void*>(offsetof(Vertex, uv)));
        glEnableVertexAttribArray(2);
        glVertexAttribIPointer(2, 1, GL_UNSIGNED_INT, sizeof(Vertex), reinterpret_cast<void*>(offsetof(Vertex, face)));
    }

    ~Impl() {
        make_current();
        release_fbo();
        glDeleteBuffers(1, &vbo);
        glDeleteBuffers(1, &ebo);
        glDeleteVertexArrays(1, &vao);
        glDeleteProgram(program);
    }

    void make_current() { gl.make_current(); }

    void release_fbo() {
        if (!fbo) return;
        glDeleteFramebuffers(1, &fbo);
        glDeleteTextures(1, &tex_face);
        glDeleteTextures(1, &tex_uv);
        glDeleteRenderbuffers(1, &rb_depth);
        fbo = tex_face = tex_uv = rb_depth = 0;
    }

    void ensure_fbo(int w, int h) {
        if (fbo && fb_w == w && fb_h == h) return;
        release_fbo();
        glGenFramebuffers(1, &fbo);
        glBindFramebuffer(GL_FRAMEBUFFER, fbo);
        glGenTextures(1, &tex_face);
        glBindTexture(GL_TEXTURE_2D, tex_face);
        glTexStorage2D(GL_TEXTURE_2D, 1, GL_R32UI, w, h);
        glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, tex_face, 0);
        glGenTextures(1, &tex_uv);
        glBindTexture(GL_TEXTURE_2D, tex_uv);
        glTexStorage2D(GL_TEXTURE_2D, 1, GL_RG32F, w, h);
        glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT1, GL_TEXTURE_2D, tex_uv, 0);
        glGenRenderbuffers(1, &rb_depth);
        glBindRenderbuffer(GL_RENDERBUFFER, rb_depth);
        glRenderbufferStorage(GL_RENDERBUFFER, GL_DEPTH_COMPONENT32F, w, h);
        glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, rb_depth);
        const GLenum bufs[2] = {GL_COLOR_ATTACHMENT0, GL_COLOR_ATTACHMENT1};
        glDrawBuffers(2, bufs);
        if (glCheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE) fail("framebuffer incomplete");
        fb_w = w;
        fb_h = h;
    }
};

MapRenderer::MapRenderer() : impl_(std::make_unique<Impl>()) {}
MapRenderer::~MapRenderer() = default;

PreliminaryMap MapRenderer::render(const Scene& scene, const Camera& camera, MapPrecision precision) {
    const int W = camera.width(), H = camera.height();
    GLint max_size = 0;
    impl_->make_current();
    glGetIntegerv(GL_MAX_RENDERBUFFER_SIZE, &max_size);
    if (W > max_size || H > max_size)
        throw Error(ErrorCode::limit_exceeded, "preliminary map: image larger than " + std::to_string(max_size));
    impl_->ensure_fbo(W, H);

    // Depth range along f of all mesh vertices (near/far planes of the map).
    double zmin = HUGE_VAL, zmax = -HUGE_VAL;
    size_t nv = 0, ni = 0;
    for (const Face& f : scene.faces) {
        for (const Vec3& p : f.mesh.xyz) {
            const double z = dot(camera.forward(), p - camera.spec().eye);
            zmin = std::min(zmin, z);
            zmax = std::max(zmax, z);
        }
        nv += f.mesh.xyz.size();
        ni += f.mesh.triangles.size();
    }
    double zfar = 0, znear = 0;
    if (nv > 0 && zmax > (camera.perspective() ? 0.0 : -HUGE_VAL)) {
        const double span = std::max(zmax - zmin, 1e-9 * std::max(1.0, std::abs(zmax)));
        zfar = zmax + 0.01 * span;
        znear = camera.perspective() ? std::max(zmin - 0.01 * span, 1e-6 * zfar) : zmin - 0.01 * span;
    }

    std::vector<Vertex> verts;
    std::vector<uint32_t> idx;
    if (zfar > znear) {
        verts.reserve(nv);
        idx.reserve(ni);
        for (const Face& f : scene.faces) {
            const uint32_t base = static_cast<uint32_t>(verts.size());
            const size_t n = std::min(f.mesh.xyz.size(), f.mesh.uv.size());
            for (size_t k = 0; k < n; ++k) {
                const Vec4 c = camera.clip(f.mesh.xyz[k], znear, zfar);
                verts.push_back({{float(c.x), float(c.y), float(c.z), float(c.w)},
                                 {float(f.mesh.uv[k].x), float(f.mesh.uv[k].y)}, f.index});
            }
            for (size_t k = 0; k + 2 < f.mesh.triangles.size(); k += 3) {
                const uint32_t a = f.mesh.triangles[k], b = f.mesh.triangles[k + 1], c = f.mesh.triangles[k + 2];
                if (a >= n || b >= n || c >= n) continue;  // malformed triangle: skip
                idx.insert(idx.end(), {base + a, base + b, base + c});
            }
        }
    }
    last_triangles_ = idx.size() / 3;

    glBindFramebuffer(GL_FRAMEBUFFER, impl_->fbo);
    glViewport(0, 0, W, H);
    glDisable(GL_CULL_FACE);
    glEnable(GL_DEPTH_TEST);
    glDepthFunc(GL_LESS);
    const GLuint zero_u[4] = {0, 0, 0, 0};
    const GLfloat zero_f[4] = {0, 0, 0, 0};
    const GLfloat one = 1.0f;
    glClearBufferuiv(GL_COLOR, 0, zero_u);
    glClearBufferfv(GL_COLOR, 1, zero_f);
    glClearBufferfv(GL_DEPTH, 0, &one);
    if (!idx.empty()) {
        glUseProgram(impl_->program);
        glBindVertexArray(impl_->vao);
        glBindBuffer(GL_ARRAY_BUFFER, impl_->vbo);
        glBufferData(GL_ARRAY_BUFFER, verts.size() * sizeof(Vertex), verts.data(), GL_STREAM_DRAW);
        glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, impl_->ebo);
        glBufferData(GL_ELEMENT_ARRAY_BUFFER, idx.size() * sizeof(uint32_t), idx.data(), GL_STREAM_DRAW);
        glDrawElements(GL_TRIANGLES, static_cast<GLsizei>(idx.size()), GL_UNSIGNED_INT, nullptr);
    }

    PreliminaryMap map;
    map.width = W;
    map.height = H;
    const size_t npx = static_cast<size_t>(W) * H;
    std::vector<uint32_t> ids(npx);
    std::vector<float> uv(2 * npx);
    glPixelStorei(GL_PACK_ALIGNMENT, 1);
    glReadBuffer(GL_COLOR_ATTACHMENT0);
    glReadPixels(0, 0, W, H, GL_RED_INTEGER, GL_UNSIGNED_INT, ids.data());
    glReadBuffer(GL_COLOR_ATTACHMENT1);
    glReadPixels(0, 0, W, H, GL_RG, GL_FLOAT, uv.data());
    if (glGetError() != GL_NO_ERROR) fail("OpenGL error while rendering");

    // GL row 0 is the bottom: flip to the contract's row order. rgb8: eq. (4).
    map.face.resize(npx);
    map.u.resize(npx);
    map.v.resize(npx);
    for (int j = 0; j < H; ++j) {
        const size_t src = static_cast<size_t>(H - 1 - j) * W, dst = static_cast<size_t>(j) * W;
        for (int i = 0; i < W; ++i) {
            const uint32_t id = ids[src + i];
            float u = uv[2 * (src + i)], v = uv[2 * (src + i) + 1];
            if (precision == MapPrecision::rgb8 && id >= 1 && id <= scene.faces.size()) {
                const Face& f = scene.faces[id - 1];
                u = quantize_rgb8(u, f.u_min, f.u_max);
                v = quantize_rgb8(v, f.v_min, f.v_max);
            }
            map.face[dst + i] = id;
            map.u[dst + i] = u;
            map.v[dst + i] = v;
        }
    }
    return map;
}

PreliminaryMap render_preliminary_map(const Scene& scene, const Camera& camera, MapPrecision precision) {
    thread_local MapRenderer renderer;
    return renderer.render(scene, camera, precision);
}

}  // namespace nurbsrt
