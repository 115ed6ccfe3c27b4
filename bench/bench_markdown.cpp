// The Markdown report of a `nurbsrt bench` JSON document: every figure comes
// from the document, so the report and the JSON never disagree.
#include <cmath>
#include <cstdio>
#include <string>

#include <nlohmann/json.hpp>

#include "bench/bench.h"

namespace nurbsrt::bench {
namespace {

using nlohmann::json;

std::string num(double x, int prec = 1) {
    char b[64];
    std::snprintf(b, sizeof b, "%.*f", prec, x);
    return b;
}
std::string sci(double x) {
    if (x == 0) return "0";
    char b[64];
    std::snprintf(b, sizeof b, "%.1e", x);
    return b;
}
std::string ms(double x) { return x >= 100 ? num(x, 0) : x >= 10 ? num(x, 1) : num(x, 2); }
double d(const json& j, const char* k) { return j.contains(k) && j[k].is_number() ? j[k].get<double>() : 0.0; }
long long n(const json& j, const char* k) { return j.contains(k) && j[k].is_number() ? j[k].get<long long>() : 0; }
std::string s(const json& j, const char* k) { return j.contains(k) && j[k].is_string() ? j[k].get<std::string>() : ""; }

std::string title_of(const json& doc, const std::string& key) {
    for (const json& sc : doc["scenes"])
        if (s(sc, "key") == key) return s(sc, "title");
    return key;
}

void machine(std::string& o, const json& doc) {
    const json& m = doc["machine"];
    o += "Machine: **" + s(m, "cpu") + "**, " + std::to_string(n(m, "online_cpus")) + " CPUs online, " +
         s(m, "memory_total") + " RAM, " + s(m, "kernel") + "; " + s(m, "compiler") + ", " + s(m, "build_type") +
         " build. Run " + s(m, "date_utc") + " (UTC), " + num(d(doc, "elapsed_s"), 0) + " s.";
    if (m.contains("load_average") && m["load_average"].size() == 3)
        o += " Load average at start " + num(m["load_average"][0].get<double>(), 2);
    if (m.contains("load_average_end") && m["load_average_end"].size() == 3)
        o += ", at end " + num(m["load_average_end"][0].get<double>(), 2);
    o += " (1 min).\n\n";
    const json& st = doc["settings"];
    o += "Settings: " + std::to_string(n(st, "width")) + "x" + std::to_string(n(st, "height")) +
         ", one ray per pixel, iso view (perspective), " + "at least " + std::to_string(n(st, "runs")) +
         " timed runs per figure, " + std::to_string(n(st, "threads")) + " render thread(s); models from `" +
         s(st, "models_dir") + "`" +
         (st.value("fallback_models", false) ? " (OCCT's samples: ../shared/models was not found)" : "") + ".\n\n";
    o += "| scene | stands for | file | copies | faces | import ms |\n|---|---|---|---:|---:|---:|\n";
    for (const json& sc : doc["scenes"])
        o += "| " + s(sc, "key") + " | " + s(sc, "title") + " | `" + s(sc, "file") + "` | " +
             std::to_string(n(sc, "copies")) + " | " + std::to_string(n(sc, "faces")) + " | " + ms(d(sc, "import_ms")) +
             " |\n";
    o += "\n";
}

// A Table 1 row's scene name, marked where it is not one of the paper's scenes.
std::string table1_title(const json& r) { return s(r, "title") + (r.value("extra", false) ? " (extra)" : ""); }

void table1(std::string& o, const json& t) {
    o += "## Table 1: proposed (eq. 9-11) vs Martin et al., same preliminary map\n\n";
    o += "Medians of interleaved runs (at least " + std::to_string(n(t, "min_runs")) +
         (d(t, "min_ms") > 0 ? ", more until each method has " + num(d(t, "min_ms") / 1e3, 0) + " s of frames" : "") +
         "), " + std::to_string(n(t, "width")) + "x" + std::to_string(n(t, "height")) + ", " +
         std::to_string(n(t, "threads")) +
         " thread(s). Speed-up as the paper computes it: 100 (t_Martin - t_proposed) / t_Martin, from the medians; "
         "in brackets the middle half (25th..75th percentile) of the speed-ups of each pair of neighbouring runs. "
         "Interference from other work only adds time, so the speed-up of the fastest runs (minima) and of the "
         "process CPU time per frame are given too. Rows marked (extra) are models beside the paper's scenes "
         "(a full run only): other kinds of files (free-form, mechanical, an assembly, IGES), to see whether the "
         "paper's speed-up (14-24 %) carries over to them.\n\n";
    o += "| scene | runs | proposed Newton ms | Martin Newton ms | speed-up Newton % (pairs p25..p75) | proposed "
         "frame ms | Martin frame ms | speed-up frame % |\n|---|---:|---:|---:|---:|---:|---:|---:|\n";
    for (const json& r : t["rows"]) {
        const json &p = r["proposed"], &m = r["martin"];
        o += "| " + table1_title(r) + " | " + std::to_string(n(r, "runs")) + " | " + ms(d(p, "newton_ms")) + " | " +
             ms(d(m, "newton_ms")) + " | **" + num(d(r, "speedup_newton_pct"), 1) + "** (" +
             num(d(r, "speedup_newton_pct_p25"), 1) + " .. " + num(d(r, "speedup_newton_pct_p75"), 1) + ") | " +
             ms(d(p, "frame_ms")) + " | " + ms(d(m, "frame_ms")) + " | " + num(d(r, "speedup_frame_pct"), 1) + " |\n";
    }
    o += "\nThe Newton stage split into its first pass (per-face set-up and one solve per map pixel with the trim "
         "test: what the paper compares) and the rescue of failed pixels (neighbour, silhouette and general "
         "fallback; not in the paper), with the robust figures and the solver statistics (P = proposed, M = "
         "Martin):\n\n";
    o += "| scene | primary pass ms P / M | speed-up primary % | rescue ms P / M | speed-up of minima % | speed-up "
         "frame CPU % | mean iterations P / M | Newton failures P / M | rescued P / M |\n"
         "|---|---:|---:|---:|---:|---:|---:|---:|---:|\n";
    for (const json& r : t["rows"]) {
        const json &p = r["proposed"], &m = r["martin"];
        o += "| " + table1_title(r) + " | " + ms(d(p, "newton_primary_ms")) + " / " + ms(d(m, "newton_primary_ms")) +
             " | **" + num(d(r, "speedup_primary_pct"), 1) + "** | " + ms(d(p, "rescue_ms")) + " / " +
             ms(d(m, "rescue_ms")) + " | " + num(d(r, "speedup_newton_min_pct"), 1) + " | " +
             num(d(r, "speedup_frame_cpu_pct"), 1) + " | " + num(d(p, "mean_iterations"), 2) + " / " +
             num(d(m, "mean_iterations"), 2) + " | " + std::to_string(n(p, "failures")) + " / " +
             std::to_string(n(m, "failures")) + " | " + std::to_string(n(p, "rescued")) + " / " +
             std::to_string(n(m, "rescued")) + " |\n";
    }
    o += "\nThe paper (Xeon 3.2 GHz, 2010): Mobile phone 4.297 s vs 5.422 s (20.75 %), Machine component 1.890 vs "
         "2.203 s (14.21 %), 27 Ducks 9.0 vs 11.86 s (24.11 %), whole rendering time.\n\n";
}

void precision(std::string& o, const json& t) {
    o += "## Map precision: float (u, v) vs the paper's 8-bit starts (eq. 4)\n\n";
    o += "| scene | method | mean iterations float / rgb8 | Newton failures float / rgb8 | rescued float / rgb8 | "
         "Newton ms float / rgb8 | primary pass ms float / rgb8 | rgb8 / float Newton time |\n"
         "|---|---|---:|---:|---:|---:|---:|---:|\n";
    for (const json& r : t["rows"]) {
        const json &f = r["float32"], &q = r["rgb8"];
        o += "| " + s(r, "scene") + " | " + s(r, "method") + " | " + num(d(f, "mean_iterations"), 2) + " / " +
             num(d(q, "mean_iterations"), 2) + " | " + std::to_string(n(f, "failures")) + " / " +
             std::to_string(n(q, "failures")) + " | " + std::to_string(n(f, "rescued")) + " / " +
             std::to_string(n(q, "rescued")) + " | " + ms(d(f, "newton_ms")) + " / " + ms(d(q, "newton_ms")) + " | " +
             ms(d(f, "newton_primary_ms")) + " / " + ms(d(q, "newton_primary_ms")) + " | " +
             num(d(r, "newton_time_ratio_rgb8_over_float"), 2) + " |\n";
    }
    o += "\n";
}

void occt(std::string& o, const json& t) {
    o += "## Exact peer: OCCT IntCurvesFace_ShapeIntersector on the same pixel rays\n\n";
    o += "A uniform random subset of the frame's pixel rays (interior: those whose 8 neighbours in our frame hit "
         "the same face, i.e. away from silhouettes and face borders); OCCT's time per ray times the pixel count plus "
         "its "
         "set-up (Load) is its frame time. Ours: whole frame (map + Newton + rescue + shading), " +
         std::to_string(n(t, "threads_ours")) +
         " thread(s); OCCT: 1 thread. |dt| is the hit distance difference "
         "over the bounding-box diagonal where both hit.\n\n";
    o += "| scene | rays | OCCT us/ray | OCCT frame ms (extrap.) | ours frame ms | OCCT / ours | hit agreement % | "
         "ours-only / OCCT-only | face agreement % | abs(dt)/diag median / p99 / max | within 1e-6 % | interior "
         "rays: hit agreement % | interior abs(dt)/diag p99 / max | interior abs(dt) > 1e-6 diag: ours nearer / OCCT "
         "nearer |\n";
    o += "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n";
    for (const json& r : t["rows"])
        o += "| " + s(r, "scene") + " | " + std::to_string(n(r, "rays")) + " | " + num(d(r, "occt_us_per_ray"), 1) +
             " | " + ms(d(r, "occt_frame_ms_extrapolated")) + " | " + ms(d(r, "ours_frame_ms")) + " | " +
             num(d(r, "occt_over_ours"), 1) + "x | " + num(d(r, "hit_agreement_pct"), 2) + " | " +
             std::to_string(n(r, "ours_only_hits")) + " / " + std::to_string(n(r, "occt_only_hits")) + " | " +
             num(d(r, "face_agreement_pct"), 2) + " | " + sci(d(r, "dt_rel_median")) + " / " + sci(d(r, "dt_rel_p99")) +
             " / " + sci(d(r, "dt_rel_max")) + " | " + num(d(r, "dt_within_1e-6_pct"), 2) + " | " +
             std::to_string(n(r, "interior_rays")) + ": " + num(d(r, "interior_hit_agreement_pct"), 2) + " | " +
             sci(d(r, "interior_dt_rel_p99")) + " / " + sci(d(r, "interior_dt_rel_max")) + " | " +
             std::to_string(n(r, "interior_dt_over_1e-6_ours_nearer")) + " / " +
             std::to_string(n(r, "interior_dt_over_1e-6_occt_nearer")) + " |\n";
    o += "\n";
}

void tessellation(std::string& o, const json& doc, const json& t) {
    const bool embree = t.value("embree", false);
    o += "## Tessellating peer: BRepMesh + rasterization (OSMesa)" + std::string(embree ? " and Embree" : "") + "\n\n";
    o += "Deflection relative to the bounding-box diagonal, angular deflection " +
         num(d(t, "angular_deflection_rad"), 2) +
         " rad. Time = BRepMesh + copying the mesh out + rendering (rasterization: upload, draw, read back). "
         "dz = abs(t_mesh - t_exact)/diag where both hit our exact frame; disagreement = pixels hit by only one, "
         "over pixels hit by either (mostly the silhouette).";
    if (!embree) o += " Embree was not built in (no libembree-dev at configure time).";
    o += "\n\n";
    for (const json& r : t["rows"]) {
        const json& ours = r["ours"];
        const std::string key = s(r, "scene");
        o += "**" + title_of(doc, key) + "** (" + key + "): ours (exact) frame " + ms(d(ours, "frame_ms")) +
             " ms, plus " + ms(d(ours, "convert_and_map_mesh_ms")) +
             " ms of NURBS conversion and map meshing at import; Newton tolerance " + sci(d(ours, "tolerance_rel")) +
             " x diag.\n\n";
        o += "| deflection | triangles | mesh ms | raster ms | raster total ms | dz median | dz p99 | dz max | "
             "interior dz p99 | disagreement %";
        if (embree) o += " | Embree build ms | Embree render ms | Embree total ms | Embree dz median";
        o += " |\n|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:";
        if (embree) o += "|---:|---:|---:|---:";
        o += "|\n";
        for (const json& lv : r["levels"]) {
            const json& ra = lv["raster"];
            o += "| " + sci(d(lv, "relative_deflection")) + " | " + std::to_string(n(lv, "triangles")) + " | " +
                 ms(d(lv, "mesh_ms")) + " | " + ms(d(ra, "render_ms")) + " | " + ms(d(ra, "total_ms")) + " | " +
                 sci(d(ra, "dz_rel_median")) + " | " + sci(d(ra, "dz_rel_p99")) + " | " + sci(d(ra, "dz_rel_max")) +
                 " | " + sci(d(ra, "interior_dz_rel_p99")) + " | " + num(d(ra, "hit_disagreement_pct"), 2);
            if (embree && lv.contains("embree")) {
                const json& e = lv["embree"];
                o += " | " + ms(d(e, "build_ms")) + " | " + ms(d(e, "render_ms")) + " | " + ms(d(e, "total_ms")) +
                     " | " + sci(d(e, "dz_rel_median"));
            }
            o += " |\n";
        }
        // Equal time: the finest mesh whose first frame (BRepMesh + extract + raster)
        // costs no more than ours (NURBS conversion + map mesh + frame): what a mesh
        // renderer gets for our time. Both exclude reading the file.
        const double ours_first = d(ours, "frame_ms") + d(ours, "convert_and_map_mesh_ms");
        const json* at_time = nullptr;
        for (const json& lv : r["levels"])
            if (d(lv["raster"], "total_ms") <= ours_first) at_time = &lv;
        o += "\nFirst frame after reading the file: ours " + ms(ours_first) + " ms. ";
        if (at_time)
            o += "At equal time the finest mesh (deflection " + sci(d(*at_time, "relative_deflection")) + ", " +
                 ms(d((*at_time)["raster"], "total_ms")) + " ms) has depth error median " +
                 sci(d((*at_time)["raster"], "dz_rel_median")) + ", p99 " + sci(d((*at_time)["raster"], "dz_rel_p99")) +
                 " (interior " + sci(d((*at_time)["raster"], "interior_dz_rel_p99")) + ") x diag. ";
        else
            o += "Even the coarsest mesh is slower than that. ";
        if (!r["levels"].empty()) {
            const json& finest = r["levels"].back();
            o += "Further frames of the same model (camera moved, mesh kept): ours " + ms(d(ours, "frame_ms")) +
                 " ms, rasterizing the finest mesh " + ms(d(finest["raster"], "render_ms")) + " ms";
            if (finest.contains("embree"))
                o += ", Embree " + ms(d(finest["embree"], "render_ms")) + " ms (+" +
                     ms(d(finest["embree"], "build_ms")) + " ms BVH)";
            o += ". Accuracy of the finest mesh: median " + sci(d(finest["raster"], "dz_rel_median")) + ", p99 " +
                 sci(d(finest["raster"], "dz_rel_p99")) + " (interior " +
                 sci(d(finest["raster"], "interior_dz_rel_p99")) + ") x diag";
        }
        if (doc.contains("occt"))
            for (const json& q : doc["occt"]["rows"])
                if (s(q, "scene") == key)
                    o += "; ours against OCCT's exact hits: median " + sci(d(q, "dt_rel_median")) + ", p99 " +
                         sci(d(q, "dt_rel_p99")) + " (interior " + sci(d(q, "interior_dt_rel_p99")) + ") x diag";
        o += ".\n\n";
    }
}

void mesh_tracer(std::string& o, const json& t) {
    o += "## Frame vs mesh tracer (Embree)\n\n";
    if (!t.value("embree", false)) {
        o += "Embree was not built in (no libembree-dev at configure time): no figures.\n\n";
        return;
    }
    o += "Our exact frame (map + Newton + shading of the prepared model) against Embree tracing the same camera's "
         "rays through a BRepMesh mesh at " +
         sci(d(t, "fine_relative_deflection")) +
         " of the diagonal (trace only, "
         "BVH built beforehand), " +
         std::to_string(n(t, "threads")) +
         " thread(s) each; goal: at most 2x. First "
         "frame after reading the file: ours (NURBS conversion + map mesh + prepare + frame) against BRepMesh at " +
         sci(d(t, "coarse_relative_deflection")) +
         " + mesh copy + BVH + trace; goal: at most 1x. The two sides run "
         "alternately (frames: " +
         std::to_string(t["rows"].empty() ? 0 : n(t["rows"][0], "pairs")) +
         " pairs, first "
         "frames: " +
         std::to_string(t["rows"].empty() ? 0 : n(t["rows"][0], "first_frame_pairs")) +
         "), so that both "
         "see the same load of the machine; times are medians, ratios the medians of the pairs' ratios.\n\n";
    o += "| scene | faces | ours frame ms | Embree trace ms | triangles | frame / trace | ours first frame ms | "
         "mesh first frame ms | first / mesh first |\n|---|---:|---:|---:|---:|---:|---:|---:|---:|\n";
    for (const json& x : t["rows"])
        o += "| " + s(x, "title") + " | " + std::to_string(n(x, "faces")) + " | " + ms(d(x, "ours_frame_ms")) + " | " +
             ms(d(x, "embree_trace_ms")) + " | " + std::to_string(n(x, "fine_triangles")) + " | **" +
             num(d(x, "frame_over_trace"), 2) + "** | " + ms(d(x, "ours_first_frame_ms")) + " | " +
             ms(d(x, "mesh_first_frame_ms")) + " | **" + num(d(x, "first_over_mesh_first"), 2) + "** |\n";
    o += "\nWhere our frame goes (one run's stages, ms): the map, the primary Newton pass, the rescue and "
         "nearer-sheet passes, shading, the rest (set-up, statistics).\n\n| scene | map | primary | rescue + nearer | "
         "shade | rest | frame |\n|---|---:|---:|---:|---:|---:|---:|\n";
    for (const json& x : t["rows"]) {
        if (!x.contains("ours_frame_stages")) continue;
        const json& g = x["ours_frame_stages"];
        o += "| " + s(x, "title") + " | " + ms(d(g, "preliminary_map_ms")) + " | " + ms(d(g, "newton_primary_ms")) +
             " | " + ms(d(g, "newton_rescue_ms")) + " | " + ms(d(g, "shade_ms")) + " | " + ms(d(g, "other_ms")) +
             " | " + ms(d(g, "total_ms")) + " |\n";
    }
    if (t.contains("missing_models") && !t["missing_models"].empty()) {
        o += "\nNot found under the models directory (skipped):";
        for (const json& m : t["missing_models"]) o += " `" + m.get<std::string>() + "`";
        o += "\n";
    }
    o += "\n";
}

void scaling(std::string& o, const json& t) {
    o += "## Scaling (`proposed`)\n\n";
    const json& r = t["resolution"];
    o += "Resolution (" + s(r, "scene") + ", " + std::to_string(n(t, "threads")) + " thread(s)):\n\n";
    o += "| size | frame ms | Newton ms | map ms | ns per pixel | pixels hit | runs |\n"
         "|---:|---:|---:|---:|---:|---:|---:|\n";
    for (const json& x : r["rows"])
        o += "| " + std::to_string(n(x, "size")) + "^2 | " + ms(d(x, "frame_ms")) + " | " + ms(d(x, "newton_ms")) +
             " | " + ms(d(x, "preliminary_map_ms")) + " | " + num(d(x, "ns_per_pixel"), 0) + " | " +
             std::to_string(n(x, "pixels_hit")) + " | " + std::to_string(n(x, "runs")) + " |\n";
    const json& p = t["patches"];
    o += "\nPatches (" + std::to_string(n(p, "width")) + "x" + std::to_string(n(p, "height")) + "):\n\n";
    o += "| scene | patches | map triangles | frame ms | Newton ms | of which rescue ms | map ms | pixels hit | mean "
         "iterations | primary pass ns per solve |\n|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n";
    for (const json& x : p["rows"])
        o += "| " + s(x, "scene") + " | " + std::to_string(n(x, "patches")) + " | " +
             std::to_string(n(x, "map_triangles")) + " | " + ms(d(x, "frame_ms")) + " | " + ms(d(x, "newton_ms")) +
             " | " + ms(d(x, "rescue_ms")) + " | " + ms(d(x, "preliminary_map_ms")) + " | " +
             std::to_string(n(x, "pixels_hit")) + " | " + num(d(x, "mean_iterations"), 2) + " | " +
             num(d(x, "primary_ns_per_solve"), 0) + " |\n";
    const json& th = t["threads_scaling"];
    o += "\nThreads (interleaved runs; " + std::to_string(n(th, "hardware_threads")) +
         " hardware threads; CPU/wall is the process CPU time over the wall time of a frame: the cores it really got):"
         "\n\n";
    o += "| scene | frame ms, 1 thread | frame ms, 2 threads | frame speed-up | Newton speed-up | CPU/wall, 2 threads "
         "|\n|---|---:|---:|---:|---:|---:|\n";
    for (const json& x : th["rows"])
        o += "| " + s(x, "scene") + " | " + ms(d(x["threads_1"], "frame_ms")) + " | " +
             ms(d(x["threads_2"], "frame_ms")) + " | " + num(d(x, "frame_speedup"), 2) + "x | " +
             num(d(x, "newton_speedup"), 2) + "x | " + num(d(x["threads_2"], "cpu_over_wall"), 2) + " |\n";
    o += "\n";
}

void look(std::string& o, const json& t) {
    o += "## Image options: anti-aliasing + feature lines, shadows, a section, a ground\n\n";
    o += "Whole-frame times of one prepared scene and camera rendered five ways, interleaved and their order "
         "rotated from run to run (at least " +
         std::to_string(n(t, "min_runs")) +
         (d(t, "min_ms") > 0 ? " runs, more until each variant has " + num(d(t, "min_ms") / 1e3, 0) + " s of frames"
                             : " runs") +
         "), " + std::to_string(n(t, "width")) + "x" + std::to_string(n(t, "height")) + ", " +
         std::to_string(n(t, "threads")) + " thread(s): `plain` (one ray per pixel), `aa_edges` (" +
         std::to_string(n(t, "antialias_rays")) +
         " extra samples per edge pixel, exact rays where an edge can cross them, and feature lines), `shadows` "
         "(the key light's map and Newton along light rays), `section` (a plane through the box centre facing the "
         "eye, caps on), `ground` (a shadow catcher under the part). Ratios to `plain` from the medians, in brackets "
         "from "
         "the minima (interference from other work only adds time); targets: aa_edges <= " +
         num(d(t, "target_aa_edges_over_plain"), 1) + "x, shadows <= " + num(d(t, "target_shadows_over_plain"), 1) +
         "x, section <= " + num(d(t, "target_section_over_plain"), 2) +
         "x, ground <= " + num(d(t, "target_ground_over_plain"), 1) + "x.\n\n";
    o +=
        "| scene | runs | plain ms (min) | aa_edges ms (min) | shadows ms (min) | section ms (min) | ground ms (min) | "
        "aa_edges / plain | shadows / plain | section / plain | ground / plain "
        "|\n|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n";
    auto ratio = [](const json& r) {
        return "**" + num(d(r, "median"), 2) + "x** (" + num(d(r, "min"), 2) + "x) " +
               (r.value("meets_target", false) ? "ok" : "over " + num(d(r, "target"), 1) + "x");
    };
    for (const json& r : t["rows"]) {
        o += "| " + s(r, "title") + " | " + std::to_string(n(r, "runs"));
        for (const char* v : {"plain", "aa_edges", "shadows", "section", "ground"})
            o += " | " + ms(d(r[v], "frame_ms")) + " (" + ms(d(r[v], "frame_ms_min")) + ")";
        for (const char* q : {"aa_edges_over_plain", "shadows_over_plain", "section_over_plain", "ground_over_plain"})
            o += " | " + ratio(r[q]);
        o += " |\n";
    }
    if (t.contains("sheet")) {
        const json& sh = t["sheet"];
        o += "\nContact sheet (" + s(sh, "scene") + ", views front, top, right, iso, uncached: import, prepare, " +
             "frames): one request " + ms(d(sh, "sheet_ms")) + " ms against four " + ms(d(sh, "separate_ms")) +
             " ms: **" + num(d(sh, "sheet_over_separate"), 2) + "x** (target <= " + num(d(sh, "target"), 2) + "x" +
             (sh.value("meets_target", false) ? ", ok" : ", over") + ").\n";
    }
    o += "\nWhere the extra time goes: median stage times, ms (`shadow_map` draws the light's map; the light rays' "
         "solves are part of `shade` and `antialias`).\n\n";
    o += "| scene | variant | map | Newton | shade | antialias | edges | shadow_map | frame |\n"
         "|---|---|---:|---:|---:|---:|---:|---:|---:|\n";
    for (const json& r : t["rows"])
        for (const char* v : {"plain", "aa_edges", "shadows", "section", "ground"}) {
            const json& st = r[v]["stages_ms"];
            o += "| " + s(r, "title") + " | " + v;
            for (const char* k : {"map", "newton", "shade", "antialias", "edges", "shadow_map"})
                o += " | " + ms(d(st, k));
            o += " | " + ms(d(r[v], "frame_ms")) + " |\n";
        }
    o += "\n";
}

void batch(std::string& o, const json& t) {
    o += "## Batch job: one job against one CLI process per output\n\n";
    o += std::to_string(t["files"].size()) + " files x (render " + std::to_string(n(t["render"], "width")) + "x" +
         std::to_string(n(t["render"], "height")) + ", STL, glb) = " + std::to_string(n(t, "outputs")) +
         " outputs: one job through `nurbsrt serve` (default settings; submitted, polled, every artifact "
         "downloaded) against one `nurbsrt render`/`nurbsrt convert` process per output run one after another, "
         "interleaved run by run. Stage sums in ms: reads (file parses; the job reads each file once for all its "
         "outputs), render frames, conversion meshing and writing.\n\n";
    o += "| run | CLI loop ms | job ms | job / CLI | CLI reads (ms) | job reads (ms) | CLI frames | job frames | "
         "CLI mesh+write | job mesh+write |\n|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n";
    int k = 0;
    for (const json& r : t["runs"]) {
        const json &c = r["cli_loop_stages"], &j = r["job_stages"];
        o += "| " + std::to_string(++k) + " | " + ms(d(r, "cli_loop_ms")) + " | " + ms(d(r, "job_ms")) + " | **" +
             num(d(r, "ratio"), 3) + "** | " + std::to_string(n(c, "reads")) + " (" + ms(d(c, "read_ms")) + ") | " +
             std::to_string(n(j, "reads")) + " (" + ms(d(j, "read_ms")) + ") | " + ms(d(c, "render_ms")) + " | " +
             ms(d(j, "render_ms")) + " | " + ms(d(c, "write_ms")) + " | " + ms(d(j, "write_ms")) + " |\n";
    }
    o += "\nMedian job / CLI loop: **" + num(d(t, "median_ratio"), 3) + "** (" + num(d(t, "min_ratio"), 3) + "-" +
         num(d(t, "max_ratio"), 3) + ").\n\n";
}

}  // namespace

std::string bench_markdown(const json& doc) {
    std::string o = "# nurbsrt bench (" + s(doc, "mode") + ")\n\n";
    machine(o, doc);
    if (doc.contains("table1")) table1(o, doc["table1"]);
    if (doc.contains("precision")) precision(o, doc["precision"]);
    if (doc.contains("occt")) occt(o, doc["occt"]);
    if (doc.contains("tessellation")) tessellation(o, doc, doc["tessellation"]);
    if (doc.contains("meshtracer")) mesh_tracer(o, doc["meshtracer"]);
    if (doc.contains("scaling")) scaling(o, doc["scaling"]);
    if (doc.contains("look")) look(o, doc["look"]);
    if (doc.contains("batch")) batch(o, doc["batch"]);
    return o;
}

}  // namespace nurbsrt::bench
