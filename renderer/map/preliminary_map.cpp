// Preliminary map with OSMesa (see preliminary_map.h).
#include "renderer/map/preliminary_map.h"

#include <GL/gl.h>
#include <GL/glext.h>

#include <sys/resource.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <map>
#include <memory>
#include <mutex>
#include <string>

#include "core/error.h"
#include "renderer/map/gl_context.h"
#include "renderer/solve/prepared_data.h"

namespace nurbsrt {

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
layout(location = 1) out float o_u;
layout(location = 2) out float o_v;
void main() {
    o_face = v_face;
    o_u = v_uv.x;
    o_v = v_uv.y;
}
)";

// With section planes (section.h): each vertex carries its signed distance from
// up to six planes (positive on the removed side), interpolated across the
// triangle, and fragments on the removed side are discarded. A distance is
// affine in the model point, so its perspective-correct interpolation is the
// fragment's own distance (up to float rounding): the map is clipped to the
// mesh's exact cut. Discarding rather than gl_ClipDistance, because a cut-away
// (removing the planes' intersection) keeps a union of half-spaces, which
// clipping (an intersection) cannot express.
const char* kCutVertexShader = R"(#version 450 core
layout(location = 0) in vec4 a_clip;
layout(location = 1) in vec2 a_uv;
layout(location = 2) in uint a_face;
layout(location = 3) in vec3 a_d0;
layout(location = 4) in vec3 a_d1;
layout(location = 5) in uint a_body;
out vec2 v_uv;
out vec3 v_d0;
out vec3 v_d1;
flat out uint v_face;
flat out uint v_body;
void main() {
    v_uv = a_uv;
    v_face = a_face;
    v_body = a_body;
    v_d0 = a_d0;
    v_d1 = a_d1;
    gl_Position = a_clip;
}
)";

// The removal test of the sectioned programs' fragment shaders.
#define NURBSRT_SECTION_DISCARD                                                    \
    "    float d[6] = float[6](v_d0.x, v_d0.y, v_d0.z, v_d1.x, v_d1.y, v_d1.z);\n" \
    "    bool any_removed = false, all_removed = true;\n"                          \
    "    for (int k = 0; k < u_planes; ++k) {\n"                                   \
    "        bool removed = d[k] > 0.0;\n"                                         \
    "        any_removed = any_removed || removed;\n"                              \
    "        all_removed = all_removed && removed;\n"                              \
    "    }\n"                                                                      \
    "    if (u_cutaway ? all_removed : any_removed) discard;\n"

const char* kCutFragmentShader =
    "#version 450 core\n"
    "in vec2 v_uv;\n"
    "in vec3 v_d0;\n"
    "in vec3 v_d1;\n"
    "flat in uint v_face;\n"
    "uniform int u_planes;\n"
    "uniform bool u_cutaway;\n"
    "layout(location = 0) out uint o_face;\n"
    "layout(location = 1) out float o_u;\n"
    "layout(location = 2) out float o_v;\n"
    "void main() {\n" NURBSRT_SECTION_DISCARD
    "    o_face = v_face;\n"
    "    o_u = v_uv.x;\n"
    "    o_v = v_uv.y;\n"
    "}\n";

// The inside layer of a sectioned frame with caps (PreliminaryMap::inside):
// every kept fragment of a closed body XORs 1 + the body's index into the
// pixel (GL_XOR logic op, no depth test), so that a pixel ends with 1 + the
// closed body holding the ray where it enters the kept space (each body the ray
// crosses an even number of times there cancels out), or 0 outside all of them.
// A body's index travels as the face id does (a flat integer attribute of
// kCutVertexShader, which both sectioned programs share; 0 for faces of open
// bodies, which XOR nothing).
const char* kInsideFragmentShader =
    "#version 450 core\n"
    "in vec3 v_d0;\n"
    "in vec3 v_d1;\n"
    "flat in uint v_body;\n"
    "uniform int u_planes;\n"
    "uniform bool u_cutaway;\n"
    "layout(location = 0) out uint o_inside;\n"
    "void main() {\n" NURBSRT_SECTION_DISCARD
    "    o_inside = v_body;\n"
    "}\n";
