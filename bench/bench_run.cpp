// run_bench(): finds the models, imports the scenes, runs the selected sections
// and assembles the JSON document (machine, settings, scenes, sections).
#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <set>

#include "bench/bench_context.h"
#include "core/error.h"

#ifndef NURBSRT_SOURCE_DIR
#define NURBSRT_SOURCE_DIR "."
#endif

namespace nurbsrt::bench {
namespace {

namespace fs = std::filesystem;

struct SceneDef {
    const char* key;
    const char* title;  // the paper's scene it stands for, or a description
    const char* file;   // relative to the models directory
    int grid_n;         // n x n x n copies (1: the file as it is)
};

// The paper's three scenes, mapped onto ../shared/models.
const SceneDef kPaperScenes[] = {
    {"mobile_phone", "Mobile phone", "step/bug27693_cornetta-step.stp", 1},
    {"machine_component", "Machine component", "step/trj8_b1-ec-214.stp", 1},
    {"27_ducks", "27 Ducks", "duck/duck_from_glscene.igs", 3},
};
// --quick without ../shared/models: OCCT's own sample files (package occt-misc).
const char* kOcctSamples = "/usr/share/opencascade/data";
const SceneDef kSampleScenes[] = {
    {"screw", "screw.step (OCCT sample)", "step/screw.step", 1},
    {"bearing", "bearing.iges (OCCT sample)", "iges/bearing.iges", 1},
    {"8_screws", "8 screws (OCCT sample, 2x2x2)", "step/screw.step", 2},
};

bool has_all(const fs::path& dir, const SceneDef* defs, size_t n) {
    for (size_t k = 0; k < n; ++k)
        if (!fs::is_regular_file(dir / defs[k].file)) return false;
    return true;
}

}  // namespace

nlohmann::json run_bench(const BenchOptions& options) {
    BenchContext ctx;
    ctx.opt = options;
    ctx.runs = options.runs > 0 ? options.runs : options.quick ? 2 : 9;
    // Small frames are noisy on a shared machine: Table 1 and the precision figures
    // run on past ctx.runs until each variant has accumulated this much frame time.
    ctx.min_ms = options.quick ? 0 : 4000;
    ctx.size = options.size > 0 ? options.size : options.quick ? 128 : 512;
    if (ctx.opt.threads < 1) throw Error(ErrorCode::invalid_argument, "--threads must be at least 1");
    std::vector<std::string> sections = options.only.empty() ? kSections : options.only;
    for (const std::string& s : sections)
        if (std::find(kSections.begin(), kSections.end(), s) == kSections.end())
            throw Error(ErrorCode::invalid_argument,
                        "unknown section '" + s +
                            "' (table1, precision, occt, tessellation, meshtracer, scaling, look, batch)");

    // Models: --models, else $NURBSRT_MODELS, else ../shared/models from the working
    // directory, else beside the source tree; --quick falls back to OCCT's samples.
    const SceneDef* defs = kPaperScenes;
    const size_t ndefs = std::size(kPaperScenes);
    fs::path dir;
    std::vector<std::string> looked;
    if (!options.models_dir.empty()) {
        dir = options.models_dir;
        if (!fs::is_directory(dir)) throw Error(ErrorCode::io, "--models: no directory " + dir.string());
        if (!has_all(dir, defs, ndefs))
            throw Error(ErrorCode::io, "--models " + dir.string() + " lacks one of " + kPaperScenes[0].file + ", " +
                                           kPaperScenes[1].file + ", " + kPaperScenes[2].file);
    } else {
        // NURBSRT_MODELS (as for build/nurbsrt_bench) replaces the default search.
        std::vector<fs::path> candidates{fs::path("../shared/models"),
                                         fs::path(NURBSRT_SOURCE_DIR) / "../shared/models"};
        if (const char* env = std::getenv("NURBSRT_MODELS")) candidates = {fs::path(env)};
        for (const fs::path& c : candidates) {
            looked.push_back(fs::absolute(c).lexically_normal().string());
            if (has_all(c, defs, ndefs)) {
                dir = c;
                break;
            }
        }
    }
    const SceneDef* use = defs;
    size_t nuse = ndefs;
    if (dir.empty()) {
        std::string where;
        for (const std::string& l : looked) where += (where.empty() ? "" : ", ") + l;
        if (!options.quick || !has_all(kOcctSamples, kSampleScenes, std::size(kSampleScenes)))
            throw Error(ErrorCode::io, "the benchmark models (../shared/models) were not found (looked in " + where +
                                           "); pass --models DIR" +
                                           (options.quick ? "" : ", or run --quick on OCCT's sample files"));
        dir = kOcctSamples;
        use = kSampleScenes;
        nuse = std::size(kSampleScenes);
        ctx.fallback_models = true;
    }
    ctx.models_dir = fs::absolute(dir).lexically_normal().string();

    ctx.doc["tool"] = "nurbsrt bench";
    ctx.doc["mode"] = options.quick ? "quick" : "full";
    ctx.doc["machine"] = machine_json();
    ctx.doc["settings"] = {{"width", ctx.size},
                           {"height", ctx.size},
                           {"runs", ctx.runs},
                           {"min_frame_time_ms_per_variant", ctx.min_ms},
                           {"threads", ctx.opt.threads},
                           {"sections", sections},
                           {"models_dir", ctx.models_dir},
                           {"fallback_models", ctx.fallback_models},
                           {"view", "iso"},
                           {"projection", "perspective"},
                           {"rays_per_pixel", 1}};

    nlohmann::json scenes = nlohmann::json::array();
    for (size_t k = 0; k < nuse; ++k) {
        const SceneDef& d = use[k];
        ctx.say("importing %s (%s%s)", d.key, d.file, d.grid_n > 1 ? ", placed in a grid" : "");
        ctx.scenes.push_back(load_bench_scene(d.key, d.title, (dir / d.file).string(), d.grid_n));
        const BenchScene& s = ctx.scenes.back();
        scenes.push_back({{"key", s.key},
                          {"title", s.title},
                          {"file", d.file},
                          {"copies", std::max<size_t>(1, s.placements.size())},
                          {"faces", s.scene.faces.size()},
                          {"bbox_diagonal", s.scene.bbox.diagonal()},
                          {"import_ms", s.import_ms}});
    }
    ctx.doc["scenes"] = scenes;

    const std::set<std::string> want(sections.begin(), sections.end());
    if (want.count("table1")) run_table1(ctx);
    if (want.count("precision")) run_precision(ctx);
    if (want.count("occt")) run_occt(ctx);
    if (want.count("tessellation")) run_tessellation(ctx);
    if (want.count("meshtracer")) run_mesh_tracer(ctx);
    if (want.count("scaling")) run_scaling(ctx);
    if (want.count("look")) run_look(ctx);
    if (want.count("batch")) run_batch(ctx);
    double load[3] = {0, 0, 0};
    if (getloadavg(load, 3) == 3) ctx.doc["machine"]["load_average_end"] = {load[0], load[1], load[2]};
    ctx.doc["elapsed_s"] = ms_since(ctx.t0) / 1e3;
    ctx.say("done in %.1f s", ms_since(ctx.t0) / 1e3);
    return ctx.doc;
}

}  // namespace nurbsrt::bench
