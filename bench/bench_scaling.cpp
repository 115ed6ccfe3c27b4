// Scaling of the `proposed` frame: with resolution (256^2 .. 2048^2), with the
// number of patches (1, 8 and 27 ducks, then the larger models) and with threads
// (1 and 2, interleaved runs). Medians over runs; big frames get fewer runs.
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <thread>

#include "bench/bench_context.h"

namespace nurbsrt::bench {
namespace {

struct Timed {
    std::vector<double> frame, newton, primary, map, cpu;
    RenderStats last;
    void add(const RenderStats& s) {
        frame.push_back(s.total_ms);
        newton.push_back(s.newton_ms);
        primary.push_back(s.newton_primary_ms);
        map.push_back(s.preliminary_map_ms);
        last = s;
    }
    // Times one frame, with the process CPU time it used.
    void run(const BenchScene& sc, const Camera& cam, const RenderOptions& o) {
        const double c0 = process_cpu_ms();
        const RenderStats s = render(sc.prepared(), cam, o).stats;
        cpu.push_back(process_cpu_ms() - c0);
        add(s);
    }
    nlohmann::json json() const {
        const double solves = static_cast<double>(primary_solves(last));
        return {{"frame_ms", median(frame)},
                {"newton_ms", median(newton)},
                {"preliminary_map_ms", median(map)},
                {"runs", frame.size()},
                {"pixels_hit", last.pixels_hit},
                {"map_triangles", last.map_triangles},
                {"mean_iterations", last.mean_iterations},
                {"newton_primary_ms", median(primary)},
                {"rescue_ms", median(newton) - median(primary)},
                {"newton_ns_per_primary_solve", solves > 0 ? 1e6 * median(newton) / solves : 0.0},
                {"primary_ns_per_solve", solves > 0 ? 1e6 * median(primary) / solves : 0.0},
                {"cpu_over_wall", median(frame) > 0 && !cpu.empty() ? median(cpu) / median(frame) : 0.0}};
    }
};

Timed time_frames(const BenchScene& sc, const Camera& cam, const RenderOptions& o, int runs) {
    render(sc.prepared(), cam, o);  // warm-up (map context and FBO of this size)
    Timed t;
    for (int r = 0; r < runs; ++r) t.run(sc, cam, o);
    return t;
}

}  // namespace

void run_scaling(BenchContext& ctx) {
    nlohmann::json out;
    out["threads"] = ctx.opt.threads;
    BenchScene& first = ctx.scenes.front();

    // Resolution: pixels grow 4x per step; the time per pixel shows what is per
    // pixel (Newton, shading) and what is per frame (map set-up, projection).
    const std::vector<int> sizes = ctx.opt.quick ? std::vector<int>{64, 128} : std::vector<int>{256, 512, 1024, 2048};
    nlohmann::json res = nlohmann::json::array();
    for (int sz : sizes) {
        const int runs = ctx.opt.quick ? 1 : sz <= 512 ? ctx.runs : sz <= 1024 ? 2 : 1;
        ctx.say("scaling resolution %s: %dx%d, %d run(s)", first.key.c_str(), sz, sz, runs);
        const Camera cam(ctx.camera(first, sz));
        Timed t = time_frames(first, cam, ctx.render_options(NewtonMethod::proposed), runs);
        nlohmann::json row = t.json();
        row["size"] = sz;
        row["ns_per_pixel"] = 1e6 * median(t.frame) / (static_cast<double>(sz) * sz);
        res.push_back(row);
    }
    out["resolution"] = {{"scene", first.key}, {"rows", res}};

    // Patches: a grid of 1, 8, 27 copies of the grid scene's file (the ducks),
    // then every other scene, at the benchmark's size.
    nlohmann::json pat = nlohmann::json::array();
    auto patch_row = [&](const BenchScene& sc, const std::string& label) {
        ctx.say("scaling patches %s: %zu faces", label.c_str(), sc.scene.faces.size());
        const Camera cam(ctx.camera(sc, ctx.size));
        const int runs = ctx.opt.quick ? 1 : std::max(1, ctx.runs / 2);
        nlohmann::json row = time_frames(sc, cam, ctx.render_options(NewtonMethod::proposed), runs).json();
        row["scene"] = label;
        row["patches"] = sc.scene.faces.size();
        pat.push_back(row);
    };
    const auto grid =
        std::find_if(ctx.scenes.begin(), ctx.scenes.end(), [](const BenchScene& s) { return !s.placements.empty(); });
    const int grid_n = grid == ctx.scenes.end() ? 0 : static_cast<int>(std::cbrt(grid->placements.size()) + 0.5);
    if (grid != ctx.scenes.end())
        for (int n = 1; n < grid_n; ++n)
            patch_row(load_bench_scene(grid->key, grid->title, grid->file, n),
                      std::to_string(n * n * n) + "x " + std::filesystem::path(grid->file).stem().string());
    std::vector<const BenchScene*> by_size;
    for (const BenchScene& s : ctx.scenes) by_size.push_back(&s);
    std::sort(by_size.begin(), by_size.end(),
              [](const BenchScene* a, const BenchScene* b) { return a->scene.faces.size() < b->scene.faces.size(); });
    for (const BenchScene* s : by_size) patch_row(*s, s->key);
    out["patches"] = {{"width", ctx.size}, {"height", ctx.size}, {"rows", pat}};

    // Threads: 1 and 2 interleaved (the renderer's rows run on a TBB arena of that size).
    nlohmann::json thr = nlohmann::json::array();
    const int max_threads = 2;
    for (const BenchScene& sc : ctx.scenes) {
        const Camera cam(ctx.camera(sc, ctx.size));
        Timed t[2];
        for (int k = 0; k < 2; ++k)
            render(sc.prepared(), cam, ctx.render_options(NewtonMethod::proposed, MapPrecision::float32, k + 1));
        for (int r = 0; r < ctx.runs; ++r)
            for (int k = 0; k < 2; ++k) {
                const int m = (r % 2 == 0) ? k : 1 - k;
                ctx.say("scaling threads %s: run %d/%d, %d thread(s)", sc.key.c_str(), r + 1, ctx.runs, m + 1);
                t[m].run(sc, cam, ctx.render_options(NewtonMethod::proposed, MapPrecision::float32, m + 1));
            }
        const double f1 = median(t[0].frame), f2 = median(t[1].frame);
        const double n1 = median(t[0].newton), n2 = median(t[1].newton);
        thr.push_back({{"scene", sc.key},
                       {"threads_1", t[0].json()},
                       {"threads_2", t[1].json()},
                       {"frame_speedup", f2 > 0 ? f1 / f2 : 0.0},
                       {"newton_speedup", n2 > 0 ? n1 / n2 : 0.0}});
    }
    out["threads_scaling"] = {{"width", ctx.size},
                              {"height", ctx.size},
                              {"max_threads", max_threads},
                              {"hardware_threads", std::thread::hardware_concurrency()},
                              {"rows", thr}};
    ctx.doc["scaling"] = out;
}

}  // namespace nurbsrt::bench
