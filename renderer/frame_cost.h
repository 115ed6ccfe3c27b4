// What a frame will cost before it is rendered: an upper estimate of the memory
// it allocates and of its work, from the image size and the prepared scene
// alone (no pixel is traced). A service admits a render against its budgets
// with this (the process's memory budget, a per-request cap), and schedules
// cheap frames ahead of heavy ones.
//
// Memory: every per-pixel buffer of the frame (the preliminary map and its GL
// framebuffer, the solve buffers, the rescue's worst-case candidate lists, the
// output image with its AOVs, the encoder's 8-bit copy), the per-frame
// projection of the patches (or control points) and the map vertices' clip positions.
// Calibrated against the measured peak RSS of real frames (bench/fairness.sh
// prints estimate / measured); meant to be >= the truth, within ~2x (often 1.5-2.5x: the rescue lists rarely fill).
//
// Work: core-seconds on the reference machine (a 2-core Xeon build host), the
// sum of a per-pixel solve cost that grows with the evaluation cost of the
// faces ((p+1)(q+1) basis products per point, Piegl & Tiller A3.5), weighted by
// each face's share of the map mesh as a proxy for its share of the pixels, and
// a per-triangle cost of the map. Anti-aliasing and shadows scale that work by
// factors measured on real models (frame_cost.cpp) and add their buffers.
#pragma once

#include <cstddef>

namespace nurbsrt {

class PreparedScene;

struct FrameCost {
    size_t memory_bytes = 0;
    double core_seconds = 0;
};

// The passes that change a frame's cost (RenderOptions::antialias, ::shadows).
struct FrameCostOptions {
    int antialias = 0;
    bool shadows = false;
};

FrameCost estimate_frame_cost(const PreparedScene& scene, int width, int height, FrameCostOptions options = {});

}  // namespace nurbsrt
