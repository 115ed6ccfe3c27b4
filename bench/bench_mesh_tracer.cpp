// "Frame vs mesh tracer": our exact frame (preliminary map + Newton + shading,
// prepared scene, the bench's thread count) against Embree tracing the same
// camera's pixel rays through a BRepMesh mesh of the model, the way a
// tessellating ray tracer renders it:
//   further frames  ours (the model prepared) vs the Embree trace alone over a
//                   mesh at 1e-4 of the diagonal (the BVH built once, not counted)
//   first frame     ours: NURBS conversion + map meshing at import + prepare +
//                   frame; the tracer's: BRepMesh at 1e-3 + copying the mesh out +
//                   BVH build + trace. Neither counts reading the file.
// On the Table 1 scenes and, in a full run, the four extra models (extra_scenes).
#include "bench/bench_context.h"
#include "bench/embree_peer.h"
#include "importer/tessellate.h"

namespace nurbsrt::bench {
namespace {

// The fine mesh of "further frames" and the coarse one of "first frame", relative
// to the bounding-box diagonal: 1e-4 is about what a 512-pixel view of the whole
// model can show (a pixel is ~2e-3 of the diagonal), 1e-3 what a quick first look uses.
constexpr double kFineDeflection = 1e-4;
constexpr double kCoarseDeflection = 1e-3;
constexpr double kAngularDeflection = 0.5;  // rad, BRepMesh's usual; the linear one is the knob
// Embree's trace repeats (its BVH is rebuilt each time, not timed): the median of 3
// steadies the trace time on a shared machine at little cost.
constexpr int kTraceRuns = 3;

// Median trace time and the last run's frame over `runs` Embree renders of `mesh`.
EmbreeFrame trace(const TriangleMesh& mesh, const Camera& cam, int threads, int runs) {
    EmbreeFrame last;
    std::vector<double> ms;
    for (int r = 0; r < runs; ++r) {
        last = embree_render(mesh, cam, threads);
        ms.push_back(last.render_ms);
    }
    last.render_ms = median(ms);
    return last;
}

nlohmann::json measure(BenchContext& ctx, BenchScene& sc) {
    const Camera cam(ctx.camera(sc, ctx.size));
    const double diag = sc.scene.bbox.diagonal();
    exact_render(ctx, sc);
    // The first frame of a freshly imported model: prepare() and the frame, once.
    const auto t0 = Clock::now();
    const PreparedScene fresh = prepare(sc.scene);
    render(fresh, cam, ctx.render_options(NewtonMethod::proposed));
    const double ours_first = sc.convert_and_map_mesh_ms + ms_since(t0);

    ctx.say("mesh tracer %s: BRepMesh %g and %g x diagonal, Embree", sc.key.c_str(), kCoarseDeflection,
            kFineDeflection);
    Tessellator tess(sc.file, sc.placements);
    const Tessellation coarse = tess.mesh(kCoarseDeflection * diag, kAngularDeflection, false);
    const EmbreeFrame ec = trace(coarse.mesh, cam, ctx.opt.threads, 1);
    const double mesh_first = coarse.mesh_ms + coarse.extract_ms + ec.build_ms + ec.render_ms;
    const Tessellation fine = tess.mesh(kFineDeflection * diag, kAngularDeflection, false);
    const EmbreeFrame ef = trace(fine.mesh, cam, ctx.opt.threads, kTraceRuns);
    const double ours_frame = median(sc.exact_frame_ms);
    // Where our frame goes (the last timed run's stages): what the ratio above is made of.
    const RenderStats& st = sc.exact->stats;
    const nlohmann::json stages = {{"preliminary_map_ms", st.preliminary_map_ms},
                                   {"newton_primary_ms", st.newton_primary_ms},
                                   {"newton_rescue_ms", st.newton_ms - st.newton_primary_ms},
                                   {"shade_ms", st.shade_ms},
                                   {"other_ms", st.setup_ms + st.antialias_ms + st.edges_ms + st.statistics_ms},
                                   {"total_ms", st.total_ms}};
    return {{"scene", sc.key},
            {"title", sc.title},
            {"faces", sc.scene.faces.size()},
            {"ours_frame_ms", ours_frame},
            {"ours_first_frame_ms", ours_first},
            {"fine_triangles", fine.mesh.triangle_count()},
            {"embree_trace_ms", ef.render_ms},
            {"embree_build_ms", ef.build_ms},
            {"ours_frame_stages", stages},
            {"frame_over_trace", ef.render_ms > 0 ? ours_frame / ef.render_ms : 0.0},
            {"coarse_triangles", coarse.mesh.triangle_count()},
            {"mesh_first_frame_ms", mesh_first},
            {"first_over_mesh_first", mesh_first > 0 ? ours_first / mesh_first : 0.0}};
}

}  // namespace

void run_mesh_tracer(BenchContext& ctx) {
    if (!embree_available()) {
        ctx.doc["meshtracer"] = {{"embree", false}, {"rows", nlohmann::json::array()}};
        return;
    }
    nlohmann::json rows = nlohmann::json::array();
    for (BenchScene& sc : ctx.scenes) rows.push_back(measure(ctx, sc));
    for (BenchScene& sc : extra_scenes(ctx)) rows.push_back(measure(ctx, sc));
    ctx.doc["meshtracer"] = {{"embree", true},
                             {"threads", ctx.opt.threads},
                             {"fine_relative_deflection", kFineDeflection},
                             {"coarse_relative_deflection", kCoarseDeflection},
                             {"missing_models", ctx.missing_extras},
                             {"rows", rows}};
}

}  // namespace nurbsrt::bench
