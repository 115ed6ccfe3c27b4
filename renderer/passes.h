// The passes of a frame, in the order render() runs them (render.cpp):
//   primary_pass       Newton per map pixel from the map's start, trim test
//                      (Sisojevs & Glazs 2010, section 2; the solves the paper's statistics describe)
//   rescue_pass        pixels without a primary hit, from their neighbours' faces
//                      and starts; then silhouette growth (pass_rescue.cpp)
//   nearer_sheet_pass  depth spikes re-solved from their neighbours (pass_nearer.cpp)
//   shade_pass         shading from the exact normal, AOVs
//   frame_statistics   RenderStats from the buffers
// Each reads only what earlier passes wrote, so a frame's output is independent of
// the thread count.
#pragma once

#include <cstdint>

#include "renderer/frame.h"
#include "renderer/pixel_solver.h"
#include "renderer/render.h"

namespace nurbsrt {

// Fills b.first and b.outcome.
void primary_pass(const FrameContext& c, const Solver& solver, FrameBuffers& b);

// Fills b.hits and b.rescued where the primary solve found no hit.
void rescue_pass(const FrameContext& c, const Solver& solver, FrameBuffers& b);

// Replaces hits on a farther sheet by nearer ones in b.hits; returns how many.
uint64_t nearer_sheet_pass(const FrameContext& c, const Solver& solver, FrameBuffers& b);

// The image and AOVs from b.hits.
void shade_pass(const FrameContext& c, const FrameBuffers& b, RenderImage& img);

// Hits, primary outcomes, iterations, rescue kinds and holes into st.
void frame_statistics(const FrameContext& c, const FrameBuffers& b, const RenderImage& img, int max_iterations,
                      RenderStats& st);

}  // namespace nurbsrt
