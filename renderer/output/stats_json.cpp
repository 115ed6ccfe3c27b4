#include "renderer/stats_json.h"

#include <nlohmann/json.hpp>

namespace nurbsrt {

namespace {

// The stages of a frame and of an import, in the order they run, named as the
// API's timings_ms and Server-Timing name them.
template <typename Stats>
struct StageField {
    const char* name;
    double Stats::*ms;
};
constexpr StageField<RenderStats> kFrameStages[] = {{"prepare", &RenderStats::prepare_ms},
                                                    {"frame_setup", &RenderStats::setup_ms},
                                                    {"preliminary_map", &RenderStats::preliminary_map_ms},
                                                    {"newton", &RenderStats::newton_ms},
                                                    {"shadow_map", &RenderStats::shadow_map_ms},
                                                    {"shade", &RenderStats::shade_ms},
                                                    {"antialias", &RenderStats::antialias_ms},
                                                    {"edges", &RenderStats::edges_ms},
                                                    {"statistics", &RenderStats::statistics_ms}};
constexpr StageField<ImportTimings> kImportStages[] = {{"read", &ImportTimings::read_ms},
                                                       {"nurbs_convert", &ImportTimings::nurbs_convert_ms},
                                                       {"mesh", &ImportTimings::mesh_ms}};

}  // namespace

void add_frame_stages(const RenderStats& s, StageClock& clock) {
    for (const auto& stage : kFrameStages) clock.add(stage.name, s.*stage.ms);
}

void add_import_stages(const ImportTimings& import, StageClock& clock) {
    for (const auto& stage : kImportStages) clock.add(stage.name, import.*stage.ms);
}

nlohmann::json render_stats_json(const RenderStats& s, const nlohmann::json& timings) {
    using nlohmann::json;
    json histogram = json::object();
    for (size_t k = 0; k < s.iteration_histogram.size(); ++k)
        if (s.iteration_histogram[k]) histogram[std::to_string(k)] = s.iteration_histogram[k];
#define NURBSRT_STAT(member) {#member, s.member}
    // Most keys are the RenderStats members' own names: one macro says so, and
    // a member renamed breaks the build instead of the API's documented key.
    json j = {{"method", newton_method_name(s.method)},
              NURBSRT_STAT(width),
              NURBSRT_STAT(height),
              NURBSRT_STAT(threads),
              NURBSRT_STAT(faces),
              NURBSRT_STAT(patches),
              NURBSRT_STAT(map_triangles),
              NURBSRT_STAT(pixels_hit)};
    j["newton"] = {NURBSRT_STAT(tolerance),       NURBSRT_STAT(solves),
                   NURBSRT_STAT(mean_iterations), {"iteration_histogram", histogram},
                   NURBSRT_STAT(converged),       NURBSRT_STAT(diverged),
                   NURBSRT_STAT(singular),        NURBSRT_STAT(max_iterations),
                   NURBSRT_STAT(iteration_limit), NURBSRT_STAT(left_domain),
                   NURBSRT_STAT(behind_eye),      NURBSRT_STAT(trimmed),
                   NURBSRT_STAT(fallback),        {"primary_pass_ms", s.newton_primary_ms}};
#undef NURBSRT_STAT
    j["rescue"] = {{"neighbour", s.rescue_neighbour}, {"silhouette", s.rescue_silhouette},
                   {"general", s.rescue_general},     {"trim_tolerance", s.rescue_trim_tolerance},
                   {"nearer_sheet", s.rescue_nearer}, {"holes", s.holes}};
    j["antialias"] = {{"rays_per_edge_pixel", s.antialias}, {"pixels", s.antialias_pixels}, {"rays", s.antialias_rays}};
    j["shadows"] = {{"enabled", s.shadows},  {"map_size", s.shadow_map_size},
                    {"rays", s.shadow_rays}, {"shadowed_pixels", s.shadowed_pixels},
                    {"ground", s.ground},    {"ground_shadowed_pixels", s.ground_shadowed_pixels}};
    j["sections"] = {
        {"planes", s.section_planes}, {"cap_pixels", s.cap_pixels}, {"open_bodies_cut", s.open_bodies_cut}};
    j["parts"] = {{"hidden_faces", s.hidden_faces}, {"recoloured_faces", s.recoloured_faces},
                  {"moved_faces", s.moved_faces},   {"ghost_faces", s.ghost_faces},
                  {"ghost_pixels", s.ghost_pixels}, {"ghost_behind_ms", s.ghost_behind_ms}};
    j["timings_ms"] = timings;
    return j;
}

nlohmann::json view_stats_json(const std::string& view, const Camera& camera, const RenderStats& stats) {
    StageClock frame;
    add_frame_stages(stats, frame);
    nlohmann::json timings = nlohmann::json::object();
    for (const StageClock::Stage& s : frame.stages()) timings[s.name] = s.ms;
    return {{"view", view}, {"camera", camera_json(camera)}, {"statistics", render_stats_json(stats, timings)}};
}

nlohmann::json camera_json(const Camera& camera) {
    const CameraSpec& cs = camera.spec();
    nlohmann::json j = {{"eye", {cs.eye.x, cs.eye.y, cs.eye.z}},
                        {"target", {cs.target.x, cs.target.y, cs.target.z}},
                        {"up", {cs.up.x, cs.up.y, cs.up.z}},
                        {"projection", camera.perspective() ? "perspective" : "orthographic"}};
    if (camera.perspective())
        j["fov_deg"] = cs.fov_deg;
    else
        j["ortho_height"] = cs.ortho_height;
    return j;
}

}  // namespace nurbsrt
