// RenderStats of a frame from its buffers (DESIGN.md "Statistics and timing"):
// primary solves and their outcome, iterations, rescue by kind, hits and holes.
#include <algorithm>

#include "renderer/passes.h"

namespace nurbsrt {

void frame_statistics(const FrameContext& c, const FrameBuffers& b, const RenderImage& img, int max_iterations,
                      RenderStats& st) {
    st.iteration_limit = max_iterations;
    st.iteration_histogram.assign(static_cast<size_t>(max_iterations) + 1, 0);
    uint64_t solves = 0, its = 0;
    for (size_t k = 0; k < c.pixels(); ++k) {
        if (b.hits[k].face) ++st.pixels_hit;
        switch (b.rescued[k]) {
            case kRescueNeighbour: ++st.rescue_neighbour; break;
            case kRescueSilhouette: ++st.rescue_silhouette; break;
            case kRescueGeneral: ++st.rescue_general; break;
            case kRescueTrimTol: ++st.rescue_trim_tolerance; break;
            default: break;
        }
        if (b.outcome[k] == kNone) continue;
        ++solves;
        its += b.iterations[k];
        const size_t bin = std::min<size_t>(b.iterations[k], st.iteration_histogram.size() - 1);
        ++st.iteration_histogram[bin];
        switch (b.outcome[k]) {
            case kConverged: ++st.converged; break;
            case kDiverged: ++st.diverged; break;
            case kSingular: ++st.singular; break;
            case kMaxIter: ++st.max_iterations; break;
            case kLeftDomain: ++st.left_domain; break;
            case kBehind: ++st.behind_eye; break;
            case kTrimmed: ++st.trimmed; break;
            default: break;
        }
    }
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
