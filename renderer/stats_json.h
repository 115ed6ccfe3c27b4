// The statistics and timing object of a render (DESIGN.md, "Statistics and
// timing"): the renderer's counters plus the import stages and the encode time.
#pragma once

#include <nlohmann/json_fwd.hpp>

#include "renderer/camera.h"
#include "renderer/render.h"
#include "renderer/scene.h"

namespace nurbsrt {

// `import` holds the read / nurbs_convert / mesh stage times (zero when the
// scene came from a cache); `encode_ms` the image writing; `total_ms` the
// wall-clock time of the whole request as the caller measured it.
nlohmann::json render_stats_json(const RenderStats& stats, const ImportTimings& import, double encode_ms,
                                 double total_ms);

// The camera a frame was rendered with: eye, target, up, projection, and the
// one size that applies to it (fov_deg for perspective, ortho_height for orthographic).
nlohmann::json camera_json(const Camera& camera);

}  // namespace nurbsrt
