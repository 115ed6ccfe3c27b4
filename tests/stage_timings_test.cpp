// The timings of a render or conversion answer (server/render/stage_timings.h): the
// JSON object and the Server-Timing header carry the same stages, every listed
// stage present, and a total that their sum matches.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include <map>
#include <sstream>

#include "server/render/stage_timings.h"

namespace {

using nurbsrt::StageClock;
using namespace std::chrono_literals;

std::map<std::string, double> parse_server_timing(const std::string& header) {
    std::map<std::string, double> out;
    std::istringstream in(header);
    std::string item;
    while (std::getline(in, item, ',')) {
        const size_t b = item.find_first_not_of(' '), semi = item.find(";dur=");
        if (semi == std::string::npos) continue;
        out[item.substr(b, semi - b)] = std::stod(item.substr(semi + 5));
    }
    return out;
}

StageClock sample_clock() {
    const auto t0 = StageClock::Clock::now();
    StageClock c(t0);
    c.mark("upload", t0 + 1ms);
    c.add("read", 2.5);
    c.mark("isolation", t0 + 5ms);
    c.mark("encode", t0 + 7ms);
    c.mark("unlisted", t0 + 8ms);
    return c;
}

TEST(StageTimings, JsonHasEveryListedStageAndSumsToTotal) {
    const StageClock c = sample_clock();
    const nlohmann::json t = nurbsrt::server::stage_timings_json(c, nurbsrt::server::kRenderStages);
    double sum = 0;
    for (const char* stage : nurbsrt::server::kRenderStages) {
        ASSERT_TRUE(t.contains(stage)) << stage;
        EXPECT_GE(t[stage].get<double>(), 0.0) << stage;
    }
    for (const auto& [name, ms] : t.items())
        if (name != "total") sum += ms.get<double>();
    EXPECT_DOUBLE_EQ(t["total"].get<double>(), 8.0);
    EXPECT_DOUBLE_EQ(t["unlisted"].get<double>(), 1.0);  // not lost for want of a listing
    EXPECT_DOUBLE_EQ(t["isolation"].get<double>(), 1.5);
    EXPECT_NEAR(sum, t["total"].get<double>(), 1e-9);
}

TEST(StageTimings, ServerTimingCarriesTheSameStagesInOrder) {
    const StageClock c = sample_clock();
    const std::string h = nurbsrt::server::server_timing(c, nurbsrt::server::kConversionStages);
    EXPECT_EQ(h.rfind("upload;dur=1.000, queue;dur=0.000", 0), 0u) << h;
    EXPECT_NE(h.find("total;dur=8.000"), std::string::npos) << h;
    const std::map<std::string, double> m = parse_server_timing(h);
    double sum = 0;
    for (const auto& [name, ms] : m)
        if (name != "total") sum += ms;
    // The listed stages, then the clock's others ("encode", "unlisted"), then total.
    EXPECT_EQ(m.size(), std::size(nurbsrt::server::kConversionStages) + 3);
    EXPECT_NE(h.find("response;dur=0.000, encode;dur=2.000, unlisted;dur=1.000, total"), std::string::npos) << h;
    EXPECT_NEAR(sum, m.at("total"), 0.01);
}

}  // namespace
