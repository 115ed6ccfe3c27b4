// The statistics and timing object of a render (RenderStats and the
// stage timings): the renderer's counters plus the stage timings of whoever ran the
// frame (import, encoding, a service's request handling).
#pragma once

#include <nlohmann/json_fwd.hpp>

#include "renderer/camera.h"
#include "renderer/render.h"
#include "core/scene/scene.h"
#include "core/stage_clock.h"

namespace nurbsrt {

// The frame's stages as render() measured them (RenderStats), recorded in
// `clock` as nested inside its running stage (the call of render()), under
// their timings_ms names: prepare (when render() prepared the scene),
// frame_setup, preliminary_map, newton, shadow_map, shade, antialias, edges,
// statistics.
void add_frame_stages(const RenderStats& stats, StageClock& clock);

// The import's stages (read, nurbs_convert, mesh) measured where it ran,
// recorded the same way.
void add_import_stages(const ImportTimings& import, StageClock& clock);

// The statistics of a frame with `timings` as timings_ms.
nlohmann::json render_stats_json(const RenderStats& stats, const nlohmann::json& timings);

// The camera a frame was rendered with: eye, target, up, projection, and the
// one size that applies to it (fov_deg for perspective, ortho_height for orthographic).
nlohmann::json camera_json(const Camera& camera);
// One view of a contact sheet: its name, camera and frame statistics (their
// own stage times as timings_ms: the frame's stages).
nlohmann::json view_stats_json(const std::string& view, const Camera& camera, const RenderStats& stats);

}  // namespace nurbsrt