#undef NURBSRT_SECTION_DISCARD

// A band read back bottom row first, its rows swapped end for end into the
// map's top-first order.
template <class T>
void flip_rows(T* block, int rows, size_t width) {
    for (int r = 0; r < rows / 2; ++r)
        std::swap_ranges(block + r * width, block + (r + 1) * width, block + (rows - 1 - r) * width);
}

[[noreturn]] void fail(const std::string& what) { throw Error(ErrorCode::internal, "preliminary map: " + what); }

// Map mesh vertex k where the frame shows it: moved with its face by the
// offsets (MapClip::offsets), if any.
struct MovedVertices {
    const MapMesh& mesh;
    const std::vector<Vec3>* offsets;  // null: none
    Vec3 operator()(size_t k) const { return offsets ? mesh.xyz[k] + (*offsets)[mesh.face[k] - 1] : mesh.xyz[k]; }
};

}  // namespace

struct MapRenderer::Impl {
    GlContext gl;
    GLuint program = 0, vao = 0;
    // The sectioned frames' programs (kCutVertexShader, kInsideVertexShader) and their uniforms.
    GLuint cut_program = 0, inside_program = 0;
    GLint cut_planes = -1, cut_cutaway = -1, inside_planes = -1, inside_cutaway = -1;
    // vbo_clip: clip-space positions, rewritten every frame; vbo_uv, vbo_face and
    // ebo: the map mesh's camera-independent data of PreparedScene `uploaded`;
    // vbo_dist: the section planes' distances of a sectioned frame (6 a vertex).
    // vbo_body: per vertex 1 + its closed body, 0 for open ones (the inside layer).
    GLuint vbo_clip = 0, vbo_uv = 0, vbo_face = 0, ebo = 0, vbo_dist = 0, vbo_body = 0;
    uint64_t uploaded = 0;  // PreparedScene::id of the static buffers' contents, 0: none
    // One attachment per map array (face, u, v), so that each is read back
    // straight into its PreliminaryMap vector, with no interleaved copy to split.
    GLuint fbo = 0, tex_face = 0, tex_u = 0, tex_v = 0, rb_depth = 0;
    int fb_w = 0, fb_h = 0;
    GLuint fbo_inside = 0, tex_inside = 0;  // the inside layer's, made for the first frame with caps
    int inside_w = 0, inside_h = 0;

