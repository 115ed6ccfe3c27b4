// The passes of a frame, in the order render() runs them (render.cpp):
//   primary_pass       Newton per map pixel from the map's start, trim test
//                      (Sisojevs & Glazs 2010, section 2; the solves the paper's statistics describe)
//   rescue_pass        pixels without a primary hit, from their neighbours' faces
//                      and starts; then silhouette growth (pass_rescue.cpp)
//   nearer_sheet_pass  depth spikes, steps and silhouette pixels a sheet behind
//                      re-solved from their neighbours (pass_nearer.cpp, nearer_sheet.h)
//   shade_pass         shading from the exact normal (lighting.h), exact shadows
//                      of the key light (shadow_rays.h), AOVs
//   antialias_pass     extra exact sub-pixel rays on edge pixels (pass_antialias.cpp)
//   edges_pass         feature lines over the shading (pass_edges.cpp)
//   frame_statistics   RenderStats from the buffers
// Each reads only what earlier passes wrote, so a frame's output is independent of
// the thread count.
#pragma once

#include <cstdint>
#include <cstring>

#include "renderer/frame/frame.h"
#include "renderer/passes/lighting.h"
#include "renderer/frame/pixel_solver.h"
#include "renderer/render.h"
#include "renderer/passes/section_caps.h"
#include "renderer/passes/shadow_rays.h"

namespace nurbsrt {

// Fills b.hits, b.outcome and b.iterations.
void primary_pass(const FrameContext& c, const Solver& solver, FrameBuffers& b);

class MeshScreenPoints;

// Fills b.hits and b.rescued where the primary solve found no hit. screen_points:
// the frame's projected map meshes (mesh_screen_points.h), shared with the
// nearer-sheet pass, which asks for many of the same faces.
void rescue_pass(const FrameContext& c, const Solver& solver, const MeshScreenPoints& screen_points, FrameBuffers& b);

// Replaces hits on a farther sheet by nearer ones in b.hits; returns how many.
uint64_t nearer_sheet_pass(const FrameContext& c, const Solver& solver, const MeshScreenPoints& screen_points,
                           FrameBuffers& b);

// The lights of a frame (lighting.h) and the colour of one hit under them (pass_shade.cpp).
class Shader {
public:
    // shadows: the key light's shadow rays, or null for no shadows.
    explicit Shader(const FrameContext& c, const KeyLightShadows* shadows = nullptr);
    // Linear RGB of hit h on `ray`; n receives the shading normal (facing the
    // viewer), *shadowed (when given) whether the key light is blocked there.
    // Where h is the inside of a closed body cut by a section plane, the colour
    // is the cap's (section_caps.h), and *cap (when given) receives it; else
    // cap->plane is -1. `pixel`: the map index of the pixel the ray passes
    // through (the map's inside layer there, section_caps.h).
    Vec3 colour(const PixelHit& h, const Ray& ray, Vec3& n, bool* shadowed = nullptr, CapHit* cap = nullptr,
                size_t pixel = 0) const;
    const KeyLightShadows* shadows() const { return shadows_; }
    const SectionCaps& caps() const { return caps_; }
    // The RGBA of a ray that meets no face: the ground where it meets it
    // (RenderOptions::ground), else the background. Returns whether it is on
    // the ground; *shadowed (when given): whether the key light is blocked there.
    bool background(const Ray& ray, float rgba[4], bool* shadowed = nullptr) const;

private:
    // The lights' share at point p with shading normal n, times colour col.
    Vec3 lit(Color col, Vec3 p, Vec3 n, const Ray& ray, uint32_t face, double u, double v, bool* shadowed) const;
    const Scene& scene_;
    const RenderOptions& options_;
    double ground_z_;                                       // the ground's height, when options_.ground
    const std::vector<std::optional<Color>>& face_colors_;  // RenderOptions::face_colors
    SectionCaps caps_;
    LightRig rig_;
    const KeyLightShadows* shadows_;
};

// The image and AOVs from b.hits.
void shade_pass(const FrameContext& c, const Shader& shader, const FrameBuffers& b, RenderImage& img);

// A depth step on one face (a fold occluding itself, or one sheet of a closed
// face behind another): adjacent hits farther apart in depth than this many
// pixel footprints, times the sheet's slope where it is steeper than 1 (seen
// more than 45 degrees from face-on, pass_edges.cpp). On one sheet,
// neighbouring depths differ by about one footprint times the slope.
inline constexpr double kDepthStepFootprints = 3.0;

// Whether adjacent pixels show different things: background and a face, two
// faces, a step in depth, or normals at a crease angle (pass_edges.cpp). The
// edge pixels of anti-aliasing and the feature lines. Of each pixel and its four
// forward neighbours, once per frame
// for both the anti-aliasing and the feature lines (it is symmetric, so the
// other four directions are the neighbours' bits): per pixel, the bits below;
// the diagonal ones only when anti-aliasing is on (the feature lines use the
// right and lower neighbours).
enum NeighbourDiff : uint8_t { kDiffRight = 1, kDiffDown = 2, kDiffDownRight = 4, kDiffDownLeft = 8 };
std::vector<uint8_t> neighbour_differences(const FrameContext& c, const FrameBuffers& b, const RenderImage& img);

// The first index from i on (at most n) whose byte is not zero: the scans of a
// row's difference bits and edge flags, most of which are zero, eight bytes at
// a time.
inline int next_set(const uint8_t* bytes, int i, int n) {
    for (uint64_t word; i + 8 <= n && (std::memcpy(&word, bytes + i, 8), word == 0);) i += 8;
    while (i < n && !bytes[i]) ++i;
    return i;
}

// Anti-aliasing: pixels on silhouettes, face borders, depth steps and creases get
// c.options.antialias extra sub-pixel samples (exact rays where an edge can cross
// them, the interpolated centre colours elsewhere), and their colour comes from
// their samples: each side's mean weighted by its coverage where the samples show
// two things either side of a straight edge (edge_coverage.h), the mean of all of
// them elsewhere; img's AOVs stay the pixel-centre sample. Adds the pixels and
// traced rays to st.
// diff: neighbour_differences of the frame.
void antialias_pass(const FrameContext& c, const Solver& solver, const Shader& shader, const FrameBuffers& b,
                    const std::vector<uint8_t>& diff, RenderImage& img, RenderStats& st);

// Feature lines (c.options.edges): silhouettes, face borders and creases drawn
// over img's colour, c.options.edge_width pixels wide, anti-aliased.
void edges_pass(const FrameContext& c, const std::vector<uint8_t>& diff, RenderImage& img);

// Hits, primary outcomes, iterations, rescue kinds and holes into st.
void frame_statistics(const FrameContext& c, const FrameBuffers& b, const RenderImage& img, int max_iterations,
                      RenderStats& st);

}  // namespace nurbsrt
