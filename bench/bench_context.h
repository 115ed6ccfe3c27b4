// What the sections of `nurbsrt bench` share: the benchmark scenes (imported
// once), the options, progress output and small statistics helpers. Internal
// to bench/*.cpp.
#pragma once

#include <nlohmann/json.hpp>

#include <chrono>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "bench/bench.h"
#include "importer/importer.h"
#include "renderer/camera.h"
#include "renderer/render.h"
#include "core/scene/scene.h"
#include "core/scene/scene_ops.h"

namespace nurbsrt::bench {

using Clock = std::chrono::steady_clock;
inline double ms_since(Clock::time_point t0) {
    return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}
// CPU time of the whole process (all threads), ms: CPU over wall time of a frame
// shows how many cores it really got on a shared machine.
double process_cpu_ms();

// A scene of the benchmark: one CAD file, placed once or several times.
struct BenchScene {
    std::string key;                     // JSON key: mobile_phone, machine_component, 27_ducks, ...
    std::string title;                   // the paper's name ("Mobile phone") or the file's
    std::string file;                    // absolute path of the CAD file
    std::vector<Affine> placements;      // empty: the file as it is
    Scene scene;                         // imported, copies placed
    double import_ms = 0;                // import_file (read + convert + map mesh) of the one file
    double convert_and_map_mesh_ms = 0;  // the part of the import a renderer of a loaded model needs
    ImportOptions import_options;        // those the scene was imported with (a grid: scaled deflection)
    // The exact frame the peers are compared with: `proposed`, float map, ctx.size,
    // ctx.opt.threads threads; and its whole-frame times (Table 1's runs, or its own).
    std::shared_ptr<const RenderResult> exact;
    std::vector<double> exact_frame_ms;

    // prepare(scene), made on first use, so that the timed frames pay only the
    // frame (as the service's cached renders do). Made again if this BenchScene
    // was moved since (the PreparedScene refers to `scene` by address).
    const PreparedScene& prepared() const {
        if (!prepared_ || &prepared_->scene() != &scene)
            prepared_ = std::make_shared<const PreparedScene>(prepare(scene));
        return *prepared_;
    }

private:
    mutable std::shared_ptr<const PreparedScene> prepared_;
};

// A grid of n x n x n copies spaced 1.25 x the model's largest extent (the
// paper's "27 Ducks" is n = 3).
std::vector<Affine> grid_placements(const BBox& one, int n);
// Imports `file` and places its copies. Throws nurbsrt::Error.
BenchScene load_bench_scene(const std::string& key, const std::string& title, const std::string& file, int grid_n);

struct BenchContext {
    BenchOptions opt;
    int runs = 9;       // minimum timed runs per figure
    double min_ms = 0;  // Table 1 / precision: run on until each variant has this much frame time
    int size = 512;
    std::string models_dir;        // where the scenes came from
    bool fallback_models = false;  // OCCT's sample files instead of ../shared/models
    std::vector<BenchScene> scenes;
    // The models beside the paper's scenes (extra_scenes()), imported on first use.
    std::vector<BenchScene> extras;
    std::vector<std::string> missing_extras;  // their files not found
    bool extras_loaded = false;
    Clock::time_point t0 = Clock::now();
    nlohmann::json doc;  // sections write their results here

    // The scenes' camera: the iso view fitted to the scene, perspective, size x size.
    CameraSpec camera(const BenchScene& s, int size) const;
    RenderOptions render_options(NewtonMethod method, MapPrecision precision = MapPrecision::float32,
                                 int threads = 0) const;
    template <class... A>
    void say(const char* fmt, A... xs) const {
        if (!opt.progress) return;
        std::fprintf(stderr, "bench: [%7.1f s] ", ms_since(t0) / 1e3);
        if constexpr (sizeof...(A) == 0)
            std::fputs(fmt, stderr);
        else
            std::fprintf(stderr, fmt, xs...);
        std::fputc('\n', stderr);
    }
};

// Four models beside the paper's scenes, each standing for a kind of file users
// send (free-form, mechanical, an assembly, IGES), from the models directory:
// imported on first use, once for every section; none in a --quick run or on
// the fallback models. Files that are missing are listed in ctx.missing_extras.
std::vector<BenchScene>& extra_scenes(BenchContext& ctx);

// The scene's exact frame (rendered on first use, timed over ctx.runs runs when
// Table 1 did not already time it).
const RenderResult& exact_render(BenchContext& ctx, BenchScene& s);

// Pixels of an exact frame away from every edge: hit, and all 8 neighbours hit the
// same face. At a silhouette or a face border the pixel centre may legitimately
// land on either side within the trim and intersection tolerances, so errors
// there measure edge placement, not surface accuracy; reported separately.
std::vector<uint8_t> interior_mask(const RenderImage& im);

// Statistics over a sample (copies; empty input gives 0).
double median(std::vector<double> xs);
double percentile(std::vector<double> xs, double p);  // p in [0, 1], nearest rank
double max_of(const std::vector<double>& xs);

// Newton failures of a frame: map pixels whose primary solve ended on a failure
// criterion (13), (14), the iteration cap, leaving the domain or behind the eye.
uint64_t newton_failures(const RenderStats& s);
// Map pixels with a primary solve (converged, trimmed or failed).
uint64_t primary_solves(const RenderStats& s);
// The paper's speed-up (Table 1): the time saved as a percentage of the baseline,
// 100 (t_martin - t_proposed) / t_martin.
double speedup_pct(double proposed, double martin);

// Sections: each adds its object to ctx.doc[name].
void run_table1(BenchContext& ctx);
void run_precision(BenchContext& ctx);
void run_occt(BenchContext& ctx);
void run_tessellation(BenchContext& ctx);
void run_scaling(BenchContext& ctx);
void run_mesh_tracer(BenchContext& ctx);
void run_look(BenchContext& ctx);
// A batch job through the service against one CLI process per output (bench_batch.cpp).
void run_batch(BenchContext& ctx);

// The machine and build the figures come from.
nlohmann::json machine_json();

}  // namespace nurbsrt::bench