    Impl() {
        program = gl.link_program(kVertexShader, kFragmentShader, "preliminary map");
        cut_program = gl.link_program(kCutVertexShader, kCutFragmentShader, "sectioned preliminary map");
        cut_planes = glGetUniformLocation(cut_program, "u_planes");
        cut_cutaway = glGetUniformLocation(cut_program, "u_cutaway");
        inside_program = gl.link_program(kCutVertexShader, kInsideFragmentShader, "inside layer");
        inside_planes = glGetUniformLocation(inside_program, "u_planes");
        inside_cutaway = glGetUniformLocation(inside_program, "u_cutaway");
        glGenVertexArrays(1, &vao);
        GLuint bufs[6];
        glGenBuffers(6, bufs);
        vbo_body = bufs[5];
        vbo_clip = bufs[0];
        vbo_uv = bufs[1];
        vbo_face = bufs[2];
        ebo = bufs[3];
        vbo_dist = bufs[4];
        glBindVertexArray(vao);
        glBindBuffer(GL_ARRAY_BUFFER, vbo_clip);
        glEnableVertexAttribArray(0);
        glVertexAttribPointer(0, 4, GL_FLOAT, GL_FALSE, 4 * sizeof(float), nullptr);
        glBindBuffer(GL_ARRAY_BUFFER, vbo_uv);
        glEnableVertexAttribArray(1);
        glVertexAttribPointer(1, 2, GL_FLOAT, GL_FALSE, 2 * sizeof(float), nullptr);
        glBindBuffer(GL_ARRAY_BUFFER, vbo_face);
        glEnableVertexAttribArray(2);
        glVertexAttribIPointer(2, 1, GL_UNSIGNED_INT, sizeof(uint32_t), nullptr);
        // Attributes 3 and 4 are enabled only for sectioned frames (set_sections).
        glBindBuffer(GL_ARRAY_BUFFER, vbo_dist);
        glVertexAttribPointer(3, 3, GL_FLOAT, GL_FALSE, 6 * sizeof(float), nullptr);
        glVertexAttribPointer(4, 3, GL_FLOAT, GL_FALSE, 6 * sizeof(float),
                              reinterpret_cast<const void*>(3 * sizeof(float)));
        glBindBuffer(GL_ARRAY_BUFFER, vbo_body);
        glVertexAttribIPointer(5, 1, GL_UNSIGNED_INT, sizeof(uint32_t), nullptr);
        glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, ebo);  // part of the VAO's state
        gl.release_current();
    }

    // The static buffers of `ps`, uploaded unless they already hold them.
    void upload_static(const PreparedScene& ps) {
        if (uploaded == ps.id()) return;
        const MapMesh& m = ps.map_mesh();
        glBindBuffer(GL_ARRAY_BUFFER, vbo_uv);
        glBufferData(GL_ARRAY_BUFFER, m.uv.size() * sizeof(float), m.uv.data(), GL_STATIC_DRAW);
        glBindBuffer(GL_ARRAY_BUFFER, vbo_face);
        glBufferData(GL_ARRAY_BUFFER, m.face.size() * sizeof(uint32_t), m.face.data(), GL_STATIC_DRAW);
        glBindVertexArray(vao);
        glBufferData(GL_ELEMENT_ARRAY_BUFFER, m.indices.size() * sizeof(uint32_t), m.indices.data(), GL_STATIC_DRAW);
        uploaded = ps.id();
    }

    // The element buffer holding only the triangles of faces not hidden (a
    // triangle's vertices all belong to one face); the next frame uploads the
    // whole list again (upload_static). Returns the index count.
    GLsizei upload_shown(const PreparedScene& ps, const std::vector<uint8_t>& hidden) {
        const MapMesh& m = ps.map_mesh();
        std::vector<uint32_t> shown;
        shown.reserve(m.indices.size());
        for (size_t t = 0; t + 2 < m.indices.size(); t += 3) {
            const uint32_t f = m.face[m.indices[t]];
            if (f >= 1 && f <= hidden.size() && hidden[f - 1]) continue;
            shown.insert(shown.end(), m.indices.begin() + static_cast<std::ptrdiff_t>(t),
                         m.indices.begin() + static_cast<std::ptrdiff_t>(t + 3));
        }
        glBindVertexArray(vao);
        glBufferData(GL_ELEMENT_ARRAY_BUFFER, shown.size() * sizeof(uint32_t), shown.data(), GL_STREAM_DRAW);
        uploaded = 0;
        return static_cast<GLsizei>(shown.size());
    }

    ~Impl() {
        make_current();
        release_fbo();
        release_inside_fbo();
        const GLuint bufs[6] = {vbo_clip, vbo_uv, vbo_face, ebo, vbo_dist, vbo_body};
        glDeleteBuffers(6, bufs);
        glDeleteVertexArrays(1, &vao);
        glDeleteProgram(program);
        glDeleteProgram(cut_program);
        glDeleteProgram(inside_program);
        gl.release_current();
    }

    void make_current() { gl.make_current(); }

    // Selects the program of a frame with or without section planes, and for one
    // with them uploads every vertex's distances (in double, then float).
    void use_program(const PreparedScene& ps, const MapMesh& mesh, const Sections* sections, const MovedVertices& at) {
        const bool cut = sections && sections->active();
        glBindVertexArray(vao);
        if (!cut) {
            glDisableVertexAttribArray(3);
            glDisableVertexAttribArray(4);
            glDisableVertexAttribArray(5);
            glUseProgram(program);
            return;
        }
        const size_t planes = std::min(sections->planes.size(), kMaxSectionPlanes);
        std::vector<float> dist(6 * mesh.xyz.size(), 0.0f);
        for (size_t k = 0; k < mesh.xyz.size(); ++k)
            for (size_t p = 0; p < planes; ++p)
                dist[6 * k + p] = static_cast<float>(sections->planes[p].distance(at(k)));
        glBindBuffer(GL_ARRAY_BUFFER, vbo_dist);
        glBufferData(GL_ARRAY_BUFFER, dist.size() * sizeof(float), dist.data(), GL_STREAM_DRAW);
        glEnableVertexAttribArray(3);
        glEnableVertexAttribArray(4);
        const GLint cutaway = sections->mode == SectionMode::cutaway ? 1 : 0;
        glDisableVertexAttribArray(5);
        if (sections->caps) {
            const Scene& scene = ps.scene();
            std::vector<uint32_t> body(mesh.face.size(), 0);
            for (size_t k = 0; k < mesh.face.size(); ++k) {
                const uint32_t f = mesh.face[k];
                if (f < 1 || f > scene.faces.size()) continue;
                const uint32_t b = scene.faces[f - 1].body;
                if (b < scene.bodies.size() && scene.bodies[b].closed) body[k] = b + 1;
            }
            glBindBuffer(GL_ARRAY_BUFFER, vbo_body);
            glBufferData(GL_ARRAY_BUFFER, body.size() * sizeof(uint32_t), body.data(), GL_STREAM_DRAW);
            glEnableVertexAttribArray(5);
            glUseProgram(inside_program);
            glUniform1i(inside_planes, static_cast<GLint>(planes));
            glUniform1i(inside_cutaway, cutaway);
        }
        glUseProgram(cut_program);
        glUniform1i(cut_planes, static_cast<GLint>(planes));
        glUniform1i(cut_cutaway, cutaway);
    }

    // The inside layer of one band (kInsideFragmentShader) into its own
    // framebuffer, read into map.inside like the other layers.
    void draw_inside(PreliminaryMap& map, int y_lo, int rows, GLsizei indices) {
        ensure_inside_fbo(fb_w, fb_h);
        glBindFramebuffer(GL_FRAMEBUFFER, fbo_inside);
        const GLuint zero[4] = {0, 0, 0, 0};
        glClearBufferuiv(GL_COLOR, 0, zero);
        glUseProgram(inside_program);
        glDisable(GL_DEPTH_TEST);
        glEnable(GL_COLOR_LOGIC_OP);
        glLogicOp(GL_XOR);
        glDrawElements(GL_TRIANGLES, indices, GL_UNSIGNED_INT, nullptr);
        glDisable(GL_COLOR_LOGIC_OP);
        glEnable(GL_DEPTH_TEST);
        const size_t W = static_cast<size_t>(map.width);
        uint32_t* block = map.inside.data() + static_cast<size_t>(map.height - y_lo - rows) * W;
        glPixelStorei(GL_PACK_ALIGNMENT, 1);
        glReadBuffer(GL_COLOR_ATTACHMENT0);
        glReadPixels(0, 0, map.width, rows, GL_RED_INTEGER, GL_UNSIGNED_INT, block);
        flip_rows(block, rows, W);
        glUseProgram(cut_program);
        glBindFramebuffer(GL_FRAMEBUFFER, fbo);
    }

    void ensure_inside_fbo(int w, int h) {
        if (fbo_inside && inside_w == w && inside_h == h) return;
        release_inside_fbo();
        glGenFramebuffers(1, &fbo_inside);
        glBindFramebuffer(GL_FRAMEBUFFER, fbo_inside);
        glGenTextures(1, &tex_inside);
        glBindTexture(GL_TEXTURE_2D, tex_inside);
        glTexStorage2D(GL_TEXTURE_2D, 1, GL_R32UI, w, h);
        glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, tex_inside, 0);
        const GLenum buf = GL_COLOR_ATTACHMENT0;
        glDrawBuffers(1, &buf);
        if (glCheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE) fail("inside framebuffer incomplete");
        inside_w = w;
        inside_h = h;
    }

    void release_inside_fbo() {
        if (!fbo_inside) return;
        glDeleteFramebuffers(1, &fbo_inside);
        glDeleteTextures(1, &tex_inside);
        fbo_inside = tex_inside = 0;
    }

    void release_fbo() {
        if (!fbo) return;
        glDeleteFramebuffers(1, &fbo);
        const GLuint tex[3] = {tex_face, tex_u, tex_v};
        glDeleteTextures(3, tex);
        glDeleteRenderbuffers(1, &rb_depth);
        fbo = tex_face = tex_u = tex_v = rb_depth = 0;
    }

    void ensure_fbo(int w, int h) {
        if (fbo && fb_w == w && fb_h == h) return;
        release_fbo();
        glGenFramebuffers(1, &fbo);
        glBindFramebuffer(GL_FRAMEBUFFER, fbo);
        GLuint* const tex[3] = {&tex_face, &tex_u, &tex_v};
        const GLenum formats[3] = {GL_R32UI, GL_R32F, GL_R32F};
        for (int a = 0; a < 3; ++a) {
            glGenTextures(1, tex[a]);
            glBindTexture(GL_TEXTURE_2D, *tex[a]);
            glTexStorage2D(GL_TEXTURE_2D, 1, formats[a], w, h);
            glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0 + a, GL_TEXTURE_2D, *tex[a], 0);
        }
        glGenRenderbuffers(1, &rb_depth);
        glBindRenderbuffer(GL_RENDERBUFFER, rb_depth);
        glRenderbufferStorage(GL_RENDERBUFFER, GL_DEPTH_COMPONENT32F, w, h);
        glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, rb_depth);
        const GLenum bufs[3] = {GL_COLOR_ATTACHMENT0, GL_COLOR_ATTACHMENT1, GL_COLOR_ATTACHMENT2};
        glDrawBuffers(3, bufs);
        if (glCheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE) fail("framebuffer incomplete");
        fb_w = w;
        fb_h = h;
    }
};

