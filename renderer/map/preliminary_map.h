// The preliminary map (Sisojevs & Glazs 2010, "Preprocessing", eq. 4): every face's (u,v) mesh
// is rasterized with OpenGL into a face-id buffer and a (u,v) buffer, so each
// pixel gets the face it most likely hits and a start (u0, v0) for Newton.
//
// Rendering is offscreen with OSMesa (Mesa llvmpipe), OpenGL 4.5 core, into a
// framebuffer object with GL_R32UI face ids (Face::index, 0 = background),
// GL_R32F u and v (one attachment each, read straight into the map's arrays)
// and GL_DEPTH_COMPONENT32F depth (float attachments read back bit-exact through glReadPixels on llvmpipe). The paper
// packs the patch number and u, v into 8-bit RGB channels;
// here ids are 32-bit and u, v float by default, and MapPrecision::rgb8 reproduces
// the paper's 8-bit quantization of eq. (4) on readback, for comparison.
//
// Geometry goes through Camera::clip, so GL pixel centres are exactly the
// contract's pixel rays (row 0 of the map is the contract's top row j = 0).
// Vertices are transformed to clip space on the CPU in double precision
// (relative to the eye), so large model coordinates lose nothing before the
// float conversion.
//
// Thread rules (OSMesa: a context is current in at most one thread at a time,
// and may move between threads when released first):
//  - A MapRenderer owns one OSMesa context with its compiled shaders, buffers
//    and framebuffer; it is used by one thread at a time. Each render() makes
//    its context current and releases it at the end, so any thread may use the
//    renderer next.
//  - render_preliminary_map() borrows a MapRenderer from a process-wide pool and
//    returns it after the frame: contexts are created (and shaders compiled) only
//    when more maps are drawn at once than ever before, not per frame or per
//    thread (the server renders each request on a fresh thread).
//  - A MapRenderer keeps the map mesh's camera-independent vertex data (u, v,
//    face id, triangle indices) of the last PreparedScene it drew in GPU buffers
//    (keyed by PreparedScene::id); a frame of the same prepared scene uploads
//    only the clip-space positions.
//  - The framebuffer holds one band of rows (kMapBandPixels below): frames
//    taller than a band are drawn band by band, the cancel flag checked between.
//  - llvmpipe starts its own rasterizer threads per context; LP_NUM_THREADS
//    (read by Mesa at start-up) sets their number, 0 rasterizes in the calling thread.
#pragma once

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <string_view>
#include <vector>

#include "renderer/camera.h"
#include "renderer/method.h"
#include "renderer/section.h"
#include "core/scene/scene.h"

namespace nurbsrt {

class PreparedScene;

struct PreliminaryMap {
    int width = 0, height = 0;
    std::vector<uint32_t> face;  // width * height, row-major, row 0 = top; 0 = background
    std::vector<float> u, v;     // start parameters where face != 0
    // Sectioned frames with caps only (else empty): 1 + the closed body whose
    // inside the pixel's ray enters the kept space in, by the map meshes'
    // crossings (kInsideFragmentShader); 0 for none.
    std::vector<uint32_t> inside;
    size_t index(int i, int j) const { return static_cast<size_t>(j) * width + i; }
};

// Frames taller than this many pixels' worth of rows are drawn in horizontal
// bands, each a draw of the whole map mesh into a band-sized framebuffer. 4
// Mpixel (a 2048^2 frame is one band) keeps the framebuffer at 64 MiB however
// large the image, and bounds the uninterruptible part of a map (one OpenGL
// draw and readback) to ~0.2 s of llvmpipe, so that a canceled 25-Mpixel frame
// stops within one band; the mesh's vertex work is repeated per band, a small
// share at these sizes.
inline constexpr size_t kMapBandPixels = size_t(1) << 22;

// What a frame leaves out of its map: the half-spaces of section planes, and
// hidden faces (per face, index - 1; empty: none). Null members: nothing.
struct MapClip {
    const Sections* sections = nullptr;
    const std::vector<uint8_t>* hidden_faces = nullptr;
    // Per face, or null/empty: the face drawn translated (RenderOptions::face_offsets).
    const std::vector<Vec3>* offsets = nullptr;
};

struct MapBands {
    int rows = 0;  // rows per band; 0: kMapBandPixels / width
    // Checked between bands: when it is true, Error(canceled) is thrown.
    const std::atomic<bool>* cancel = nullptr;
};

class MapRenderer {
public:
    MapRenderer();  // creates the OSMesa context, compiles the shaders; throws Error(internal) on failure
    ~MapRenderer();
    MapRenderer(const MapRenderer&) = delete;
    MapRenderer& operator=(const MapRenderer&) = delete;

    // clip: drawn without what it leaves out (MapClip).
    PreliminaryMap render(const PreparedScene& scene, const Camera& camera, MapPrecision precision,
                          const MapBands& bands = {}, const MapClip& clip = {});

    // Triangles drawn by the last render (for statistics).
    size_t last_triangles() const { return last_triangles_; }

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
    size_t last_triangles_ = 0;
};

// Renders with a MapRenderer borrowed from the process-wide pool (see above).
PreliminaryMap render_preliminary_map(const PreparedScene& scene, const Camera& camera,
                                      MapPrecision precision = MapPrecision::float32, const MapBands& bands = {},
                                      const MapClip& clip = {});
// Convenience for one map of a Scene: prepares it first.
PreliminaryMap render_preliminary_map(const Scene& scene, const Camera& camera,
                                      MapPrecision precision = MapPrecision::float32);

// warm_up_preliminary_maps, idle_map_renderers: declared in render.h (the public API).

// eq. (4): u0 = (u_max - u_min) g / 255 + u_min with g = round(255 (u - u_min) / (u_max - u_min)).
float quantize_rgb8(float u, double lo, double hi);

}  // namespace nurbsrt
