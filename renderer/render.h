// The frame: preliminary map -> per-pixel Newton from the map's (face, u, v) ->
// trim test -> rescue from neighbouring pixels -> shading from the exact normal,
// with the AOVs and statistics of DESIGN.md. Parallel over image rows with
// oneTBB; every pixel's result depends only on the map and the first pass, so
// the output is identical for any number of threads.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "renderer/camera.h"
#include "renderer/newton.h"
#include "renderer/preliminary_map.h"
#include "renderer/scene.h"

namespace nurbsrt {

struct RenderOptions {
    NewtonMethod method = NewtonMethod::proposed;
    MapPrecision map_precision = MapPrecision::float32;
    int threads = 0;           // 0: all hardware threads
    NewtonParams newton;       // newton.eps <= 0: default_newton_eps(scene.bbox)
    bool rescue = true;        // retry failed pixels with their neighbours' faces
    Color background{0, 0, 0}; // with alpha 0
};

// Per-pixel buffers, row-major, row 0 = top (contract row j = 0).
struct RenderImage {
    int width = 0, height = 0;
    std::vector<float> rgba;        // 4 per pixel, linear
    std::vector<float> z;           // hit distance t, +inf for background
    std::vector<uint32_t> face;     // face index, 0 background
    std::vector<float> u, v;        // parameters of the hit
    std::vector<uint8_t> iterations;// Newton iterations of the pixel's final solve
};

struct RenderStats {
    std::string method;
    int width = 0, height = 0, threads = 0;
    size_t faces = 0, patches = 0, map_triangles = 0;
    size_t pixels_hit = 0;
    double mean_iterations = 0;                 // over every primary (map-started) solve
    std::vector<uint64_t> iteration_histogram;  // [k] = primary solves that took k iterations
    // Outcome of each pixel's primary solve (a map pixel): converged (hit inside
    // the trim), trimmed (converged outside the trim), or the failing criterion.
    uint64_t converged = 0, diverged = 0, singular = 0, max_iterations = 0, left_domain = 0, behind_eye = 0,
             trimmed = 0;
    uint64_t fallback = 0;        // pixels whose hit came from the neighbour rescue
    double preliminary_map_ms = 0, newton_ms = 0, shade_ms = 0, total_ms = 0;
};

struct RenderResult {
    RenderImage image;
    RenderStats stats;
};

RenderResult render(const Scene& scene, const Camera& camera, const RenderOptions& options);

// Writes by extension: .exr -> channels R, G, B, A, Z (float) and face (uint32);
// .png/.jpg/.tif -> 8-bit RGBA (RGB for jpg) with sRGB-like gamma 1/2.2.
// Throws Error(io) or Error(unsupported_format).
void write_image(const RenderImage& image, const std::string& path);

}  // namespace nurbsrt