MapRenderer::MapRenderer() : impl_(std::make_unique<Impl>()) {}
MapRenderer::~MapRenderer() = default;

namespace {

// Near and far depth along f for the map: every mesh vertex's depth with a 1%
// margin of the depth span, so no triangle is clipped by the depth range
// (perspective: the near plane stays in front of the eye). far <= near: nothing
// to draw (empty scene, or all of it behind a perspective eye).
void depth_range(const MapMesh& mesh, const MovedVertices& at, const Camera& camera, double& znear, double& zfar) {
    double zmin = HUGE_VAL, zmax = -HUGE_VAL;
    const size_t nv = mesh.xyz.size();
    for (size_t k = 0; k < nv; ++k) {
        const double z = dot(camera.forward(), at(k) - camera.spec().eye);
        zmin = std::min(zmin, z);
        zmax = std::max(zmax, z);
    }
    zfar = znear = 0;
    if (nv > 0 && zmax > (camera.perspective() ? 0.0 : -HUGE_VAL)) {
        const double span = std::max(zmax - zmin, 1e-9 * std::max(1.0, std::abs(zmax)));
        zfar = zmax + 0.01 * span;
        znear = camera.perspective() ? std::max(zmin - 0.01 * span, 1e-6 * zfar) : zmin - 0.01 * span;
    }
}

// Reads the `rows` framebuffer rows of the band whose bottom is GL window row
// y_lo into the map. GL row 0 is the bottom: the band's rows are the map's rows
// H - y_lo - rows .. H - y_lo - 1 in reverse order, so each attachment is read
// straight into that block of its map vector and the block's rows are then
// swapped end for end (a copy through a read buffer and a per-pixel loop were
// 2-3 % of a frame). rgb8: eq. (4).
void read_back_band(PreliminaryMap& map, int y_lo, int rows, const Scene& scene, MapPrecision precision) {
    const size_t W = static_cast<size_t>(map.width);
    const size_t first = static_cast<size_t>(map.height - y_lo - rows) * W, npx = W * rows;
    glPixelStorei(GL_PACK_ALIGNMENT, 1);
    glReadBuffer(GL_COLOR_ATTACHMENT0);
    glReadPixels(0, 0, map.width, rows, GL_RED_INTEGER, GL_UNSIGNED_INT, map.face.data() + first);
    glReadBuffer(GL_COLOR_ATTACHMENT1);
    glReadPixels(0, 0, map.width, rows, GL_RED, GL_FLOAT, map.u.data() + first);
    glReadBuffer(GL_COLOR_ATTACHMENT2);
    glReadPixels(0, 0, map.width, rows, GL_RED, GL_FLOAT, map.v.data() + first);
    if (glGetError() != GL_NO_ERROR) fail("OpenGL error while rendering");
    flip_rows(map.face.data() + first, rows, W);
    flip_rows(map.u.data() + first, rows, W);
    flip_rows(map.v.data() + first, rows, W);
    if (precision != MapPrecision::rgb8) return;
    for (size_t k = first; k < first + npx; ++k) {
        const uint32_t id = map.face[k];
        if (id < 1 || id > scene.faces.size()) continue;
        const Face& f = scene.faces[id - 1];
        map.u[k] = quantize_rgb8(map.u[k], f.u_min, f.u_max);
        map.v[k] = quantize_rgb8(map.v[k], f.v_min, f.v_max);
    }
}

// Releases the context on every exit of a frame, so the next user may be another thread.
struct ReleaseOnExit {
    GlContext& gl;
    ~ReleaseOnExit() { gl.release_current(); }
};

}  // namespace

