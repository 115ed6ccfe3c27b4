// The primary pass: one Newton solve per map pixel from the map's (u, v), with
// the trim test (Sisojevs & Glazs 2010, section 2; their Table 1 times this).
#include "renderer/passes.h"

namespace nurbsrt {

void primary_pass(const FrameContext& c, const Solver& solver, FrameBuffers& b) {
    const PreliminaryMap& map = c.map;
    parallel_rows(c, true, [&](int j) {
        for (int i = 0; i < c.width; ++i) {
            const size_t k = map.index(i, j);
            const uint32_t id = map.face[k];
            b.hits[k] = PixelHit{};  // the first write of the frame's hits (FrameBuffers)
            if (id == 0 || id > c.nfaces) continue;
            b.outcome[k] = solver.solve(id, i, j, map.u[k], map.v[k], b.hits[k]);
            b.iterations[k] = b.hits[k].iterations;
        }
    });
    throw_if_canceled(c.options);
}

}  // namespace nurbsrt
