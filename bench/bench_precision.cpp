// Map precision: the float (u, v) of our preliminary map against the paper's
// 8-bit quantized starts (eq. 4), for both Newton methods: iterations, failures
// and Newton time (medians over interleaved runs, as in Table 1).
#include <algorithm>

#include "bench/bench_context.h"

namespace nurbsrt::bench {

void run_precision(BenchContext& ctx) {
    nlohmann::json rows = nlohmann::json::array();
    const MapPrecision precs[2] = {MapPrecision::float32, MapPrecision::rgb8};
    for (BenchScene& sc : ctx.scenes) {
        const Camera cam(ctx.camera(sc, ctx.size));
        for (NewtonMethod method : {NewtonMethod::proposed, NewtonMethod::martin}) {
            std::vector<RenderStats> runs[2];
            for (MapPrecision p : precs) render(sc.prepared(), cam, ctx.render_options(method, p));  // warm-up
            double spent[2] = {0, 0};
            constexpr int kMaxRuns = 100;
            for (int r = 0; r < kMaxRuns && (r < ctx.runs || std::min(spent[0], spent[1]) < ctx.min_ms); ++r)
                for (int k = 0; k < 2; ++k) {
                    const int m = (r % 2 == 0) ? k : 1 - k;
                    ctx.say("precision %s %s: run %d (min %d) %s", sc.key.c_str(), newton_method_name(method), r + 1,
                            ctx.runs, map_precision_name(precs[m]));
                    runs[m].push_back(render(sc.prepared(), cam, ctx.render_options(method, precs[m])).stats);
                    spent[m] += runs[m].back().total_ms;
                }
            nlohmann::json row;
            row["scene"] = sc.key;
            row["method"] = newton_method_name(method);
            row["runs"] = runs[0].size();
            for (int m = 0; m < 2; ++m) {
                std::vector<double> newton, primary, frame;
                for (const RenderStats& s : runs[m]) {
                    newton.push_back(s.newton_ms);
                    primary.push_back(s.newton_primary_ms);
                    frame.push_back(s.total_ms);
                }
                const RenderStats& s = runs[m].back();
                row[map_precision_name(precs[m])] = {
                    {"mean_iterations", s.mean_iterations}, {"failures", newton_failures(s)},
                    {"primary_solves", primary_solves(s)},  {"rescued", s.fallback},
                    {"pixels_hit", s.pixels_hit},           {"newton_ms", median(newton)},
                    {"newton_primary_ms", median(primary)}, {"frame_ms", median(frame)}};
            }
            row["newton_time_ratio_rgb8_over_float"] =
                row["float32"]["newton_ms"].get<double>() > 0
                    ? row["rgb8"]["newton_ms"].get<double>() / row["float32"]["newton_ms"].get<double>()
                    : 0.0;
            rows.push_back(row);
        }
    }
    ctx.doc["precision"] = {{"width", ctx.size},    {"height", ctx.size},         {"min_runs", ctx.runs},
                            {"min_ms", ctx.min_ms}, {"threads", ctx.opt.threads}, {"rows", rows}};
}

}  // namespace nurbsrt::bench