PreliminaryMap MapRenderer::render(const PreparedScene& ps, const Camera& camera, MapPrecision precision,
                                   const MapBands& bands, const MapClip& left_out) {
    const Sections* sections = left_out.sections;
    const int W = camera.width(), H = camera.height();
    GLint max_size = 0, max_viewport[2] = {0, 0};
    impl_->make_current();
    const ReleaseOnExit release{impl_->gl};
    glGetIntegerv(GL_MAX_RENDERBUFFER_SIZE, &max_size);
    glGetIntegerv(GL_MAX_VIEWPORT_DIMS, max_viewport);
    if (W > std::min(max_size, max_viewport[0]) || H > max_viewport[1])
        throw Error(ErrorCode::limit_exceeded,
                    "preliminary map: image larger than " + std::to_string(std::min(max_size, max_viewport[0])));
    const int band_rows = static_cast<int>(std::clamp<size_t>(
        bands.rows > 0 ? size_t(bands.rows) : kMapBandPixels / size_t(W), 1, size_t(std::min(H, max_size))));
    impl_->ensure_fbo(W, band_rows);

    const MapMesh& mesh = ps.map_mesh();
    const MovedVertices at{mesh, left_out.offsets && !left_out.offsets->empty() ? left_out.offsets : nullptr};
    double znear = 0, zfar = 0;
    depth_range(mesh, at, camera, znear, zfar);
    bool draw = zfar > znear && !mesh.indices.empty();
    GLsizei drawn = static_cast<GLsizei>(mesh.indices.size());

    glBindFramebuffer(GL_FRAMEBUFFER, impl_->fbo);
    glDisable(GL_CULL_FACE);
    glEnable(GL_DEPTH_TEST);
    glDepthFunc(GL_LESS);
    if (draw) {
        // Positions to clip space on the CPU in double, relative to the eye
        // (Camera::clip), rounded to float only at the end (see the header).
        std::vector<float> clip(4 * mesh.xyz.size());
        for (size_t k = 0; k < mesh.xyz.size(); ++k) {
            const Vec4 c = camera.clip(at(k), znear, zfar);
            clip[4 * k] = float(c.x);
            clip[4 * k + 1] = float(c.y);
            clip[4 * k + 2] = float(c.z);
            clip[4 * k + 3] = float(c.w);
        }
        impl_->upload_static(ps);
        if (left_out.hidden_faces && !left_out.hidden_faces->empty())
            drawn = impl_->upload_shown(ps, *left_out.hidden_faces);
        draw = drawn > 0;
        impl_->use_program(ps, mesh, sections, at);
        glBindBuffer(GL_ARRAY_BUFFER, impl_->vbo_clip);
        glBufferData(GL_ARRAY_BUFFER, clip.size() * sizeof(float), clip.data(), GL_STREAM_DRAW);
    }

    last_triangles_ = draw ? static_cast<size_t>(drawn) / 3 : 0;
    PreliminaryMap map;
    map.width = W;
    map.height = H;
    const size_t npx = static_cast<size_t>(W) * H;
    map.face.resize(npx);
    map.u.resize(npx);
    map.v.resize(npx);
    const bool inside = draw && sections && sections->active() && sections->caps;
    if (inside) map.inside.resize(npx);
    // Bands bottom-up in GL's rows. The whole frame's viewport, shifted so that
    // the band's bottom row lands on framebuffer row 0: the same integer shift
    // for every vertex, so each pixel of a band sees the same clip-space
    // geometry as in one frame-sized draw.
    for (int y_lo = 0; y_lo < H; y_lo += band_rows) {
        if (bands.cancel && bands.cancel->load(std::memory_order_relaxed))
            throw Error(ErrorCode::canceled, "the render was canceled");
        const int rows = std::min(band_rows, H - y_lo);
        glViewport(0, -y_lo, W, H);
        const GLuint zero_u[4] = {0, 0, 0, 0};
        const GLfloat zero_f[4] = {0, 0, 0, 0};  // u and v where no face is drawn
        const GLfloat one = 1.0f;
        glClearBufferuiv(GL_COLOR, 0, zero_u);
        glClearBufferfv(GL_COLOR, 1, zero_f);
        glClearBufferfv(GL_COLOR, 2, zero_f);
        glClearBufferfv(GL_DEPTH, 0, &one);
        if (draw) glDrawElements(GL_TRIANGLES, drawn, GL_UNSIGNED_INT, nullptr);
        read_back_band(map, y_lo, rows, ps.scene(), precision);
        if (inside) impl_->draw_inside(map, y_lo, rows, drawn);
    }
    return map;
}

