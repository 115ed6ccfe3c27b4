// The tessellating peer: the same model meshed with BRepMesh (importer/
// tessellate.h) at linear deflections of 1e-2, 1e-3, 1e-4 of the bounding-box
// diagonal, rasterized from the same camera (bench/mesh_raster.h, OSMesa
// depth) and optionally ray cast with Embree (bench/embree_peer.h). Time = mesh +
// extract + render; accuracy = per-pixel |t_mesh - t_exact| / diagonal where
// both hit our exact frame, and the pixels where only one of the two hits.
#include <cmath>

#include "bench/bench_context.h"
#include "bench/embree_peer.h"
#include "importer/faces/tessellate.h"
#include "bench/mesh_raster.h"

namespace nurbsrt::bench {
namespace {

// Depth error of a mesh image against the exact frame.
nlohmann::json compare(const std::vector<float>& t_mesh, const RenderImage& exact, const std::vector<uint8_t>& inner,
                       double diag) {
    std::vector<double> err, err_inner;
    long mesh_only = 0, exact_only = 0, either = 0;
    for (size_t p = 0; p < t_mesh.size(); ++p) {
        const bool a = std::isfinite(t_mesh[p]), b = exact.face[p] != 0;
        if (a || b) ++either;
        if (a && b) {
            err.push_back(std::fabs(static_cast<double>(t_mesh[p]) - exact.z[p]) / diag);
            if (inner[p]) err_inner.push_back(err.back());
        } else if (a)
            ++mesh_only;
        else if (b)
            ++exact_only;
    }
    return {{"both_hit", err.size()},
            {"dz_rel_median", median(err)},
            {"dz_rel_p99", percentile(err, 0.99)},
            {"dz_rel_max", max_of(err)},
            {"interior_dz_rel_median", median(err_inner)},
            {"interior_dz_rel_p99", percentile(err_inner, 0.99)},
            {"interior_dz_rel_max", max_of(err_inner)},
            {"mesh_only_hits", mesh_only},
            {"exact_only_hits", exact_only},
            {"hit_disagreement_pct", either ? 100.0 * (mesh_only + exact_only) / either : 0.0}};
}

}  // namespace

void run_tessellation(BenchContext& ctx) {
    const std::vector<double> deflections =
        ctx.opt.quick ? std::vector<double>{1e-2, 1e-3} : std::vector<double>{1e-2, 1e-3, 1e-4};
    const double angle = 0.5;  // rad, BRepMesh's usual angular deflection; the linear one is the knob
    // Stop refining a scene once meshing alone takes longer than this, or the mesh
    // gets too large for memory on a small machine.
    const double mesh_budget_ms = ctx.opt.quick ? 3000 : 30000;
    const size_t max_triangles = 20'000'000;
    MeshRasterizer raster;
    // llvmpipe compiles its shader variants on the first draw: one untimed triangle.
    {
        TriangleMesh tri;
        tri.xyz = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
        tri.triangles = {0, 1, 2};
        CameraSpec spec;
        spec.width = spec.height = ctx.size;
        spec.eye = {0.2, 0.2, 3};
        spec.target = {0.2, 0.2, 0};
        raster.render(tri, Camera(spec));
    }
    nlohmann::json rows = nlohmann::json::array();
    for (BenchScene& sc : ctx.scenes) {
        const RenderResult& exact = exact_render(ctx, sc);
        const Camera cam(ctx.camera(sc, ctx.size));
        const double diag = sc.scene.bbox.diagonal();
        const std::vector<uint8_t> inner = interior_mask(exact.image);
        ctx.say("tessellation %s: reading", sc.key.c_str());
        Tessellator tess(sc.file, sc.placements);
        nlohmann::json levels = nlohmann::json::array();
        for (double rel : deflections) {
            ctx.say("tessellation %s: BRepMesh deflection %g x diagonal", sc.key.c_str(), rel);
            const Tessellation t = tess.mesh(rel * diag, angle, false);
            nlohmann::json lv{{"relative_deflection", rel},    {"triangles", t.mesh.triangle_count()},
                              {"vertices", t.mesh.xyz.size()}, {"mesh_ms", t.mesh_ms},
                              {"extract_ms", t.extract_ms},    {"faces_without_triangles", t.faces_without_triangles}};
            std::vector<double> raster_ms;
            DepthImage img;
            for (int r = 0; r < std::max(1, ctx.runs / 2); ++r) {
                const auto t0 = Clock::now();
                img = raster.render(t.mesh, cam);
                raster_ms.push_back(ms_since(t0));
            }
            lv["raster"] = compare(img.t, exact.image, inner, diag);
            lv["raster"]["render_ms"] = median(raster_ms);
            lv["raster"]["total_ms"] = t.mesh_ms + t.extract_ms + median(raster_ms);
            if (embree_available()) {
                const EmbreeFrame e = embree_render(t.mesh, cam, ctx.opt.threads);
                lv["embree"] = compare(e.t, exact.image, inner, diag);
                lv["embree"]["build_ms"] = e.build_ms;
                lv["embree"]["render_ms"] = e.render_ms;
                lv["embree"]["total_ms"] = t.mesh_ms + t.extract_ms + e.build_ms + e.render_ms;
            }
            levels.push_back(lv);
            if (t.mesh_ms > mesh_budget_ms || t.mesh.triangle_count() > max_triangles) {
                ctx.say("tessellation %s: stopping refinement (mesh %.0f ms, %zu triangles)", sc.key.c_str(), t.mesh_ms,
                        t.mesh.triangle_count());
                break;
            }
        }
        const RenderStats& st = exact.stats;
        rows.push_back({{"scene", sc.key},
                        {"diagonal", diag},
                        {"read_ms", tess.read_ms()},
                        {"ours",
                         {{"frame_ms", median(sc.exact_frame_ms)},
                          {"newton_ms", st.newton_ms},
                          {"convert_and_map_mesh_ms", sc.convert_and_map_mesh_ms},
                          {"pixels_hit", st.pixels_hit},
                          {"tolerance_rel", st.tolerance / diag}}},
                        {"levels", levels}});
    }
    ctx.doc["tessellation"] = {{"width", ctx.size},
                               {"height", ctx.size},
                               {"angular_deflection_rad", angle},
                               {"embree", embree_available()},
                               {"embree_threads", ctx.opt.threads},
                               {"rows", rows}};
}

}  // namespace nurbsrt::bench
