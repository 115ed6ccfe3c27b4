// The stage timings of a render or a conversion answer, from the StageClock
// (core/stage_clock.h) that ran from the start of the request: the
// timings_ms object of the JSON answers and the Server-Timing header, with the
// same stages and the same total, so that both sum to it.
#pragma once

#include <nlohmann/json_fwd.hpp>

#include <map>
#include <span>
#include <string>

#include "core/stage_clock.h"

namespace nurbsrt {
struct ConvertReport;
struct IsolationTimings;
}  // namespace nurbsrt

namespace nurbsrt::server {

// A render's stages in the order they run (a cached scene skips prescan
// through prepare; frame stages that are off take 0).
inline constexpr const char* kRenderStages[] = {
    "upload", "cache",     "queue",   "prescan",     "isolation",       "read",    "nurbs_convert",
    "mesh",   "transfer",  "prepare", "frame_setup", "preliminary_map", "newton",  "shadow_map",
    "shade",  "antialias", "edges",   "statistics",  "encode",          "response"};

// A conversion's stages in the order they run (mesh: STL, glb and NURBS JSON;
// verify: STEP and IGES).
inline constexpr const char* kConversionStages[] = {"upload", "queue", "prescan", "isolation", "read",
                                                    "mesh",   "write", "verify",  "transfer",  "response"};

// The stages of an isolated conversion (convert_isolated): the child's own
// (read, mesh, write, verify) and this process's share (prescan, isolation,
// transfer of the report), recorded in `stages` as nested in its running
// stage, the call; marking "isolation" after them completes the call.
void add_conversion_stages(const ConvertReport& report, const IsolationTimings& isolated, StageClock& stages);

// {stage: ms} for every stage of `stages` and of `clock`, and total.
nlohmann::json stage_timings_json(const StageClock& clock, std::span<const char* const> stages);

// The Server-Timing header value: "upload;dur=0.120, ..., total;dur=12.345";
// a stage named in `descriptions` carries its desc too ("cache;dur=0.8;desc=hit":
// one metric, not two of the same name).
std::string server_timing(const StageClock& clock, std::span<const char* const> stages,
                          const std::map<std::string, std::string>& descriptions = {});

}  // namespace nurbsrt::server
