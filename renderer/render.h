// The frame: preliminary map -> per-pixel Newton from the map's (face, u, v) ->
// trim test -> rescue from neighbouring pixels -> shading from the exact normal,
// with the AOVs and statistics that RenderImage and RenderStats describe below. Parallel over image rows with
// oneTBB; every pixel's result depends only on the map and the first pass, so
// the output is identical for any number of threads.
#pragma once

#include <array>
#include <atomic>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "core/scene/scene.h"
#include "renderer/camera.h"
#include "renderer/method.h"
#include "renderer/prepared_scene.h"
#include "renderer/section.h"

namespace nurbsrt {

enum class RenderPriority : uint8_t { low, normal, high };

struct RenderOptions {
    NewtonMethod method = NewtonMethod::proposed;
    MapPrecision map_precision = MapPrecision::float32;
    int threads = 0;      // 0: all hardware threads
    NewtonParams newton;  // newton.eps <= 0 (the default): default_newton_eps(scene.bbox)
    bool rescue = true;   // retry failed pixels with their neighbours' faces (pass_rescue.cpp)
    // Share of the cores against other frames rendering at the same time: the
    // frame's work runs in its own oneTBB arena of this priority, and the
    // process's one worker pool serves higher-priority arenas first (a service
    // puts cheap frames ahead of heavy ones).
    RenderPriority priority = RenderPriority::normal;
    // Extra sub-pixel samples per edge pixel (silhouettes, face borders, depth
    // steps, creases), each an exact ray where an edge can cross it and the
    // interpolated centre colours elsewhere (pass_antialias.cpp); 0: one ray per pixel.
    // The AOVs are the pixel-centre sample either way.
    int antialias = 0;
    // Feature lines over the shading (pass_edges.cpp): silhouettes, face borders
    // and creases, edge_width pixels wide (any resolution), anti-aliased.
    bool edges = false;
    Color edge_color{0.02f, 0.02f, 0.02f};
    float edge_width = 1.0f;
    // Exact shadows of the key light (shadow_rays.h): a second preliminary map
    // from the light, and Newton along the light ray of every shaded sample.
    bool shadows = false;
    // Section planes (section.h): the half-spaces they remove are left out of the
    // frame, its map, its shadows; closed bodies show caps where they are cut.
    Sections sections;
    // Per face (index - 1), or empty for none: faces left out of the frame (its
    // map, its solves, its shadows), and colours that replace the file's.
    std::vector<uint8_t> hidden_faces;
    std::vector<std::optional<Color>> face_colors;
    // Per face, or empty: faces drawn see-through. A ray's first ghost surface is
    // blended, with opacity ghost_opacity, over what the ray meets behind it
    // with every ghost face left out: a second frame of the same scene (one
    // ghost layer; ghost surfaces behind the first are not drawn). The AOVs are
    // the first surface's.
    std::vector<uint8_t> ghost_faces;
    float ghost_opacity = 0.25f;
    // Per face, or empty: the face drawn translated by this (an exploded view,
    // explode_offsets in core/scene/explode.h), exactly, without a new prepare().
    std::vector<Vec3> face_offsets;
    // A ground plane under the model (z = ground_height, model units; unset: the
    // scene's lowest point; Z is up as in the named views) that takes the key
    // light's exact shadows (it turns them on). Over an opaque background it is
    // a light grey floor; over a transparent one a shadow catcher: transparent
    // but where shadowed, black with alpha kShadowCatcherAlpha. The AOVs keep
    // it background (face 0).
    bool ground = false;
    std::optional<double> ground_height;
    Color background{0, 0, 0};   // of pixels no face covers
    float background_alpha = 0;  // their alpha: 0 transparent, 1 opaque
    // Called with the fraction done in (0, 1], from the rendering threads (one call
    // at a time, fractions increasing), about every 2% of the frame's rows and once
    // with 1.0 at the end. Must be cheap; has no effect on the output.
    std::function<void(double fraction)> progress;
    // Cooperative cancellation: when set and it becomes true, render() stops at the
    // next block of rows and throws Error(canceled). Shared so that a caller that
    // stops waiting (a timed-out request, a deleted job) can leave it behind safely.
    std::shared_ptr<const std::atomic<bool>> cancel;
};

// Per-pixel buffers, row-major, row 0 = top (contract row j = 0).
struct RenderImage {
    int width = 0, height = 0;
    std::vector<float> rgba;          // 4 per pixel, linear
    std::vector<float> z;             // hit distance t, +inf for background
    std::vector<float> normal;        // 3 per pixel: world-space shading normal (facing the viewer), 0 background
    std::vector<uint32_t> face;       // face index, 0 background; kCapFace + body on a section cap
    std::vector<float> u, v;          // parameters of the hit
    std::vector<uint8_t> iterations;  // Newton iterations of the pixel's final solve
    // 1 where the key light is blocked at the pixel-centre hit (RenderOptions::shadows;
    // empty without shadows). Points facing away from the key light are 0: their
    // darkness is their orientation, not a cast shadow.
    std::vector<uint8_t> shadow;
};

// The face AOV of a section cap (section.h) of body b is kCapFace + b: above any
// face index a scene can hold, one value per body, so a cap is told from faces
// and caps of different bodies from each other.
inline constexpr uint32_t kCapFace = 0x80000000u;

// The ground's floor colour (linear; a light grey that reads as a table top
// under any part colour), and a shadow catcher's alpha where the key light is
// blocked: about the darkening the floor's shadow shows.
inline constexpr Color kGroundColor{0.75f, 0.75f, 0.75f};
inline constexpr float kShadowCatcherAlpha = 0.5f;

struct RenderStats {
    NewtonMethod method = NewtonMethod::proposed;
    int width = 0, height = 0, threads = 0;
    size_t faces = 0, patches = 0, map_triangles = 0;
    size_t pixels_hit = 0;
    double tolerance = 0;  // (12) stop tolerance used, model units
    // Primary (map-started) solves, one per pixel the map covers: the sum of
    // iteration_histogram, and of the outcome counts below.
    uint64_t solves = 0;
    double mean_iterations = 0;                 // over every primary solve
    std::vector<uint64_t> iteration_histogram;  // [k] = primary solves that took k iterations
    int iteration_limit = 0;                    // the primary solves' cap (NewtonParams::max_iterations)
    // Outcome of each pixel's primary solve (a map pixel): converged (hit inside
    // the trim), trimmed (converged outside the trim), or the failing criterion
    // (max_iterations: how many reached iteration_limit unconverged, not the limit).
    uint64_t converged = 0, diverged = 0, singular = 0, max_iterations = 0, left_domain = 0, behind_eye = 0,
             trimmed = 0;
    uint64_t fallback = 0;  // pixels whose hit came from the rescue (any kind below)
    // Rescue, by kind (they sum to `fallback`): a pixel whose map face failed, hit
    // from its 8 neighbours' faces and starts; a map-background pixel next to hits,
    // hit the same way (the exact silhouette is not the mesh's); a pixel hit only
    // by the general fallback (every face of the 5x5 neighbourhood, several starts);
    // a crack pixel between faces filled by a hit just outside a trim loop, within
    // the face's trim tolerance.
    uint64_t rescue_neighbour = 0, rescue_silhouette = 0, rescue_general = 0, rescue_trim_tolerance = 0;
    // Hit pixels whose hit was replaced by a nearer one on the same ray, found from a
    // neighbour's face and (u, v) where the pixel was a depth spike (a surface folded
    // over itself within the map mesh's deflection). Not part of `fallback`.
    uint64_t rescue_nearer = 0;
    uint64_t holes = 0;  // diagnostic: background pixels whose 4 neighbours are all hit
    // Anti-aliasing: extra samples per edge pixel (RenderOptions::antialias), the
    // edge pixels that got them, and the samples traced as exact rays.
    int antialias = 0;
    uint64_t antialias_pixels = 0, antialias_rays = 0;
    // Shadows (RenderOptions::shadows): the light map's size (square), the light
    // rays' Newton solves (pixel centres and anti-aliasing samples), and the hit
    // pixels whose centre the key light does not reach.
    bool shadows = false;
    int shadow_map_size = 0;
    // Sections (RenderOptions::sections): the planes, the pixels showing a cap,
    // and the cut bodies that got no caps because they are open shells (their
    // insides show).
    bool ground = false;
    uint64_t ground_shadowed_pixels = 0;  // background pixels on the ground the key light does not reach
    int section_planes = 0;
    uint64_t cap_pixels = 0, open_bodies_cut = 0;
    // Parts (RenderOptions::hidden_faces, face_colors): faces left out, faces recoloured.
    uint64_t hidden_faces = 0, recoloured_faces = 0;
    // Faces drawn moved (RenderOptions::face_offsets: explode, parts.move).
    uint64_t moved_faces = 0;
    // Ghosts (RenderOptions::ghost_faces): the faces, the pixels whose first
    // surface is one, and the frame behind them (its own total, part of total_ms).
    uint64_t ghost_faces = 0, ghost_pixels = 0;
    double ghost_behind_ms = 0;
    uint64_t shadow_rays = 0, shadowed_pixels = 0;
    // Stage times of the frame, end to end on one clock (each includes the small
    // set-up before its pass), so that with prepare_ms they sum to total_ms.
    double shadow_map_ms = 0;  // drawing the light's preliminary map (the solves are in shade_ms, antialias_ms)
    double preliminary_map_ms = 0, newton_ms = 0, shade_ms = 0, antialias_ms = 0, edges_ms = 0;
    double setup_ms = 0;       // the frame's own set-up: its thread arena, per-pixel buffers
    double statistics_ms = 0;  // counting these statistics over the frame's buffers
    double total_ms = 0;
    // prepare() of the Scene when render() was given one (then included in
    // total_ms); 0 when it was given a PreparedScene.
    double prepare_ms = 0;
    // The part of newton_ms spent in the first pass: per-face set-up and one solve
    // per map pixel from its start, with the trim test (what the paper's Table 1
    // compares); the rest of newton_ms is the rescue of failed pixels.
    double newton_primary_ms = 0;
};

struct RenderResult {
    RenderImage image;
    RenderStats stats;
};

// One frame of a prepared scene (prepared_scene.h): what a caller that renders
// many views of one scene pays per view. Several frames of one PreparedScene may
// run at once, on any threads.
// Readies `count` pooled preliminary-map renderers (map/preliminary_map.h) for frames of about width x height: each
// context is created, its shaders compiled, and a small scene drawn through
// the real pipeline, so that llvmpipe generates its code now rather than in the
// first frame (a few hundred ms a context, most of a small file's first map).
// Called on a thread of its own while a file is read (the CLI) or at start-up
// (the service); the renderers then wait in the pool. Safe from any thread;
// failures are left for the real frame to report.
void warm_up_preliminary_maps(int count, int width, int height);
// MapRenderers idle in the pool now (for tests and statistics).
size_t idle_map_renderers();

RenderResult render(const PreparedScene& scene, const Camera& camera, const RenderOptions& options);
// One frame of a Scene: prepare(scene, options.threads), then the frame above.
// The same images; stats.prepare_ms says what preparing cost.
RenderResult render(const Scene& scene, const Camera& camera, const RenderOptions& options);

// Writes by extension: .exr -> channels R, G, B, A, Z (float), face (uint32),
// N.X, N.Y, N.Z, u, v (float) and iterations (uint32) (the AOVs of RenderImage);
// .png/.jpg/.tif -> 8-bit RGBA (RGB for jpg), colour sRGB-encoded (IEC 61966-2-1), alpha linear.
// Throws Error(io) or Error(unsupported_format); Error(internal) when the
// image writer module (image_module.h) cannot be loaded.
void write_image(const RenderImage& image, const std::string& path);
// The bytes write_image would write to a file of extension `format_name` (png,
// jpg or jpeg, tif or tiff, exr), made in memory. Throws as write_image.
std::string encode_image(const RenderImage& image, const std::string& format_name);

// Draws `text` into image.rgba (top-left corner at pixel (x, y), `size` pixels
// high, opaque `colour`) through the image module. Throws as write_image.
void draw_label(RenderImage& image, int x, int y, int size, const std::string& text, Color colour);

// A contact sheet: the frames (all of one size) tiled row by row, about square
// (ceil(sqrt(n)) columns), every buffer of them (colour and AOVs) in its cell,
// and each cell's label drawn in its top-left corner. The cells left over in
// the last row are the frames' background (options.background), the AOVs'
// background values.
RenderImage compose_sheet(const std::vector<RenderResult>& frames, const std::vector<std::string>& labels,
                          const RenderOptions& options);

}  // namespace nurbsrt
