// Renderer benchmarks (Google Benchmark): the Newton stage of `proposed`
// (Sisojevs & Glazs 2010, eq. 9-11) against `martin` (Martin et al. 2000) on the same
// preliminary map, the paper's Table 1 scenes at 512x512, one ray per pixel.
//
// The preliminary map is deterministic (same scene, camera and precision give
// the same map), so each benchmark renders the frame and reports the Newton
// stage's wall time through manual timing; the map, shading and import are not
// in the measured time. Counters per run:
//   iters/hit     mean Newton iterations of the primary (map-started) solves
//   rescue_share  share of hit pixels whose hit came from a neighbour rescue
//   failed_share  share of map pixels whose primary solve failed (any criterion)
//   frame_ms      the whole frame (map + Newton + shade)
// Run with interleaved repetitions so machine drift hits both methods alike:
//   build/nurbsrt_bench --benchmark_repetitions=5 --benchmark_enable_random_interleaving=true
// Models come from ../shared/models (NURBSRT_MODELS overrides); scenes whose
// files are missing are skipped with a message.
// `nurbsrt bench` (bench/bench_*.cpp) is the full report with peers and scaling;
// this binary is for profiling the Newton stage in isolation.
#include <benchmark/benchmark.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <memory>
#include <string>

#include "bench/bench_context.h"
#include "core/process/heap_tuning.h"
#include "renderer/render.h"

namespace {

using namespace nurbsrt;
namespace fs = std::filesystem;

std::string models_dir() {
    if (const char* env = std::getenv("NURBSRT_MODELS")) return env;
    return std::string(NURBSRT_SOURCE_DIR) + "/../shared/models";
}

// The paper's three scenes (mapped onto ../shared/models).
struct BenchScene {
    const char* name;
    const char* file;     // relative to models_dir()
    int copies_per_axis;  // 3 for "27 Ducks"
};
const BenchScene kScenes[] = {
    {"mobile_phone", "step/bug27693_cornetta-step.stp", 1},
    {"machine_component", "step/trj8_b1-ec-214.stp", 1},
    {"27_ducks", "duck/duck_from_glscene.igs", 3},
};

// Imported once per process and reused by every benchmark of that scene, built
// as `nurbsrt bench` builds it (bench_common.cpp: the 27 ducks' grid and its map mesh).
const Scene* load(const BenchScene& s) {
    static std::map<std::string, std::unique_ptr<Scene>> cache;
    auto it = cache.find(s.name);
    if (it != cache.end()) return it->second.get();
    const std::string path = models_dir() + "/" + s.file;
    std::unique_ptr<Scene> scene;
    if (fs::exists(path))
        scene = std::make_unique<Scene>(bench::load_bench_scene(s.name, s.name, path, s.copies_per_axis).scene);
    return cache.emplace(s.name, std::move(scene)).first->second.get();
}

void BM_NewtonStage(benchmark::State& state, BenchScene s, NewtonMethod method, MapPrecision precision) {
    const Scene* scene = load(s);
    if (!scene) {
        state.SkipWithError((std::string(s.file) + " not found under " + models_dir()).c_str());
        return;
    }
    CameraSpec base;
    base.width = base.height = 512;
    const Camera camera(fit_view("iso", *scene, base));
    RenderOptions options;
    options.method = method;
    options.map_precision = precision;
    options.threads = static_cast<int>(state.range(0));
    RenderStats last;
    double frame_ms = 0;
    for (auto _ : state) {
        const RenderResult r = render(*scene, camera, options);
        state.SetIterationTime(r.stats.newton_ms / 1e3);
        frame_ms += r.stats.total_ms;
        last = r.stats;
    }
    const double solves = static_cast<double>(last.converged + last.trimmed + last.diverged + last.singular +
                                              last.max_iterations + last.left_domain + last.behind_eye);
    state.counters["iters/hit"] = last.mean_iterations;
    state.counters["rescue_share"] = last.pixels_hit ? double(last.fallback) / last.pixels_hit : 0.0;
    state.counters["failed_share"] = solves > 0 ? (solves - last.converged - last.trimmed) / solves : 0.0;
    state.counters["pixels_hit"] = static_cast<double>(last.pixels_hit);
    state.counters["frame_ms"] = frame_ms / static_cast<double>(state.iterations());
}

const int kRegistered = [] {
    for (const BenchScene& s : kScenes) {
        for (NewtonMethod m : {NewtonMethod::proposed, NewtonMethod::martin}) {
            for (MapPrecision p : {MapPrecision::float32, MapPrecision::rgb8}) {
                const std::string name =
                    std::string("Newton/") + s.name + "/" + newton_method_name(m) + "/" + map_precision_name(p);
                benchmark::RegisterBenchmark(name.c_str(), BM_NewtonStage, s, m, p)
                    ->Arg(1)
                    ->ArgName("threads")
                    ->UseManualTime()
                    ->Unit(benchmark::kMillisecond)
                    ->MinTime(0.5);
            }
        }
    }
    return 0;
}();

}  // namespace

// BENCHMARK_MAIN with the heap settings of the nurbsrt binary, so both measure
// frames alike.
int main(int argc, char** argv) {
    nurbsrt::tune_heap_for_frames();
    benchmark::Initialize(&argc, argv);
    if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
    benchmark::RunSpecifiedBenchmarks();
    benchmark::Shutdown();
    return 0;
}
