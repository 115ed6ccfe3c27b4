// RenderStats of a frame from its buffers (the counters render.h documents):
// primary solves and their outcome, iterations, rescue by kind, hits and holes.
#include <algorithm>

#include "renderer/passes/passes.h"

namespace nurbsrt {

void frame_statistics(const FrameContext& c, const FrameBuffers& b, const RenderImage& img, int max_iterations,
                      RenderStats& st) {
    st.iteration_limit = max_iterations;
    st.iteration_histogram.assign(static_cast<size_t>(max_iterations) + 1, 0);
    // One pass over the per-pixel bytes, the outcomes and rescue kinds counted
    // by value (an array indexed by the byte, no switch); the hits read from
    // the image's face AOV (4 bytes a pixel, equal to the hits' faces) rather
    // than the 40-byte hits themselves.
    uint64_t by_rescue[256] = {}, by_outcome[256] = {};
    uint64_t its = 0;
    const size_t last_bin = st.iteration_histogram.size() - 1;
    for (size_t k = 0; k < c.pixels(); ++k) {
        st.pixels_hit += img.face[k] != 0;
        st.cap_pixels += img.face[k] >= kCapFace;
        ++by_rescue[b.rescued[k]];
        ++by_outcome[b.outcome[k]];
        if (b.outcome[k] == kNone) continue;
        its += b.iterations[k];
        ++st.iteration_histogram[std::min<size_t>(b.iterations[k], last_bin)];
    }
    st.rescue_neighbour = by_rescue[kRescueNeighbour];
    st.rescue_silhouette = by_rescue[kRescueSilhouette];
    st.rescue_general = by_rescue[kRescueGeneral];
    st.rescue_trim_tolerance = by_rescue[kRescueTrimTol];
    st.converged = by_outcome[kConverged];
    st.diverged = by_outcome[kDiverged];
    st.singular = by_outcome[kSingular];
    st.max_iterations = by_outcome[kMaxIter];
    st.left_domain = by_outcome[kLeftDomain];
    st.behind_eye = by_outcome[kBehind];
    st.trimmed = by_outcome[kTrimmed];
    const uint64_t solves = c.pixels() - by_outcome[kNone];
    st.fallback = st.rescue_neighbour + st.rescue_silhouette + st.rescue_general + st.rescue_trim_tolerance;
    st.solves = solves;
    st.mean_iterations = solves ? double(its) / solves : 0.0;
    // Holes: background pixels whose 4 neighbours are all hit.
    auto hit = [&](int i, int j) { return c.in_frame(i, j) && img.face[c.map.index(i, j)]; };
    for (int j = 0; j < c.height; ++j)
        for (int i = 0; i < c.width; ++i)
            if (!img.face[c.map.index(i, j)] && hit(i - 1, j) && hit(i + 1, j) && hit(i, j - 1) && hit(i, j + 1))
                ++st.holes;
}

}  // namespace nurbsrt
