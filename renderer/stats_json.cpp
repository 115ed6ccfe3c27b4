#include "renderer/stats_json.h"

#include <nlohmann/json.hpp>

namespace nurbsrt {

void add_frame_stages(const RenderStats& s, StageClock& clock) {
    clock.add("prepare", s.prepare_ms);
    clock.add("frame_setup", s.setup_ms);
    clock.add("preliminary_map", s.preliminary_map_ms);
    clock.add("newton", s.newton_ms);
    clock.add("shadow_map", s.shadow_map_ms);
    clock.add("shade", s.shade_ms);
    clock.add("antialias", s.antialias_ms);
    clock.add("edges", s.edges_ms);
    clock.add("statistics", s.statistics_ms);
}

void add_import_stages(const ImportTimings& import, StageClock& clock) {
    clock.add("read", import.read_ms);
    clock.add("nurbs_convert", import.nurbs_convert_ms);
    clock.add("mesh", import.mesh_ms);
}

nlohmann::json render_stats_json(const RenderStats& s, const nlohmann::json& timings) {
    using nlohmann::json;
    json histogram = json::object();
    for (size_t k = 0; k < s.iteration_histogram.size(); ++k)
        if (s.iteration_histogram[k]) histogram[std::to_string(k)] = s.iteration_histogram[k];
    return {
        {"method", s.method},
        {"width", s.width},
        {"height", s.height},
        {"threads", s.threads},
        {"faces", s.faces},
        {"patches", s.patches},
        {"map_triangles", s.map_triangles},
        {"pixels_hit", s.pixels_hit},
        {"newton",
         {{"tolerance", s.tolerance},
          {"solves", s.solves},
          {"mean_iterations", s.mean_iterations},
          {"iteration_histogram", histogram},
          {"converged", s.converged},
          {"diverged", s.diverged},
          {"singular", s.singular},
          {"max_iterations", s.max_iterations},
          {"iteration_limit", s.iteration_limit},
          {"left_domain", s.left_domain},
          {"behind_eye", s.behind_eye},
          {"trimmed", s.trimmed},
          {"fallback", s.fallback},
          {"primary_pass_ms", s.newton_primary_ms}}},
        {"rescue",
         {{"neighbour", s.rescue_neighbour},
          {"silhouette", s.rescue_silhouette},
          {"general", s.rescue_general},
          {"trim_tolerance", s.rescue_trim_tolerance},
          {"nearer_sheet", s.rescue_nearer},
          {"holes", s.holes}}},
        {"antialias", {{"rays_per_edge_pixel", s.antialias}, {"pixels", s.antialias_pixels}, {"rays", s.antialias_rays}}},
        {"shadows",
         {{"enabled", s.shadows},
          {"map_size", s.shadow_map_size},
          {"rays", s.shadow_rays},
          {"shadowed_pixels", s.shadowed_pixels}}},
        {"timings_ms", timings},
    };
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
