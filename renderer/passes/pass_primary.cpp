// The primary pass: one Newton solve per map pixel from the map's (u, v), with
// the trim test (Sisojevs & Glazs 2010, section 2; their Table 1 times this).
#include "renderer/passes/passes.h"

namespace nurbsrt {

void primary_pass(const FrameContext& c, const Solver& solver, FrameBuffers& b) {
    const PreliminaryMap& map = c.map;
    parallel_rows(c, true, [&](int j) {
        for (int i = 0; i < c.width; ++i) {
            const size_t k = map.index(i, j);
            const uint32_t id = map.face[k];
            // The first write of the frame's hits and depths (FrameBuffers).
            PixelHit& h = b.hits[k];
            h = PixelHit{};
            if (id != 0 && id <= c.nfaces) {
                b.outcome[k] = solver.solve(id, i, j, map.u[k], map.v[k], h);
                b.iterations[k] = h.iterations;
            }
            b.update_depth(k);
        }
    });
    throw_if_canceled(c.options);
}

}  // namespace nurbsrt
