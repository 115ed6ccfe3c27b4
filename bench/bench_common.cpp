// Scenes, camera, options and statistics shared by the bench sections (see
// bench_context.h).
#include <time.h>

#include <algorithm>
#include <cmath>
#include <filesystem>

#include "bench/bench_context.h"
#include "importer/importer.h"

namespace nurbsrt::bench {

double process_cpu_ms() {
    timespec ts{};
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
    return 1e3 * static_cast<double>(ts.tv_sec) + 1e-6 * static_cast<double>(ts.tv_nsec);
}

std::vector<Affine> grid_placements(const BBox& one, int n) {
    const Vec3 size = one.hi - one.lo;
    const double step = 1.25 * std::max({size.x, size.y, size.z});
    std::vector<Affine> out;
    for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j)
            for (int k = 0; k < n; ++k) out.push_back(Affine::translation({i * step, j * step, k * step}));
    return out;
}

namespace {

Scene grid_of(const Scene& one, const std::vector<Affine>& placements) {
    Scene grid;
    for (const Affine& a : placements) {
        Scene copy = one;
        transform_scene(copy, a);
        append_scene(grid, copy);
    }
    grid.source_name = one.source_name;
    return grid;
}

}  // namespace

BenchScene load_bench_scene(const std::string& key, const std::string& title, const std::string& file, int grid_n) {
    BenchScene s;
    s.key = key;
    s.title = title;
    s.file = file;
    const auto t0 = Clock::now();
    Scene one = import_file(file);
    s.import_ms = ms_since(t0);
    s.convert_and_map_mesh_ms = one.timings.nurbs_convert_ms + one.timings.mesh_ms;
    if (grid_n <= 1) {
        s.scene = std::move(one);
        return s;
    }
    s.placements = grid_placements(one.bbox, grid_n);
    s.scene = grid_of(one, s.placements);
    // The map mesh's deflection is relative to the imported model's diagonal
    // (ImportOptions::mesh_relative_deflection); a file holding the whole grid
    // would be meshed relative to the grid's, as the mesh tracer's BRepMesh is
    // (bench_mesh_tracer.cpp). So the model is imported again with the deflection
    // scaled to the grid: otherwise each copy carries the single model's mesh (27
    // ducks: 239k triangles drawn per frame instead of 101k, 47 ms of map instead
    // of 25, for no more pixels hit: 97,554 against 97,624 of 262,144).
    const double ratio = s.scene.bbox.diagonal() / one.bbox.diagonal();
    ImportOptions options;
    if (ratio > 1 && options.mesh_relative_deflection * ratio < 1) {
        options.mesh_relative_deflection *= ratio;
        const auto t1 = Clock::now();
        one = import_file(file, options);
        s.import_options = options;
        s.import_ms = ms_since(t1);
        s.convert_and_map_mesh_ms = one.timings.nurbs_convert_ms + one.timings.mesh_ms;
        s.scene = grid_of(one, s.placements);
    }
    return s;
}

CameraSpec BenchContext::camera(const BenchScene& s, int sz) const {
    CameraSpec base;
    base.width = base.height = sz;
    base.projection = Projection::perspective;
    return fit_view("iso", s.scene, base);
}

RenderOptions BenchContext::render_options(NewtonMethod method, MapPrecision precision, int threads) const {
    RenderOptions o;
    o.method = method;
    o.map_precision = precision;
    o.threads = threads > 0 ? threads : opt.threads;
    return o;  // newton.eps 0: the default relative tolerance, identical for both methods
}

namespace {

struct ExtraScene {
    const char* key;
    const char* title;
    const char* file;  // relative to the models directory
};
const ExtraScene kExtraScenes[] = {
    {"space_ship", "Free-form (Alias, 94 rational B-spline faces)", "step/trj3_s1-al-214.stp"},
    {"cylinder_block", "Mechanical part (cylinder block)", "step/cylinder_block.stp"},
    {"as1_assembly", "Assembly (CAx-IF AS1, 18 parts)", "step/as1-oc-214.stp"},
    {"bearing_iges", "IGES (bearing)", "iges/bearing.iges"},
};

}  // namespace

std::vector<BenchScene>& extra_scenes(BenchContext& ctx) {
    if (ctx.extras_loaded || ctx.opt.quick || ctx.fallback_models) return ctx.extras;
    ctx.extras_loaded = true;
    for (const ExtraScene& e : kExtraScenes) {
        const std::filesystem::path file = std::filesystem::path(ctx.models_dir) / e.file;
        if (!std::filesystem::is_regular_file(file)) {
            ctx.missing_extras.push_back(e.file);
            continue;
        }
        ctx.say("importing %s (%s)", e.key, e.file);
        ctx.extras.push_back(load_bench_scene(e.key, e.title, file.string(), 1));
    }
    return ctx.extras;
}

const RenderResult& exact_render(BenchContext& ctx, BenchScene& s) {
    if (!s.exact) {
        const Camera cam(ctx.camera(s, ctx.size));
        const RenderOptions o = ctx.render_options(NewtonMethod::proposed);
        std::shared_ptr<RenderResult> r;
        for (int k = 0; k < ctx.runs; ++k) {
            r = std::make_shared<RenderResult>(render(s.prepared(), cam, o));
            s.exact_frame_ms.push_back(r->stats.total_ms);
        }
        s.exact = r;
    }
    return *s.exact;
}

std::vector<uint8_t> interior_mask(const RenderImage& im) {
    const int W = im.width, H = im.height;
    std::vector<uint8_t> m(static_cast<size_t>(W) * H, 0);
    for (int j = 1; j + 1 < H; ++j)
        for (int i = 1; i + 1 < W; ++i) {
            const uint32_t f = im.face[static_cast<size_t>(j) * W + i];
            bool same = f != 0;
            for (int dj = -1; dj <= 1 && same; ++dj)
                for (int di = -1; di <= 1 && same; ++di) same = im.face[static_cast<size_t>(j + dj) * W + i + di] == f;
            m[static_cast<size_t>(j) * W + i] = same;
        }
    return m;
}

double median(std::vector<double> xs) { return percentile(std::move(xs), 0.5); }

double percentile(std::vector<double> xs, double p) {
    if (xs.empty()) return 0;
    std::sort(xs.begin(), xs.end());
    if (p == 0.5 && xs.size() % 2 == 0) return 0.5 * (xs[xs.size() / 2 - 1] + xs[xs.size() / 2]);
    const size_t k = static_cast<size_t>(std::ceil(p * static_cast<double>(xs.size())));
    return xs[std::min(xs.size() - 1, k == 0 ? 0 : k - 1)];
}

double max_of(const std::vector<double>& xs) { return xs.empty() ? 0 : *std::max_element(xs.begin(), xs.end()); }

uint64_t newton_failures(const RenderStats& s) {
    return s.diverged + s.singular + s.max_iterations + s.left_domain + s.behind_eye;
}
uint64_t primary_solves(const RenderStats& s) { return s.converged + s.trimmed + newton_failures(s); }

double speedup_pct(double proposed, double martin) { return martin > 0 ? 100.0 * (martin - proposed) / martin : 0; }

}  // namespace nurbsrt::bench