namespace {

// Idle MapRenderers (see the thread rules in the header). Deliberately never
// destroyed: contexts outlive every render, and destroying OSMesa contexts from a
// static destructor would race with Mesa's own teardown at exit.
// Pooled by the niceness of the thread that made the renderer: llvmpipe starts
// a context's rasterizer threads with it, and they keep the niceness of that
// thread (Linux's nice is per thread, inherited at creation). A context made
// by a niced batch render would draw an interactive frame's map at the batch's
// niceness, and the other way round; so a thread takes a renderer of its own
// niceness, or makes one.
class MapRendererPool {
public:
    size_t idle() {
        std::lock_guard<std::mutex> lock(m_);
        return idle_.size();
    }
    std::unique_ptr<MapRenderer> acquire() {
        const int nice = current_nice();
        {
            std::lock_guard<std::mutex> lock(m_);
            for (size_t i = idle_.size(); i-- > 0;) {
                if (idle_[i].nice != nice) continue;
                std::unique_ptr<MapRenderer> r = std::move(idle_[i].renderer);
                idle_.erase(idle_.begin() + static_cast<std::ptrdiff_t>(i));
                return r;
            }
        }
        auto r = std::make_unique<MapRenderer>();
        std::lock_guard<std::mutex> lock(m_);
        made_by_[r.get()] = nice;
        return r;
    }
    void release(std::unique_ptr<MapRenderer> r) {
        std::lock_guard<std::mutex> lock(m_);
        const int nice = made_by_[r.get()];
        idle_.push_back({nice, std::move(r)});
    }

private:
    static int current_nice() {
        errno = 0;
        const int n = getpriority(PRIO_PROCESS, static_cast<id_t>(syscall(SYS_gettid)));
        return errno == 0 ? n : 0;
    }
    struct Idle {
        int nice = 0;
        std::unique_ptr<MapRenderer> renderer;
    };
    std::mutex m_;
    std::vector<Idle> idle_;  // most recently released last
    // The niceness each renderer was made at; renderers are never destroyed (nor is the pool).
    std::map<const MapRenderer*, int> made_by_;
};

MapRendererPool& map_renderer_pool() {
    static MapRendererPool* pool = new MapRendererPool;
    return *pool;
}

// The scene warm_up_preliminary_maps draws: one flat bilinear face, the unit
// square in z = 0, meshed as two triangles. Prepared once.
const PreparedScene& warm_up_scene() {
    static const PreparedScene* prepared = [] {
        auto scene = std::make_shared<Scene>();
        Face f;
        f.index = 1;
        f.surface.degree_u = f.surface.degree_v = 1;
        f.surface.num_u = f.surface.num_v = 2;
        f.surface.knots_u = f.surface.knots_v = {0, 0, 1, 1};
        f.surface.cp = {{0, 0, 0, 1}, {0, 1, 0, 1}, {1, 0, 0, 1}, {1, 1, 0, 1}};
        f.u_max = f.v_max = 1;
        f.mesh.uv = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
        f.mesh.xyz = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
        f.mesh.triangles = {0, 1, 2, 0, 2, 3};
        scene->faces.push_back(std::move(f));
        scene->bodies.push_back({});
        for (const Vec3& p : scene->faces[0].mesh.xyz) scene->bbox.extend(p);
        return new PreparedScene(prepare(std::shared_ptr<const Scene>(std::move(scene)), 1));
    }();
    return *prepared;
}

}  // namespace

