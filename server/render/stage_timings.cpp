#include "server/render/stage_timings.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cstdio>
#include <utility>

#include "importer/importer.h"
#include "importer/isolated.h"

namespace nurbsrt::server {
namespace {

bool listed(std::span<const char* const> stages, const std::string& name) {
    return std::any_of(stages.begin(), stages.end(), [&](const char* s) { return name == s; });
}

}  // namespace

void add_conversion_stages(const ConvertReport& report, const IsolationTimings& isolated, StageClock& stages) {
    // In the order they run: the worker's prescan, then its conversion, then the
    // hand-over and the isolation around it.
    stages.add("prescan", isolated.prescan_ms);
    for (const auto& [name, ms] : {std::pair{"read", report.read_ms},
                                   {"mesh", report.mesh_ms},
                                   {"write", report.write_ms},
                                   {"verify", report.verify_ms}})
        stages.add(name, ms);
    stages.add("transfer", isolated.transfer_ms);
    stages.add("isolation", isolated.isolation_ms);
}

nlohmann::json stage_timings_json(const StageClock& clock, std::span<const char* const> stages) {
    nlohmann::json t = nlohmann::json::object();
    // Every listed stage, 0 where it did not run: the same keys on every answer.
    for (const char* stage : stages) t[stage] = clock.ms(stage);
    for (const StageClock::Stage& s : clock.stages()) t[s.name] = s.ms;
    t["total"] = clock.total_ms();
    return t;
}

std::string server_timing(const StageClock& clock, std::span<const char* const> stages,
                          const std::map<std::string, std::string>& descriptions) {
    std::string out;
    auto add = [&](const std::string& name, double ms) {
        char buf[96];
        std::snprintf(buf, sizeof buf, "%s%s;dur=%.3f", out.empty() ? "" : ", ", name.c_str(), ms);
        out += buf;
        if (const auto d = descriptions.find(name); d != descriptions.end()) out += ";desc=" + d->second;
    };
    for (const char* stage : stages) add(stage, clock.ms(stage));
    for (const StageClock::Stage& s : clock.stages())
        if (!listed(stages, s.name)) add(s.name, s.ms);
    add("total", clock.total_ms());
    return out;
}

}  // namespace nurbsrt::server