PreliminaryMap render_preliminary_map(const PreparedScene& scene, const Camera& camera, MapPrecision precision,
                                      const MapBands& bands, const MapClip& clip) {
    MapRendererPool& pool = map_renderer_pool();
    std::unique_ptr<MapRenderer> renderer = pool.acquire();
    // A renderer whose frame threw goes back too: every error path leaves its
    // context released and its state reset by the next frame's set-up.
    struct GiveBack {
        MapRendererPool& pool;
        std::unique_ptr<MapRenderer>& r;
        ~GiveBack() { pool.release(std::move(r)); }
    } give_back{pool, renderer};
    return renderer->render(scene, camera, precision, bands, clip);
}

void warm_up_preliminary_maps(int count, int width, int height) {
    try {
        const PreparedScene& scene = warm_up_scene();
        CameraSpec spec;
        spec.eye = {0.5, 0.5, 3};
        spec.target = {0.5, 0.5, 0};
        spec.width = std::max(width, 1);
        spec.height = std::max(height, 1);
        const Camera camera(spec);
        MapRendererPool& pool = map_renderer_pool();
        // All held at once, so that each is a renderer of its own, not the first one again.
        std::vector<std::unique_ptr<MapRenderer>> held;
        for (int k = 0; k < count; ++k) {
            held.push_back(pool.acquire());
            held.back()->render(scene, camera, MapPrecision::float32);
        }
        for (std::unique_ptr<MapRenderer>& r : held) pool.release(std::move(r));
    } catch (const std::exception&) {
        // No OpenGL here: the first frame says so, with its own error.
    }
}

size_t idle_map_renderers() { return map_renderer_pool().idle(); }

PreliminaryMap render_preliminary_map(const Scene& scene, const Camera& camera, MapPrecision precision) {
    return render_preliminary_map(prepare(scene), camera, precision);
}

}  // namespace nurbsrt
