// The exact peer: OCCT's IntCurvesFace_ShapeIntersector (importer/
// reference_intersector.h) on a uniform random subset of the same pixel rays as
// our frame. Its time per ray, extrapolated to the whole frame (plus its one-off
// set-up), is compared with our whole-frame time at the same thread count (the
// intersector is single-threaded; ctx.opt.threads is 1 unless asked otherwise),
// and its hits with ours: hit/miss agreement and |t_ours - t_occt| / diagonal.
#include <cmath>
#include <cstdint>
#include <numeric>

#include "bench/bench_context.h"
#include "core/split_mix.h"
#include "importer/reference/reference_intersector.h"

namespace nurbsrt::bench {

void run_occt(BenchContext& ctx) {
    // Rays per scene, and a wall-clock cap on casting them: the samples are in
    // random order, so any prefix is itself a uniform sample of the frame.
    const int max_rays = ctx.opt.quick ? 300 : 3000;
    const double budget_ms = ctx.opt.quick ? 1500 : 15000;
    nlohmann::json rows = nlohmann::json::array();
    for (BenchScene& sc : ctx.scenes) {
        const RenderResult& ours = exact_render(ctx, sc);
        const Camera cam(ctx.camera(sc, ctx.size));
        ctx.say("occt %s: loading IntCurvesFace_ShapeIntersector", sc.key.c_str());
        ReferenceIntersector ref(sc.file, sc.placements);
        const double diag = sc.scene.bbox.diagonal();
        const double t_max = 4.0 * diag + length(cam.spec().eye - sc.scene.bbox.center());
        const int W = cam.width(), H = cam.height();
        const size_t npx = static_cast<size_t>(W) * H;
        // A random permutation prefix of the pixels (partial Fisher-Yates).
        std::vector<uint32_t> order(npx);
        std::iota(order.begin(), order.end(), 0u);
        SplitMix64 rng{0x5eed0f0cc7ull ^ std::hash<std::string>{}(sc.key)};
        const size_t n_want = std::min<size_t>(static_cast<size_t>(max_rays), npx);
        for (size_t k = 0; k < n_want; ++k) std::swap(order[k], order[k + rng.next() % (npx - k)]);

        ctx.say("occt %s: casting up to %zu rays", sc.key.c_str(), n_want);
        long cast = 0, errors = 0, both_hit = 0, agree = 0, ours_only = 0, occt_only = 0, within_1e6 = 0;
        long face_match = 0;
        std::vector<double> dt, dt_interior;
        long interior = 0, interior_agree = 0, interior_ours_nearer = 0, interior_occt_nearer = 0;
        const std::vector<uint8_t> inner = interior_mask(ours.image);
        const auto t0 = Clock::now();
        double cast_ms = 0;
        for (size_t k = 0; k < n_want && cast_ms < budget_ms; ++k) {
            const uint32_t p = order[k];
            const int i = static_cast<int>(p % W), j = static_cast<int>(p / W);
            const ReferenceHit h = ref.cast(cam.pixel_ray(i, j), t_max);
            cast_ms = ms_since(t0);
            ++cast;
            if (h.error) {
                ++errors;
                continue;
            }
            const bool hit = ours.image.face[p] != 0;
            if (inner[p]) ++interior, interior_agree += hit == h.hit;
            if (hit == h.hit)
                ++agree;
            else if (hit)
                ++ours_only;
            else
                ++occt_only;
            if (hit && h.hit) {
                ++both_hit;
                const double d = std::fabs(static_cast<double>(ours.image.z[p]) - h.t) / diag;
                dt.push_back(d);
                if (inner[p]) {
                    dt_interior.push_back(d);
                    // A disagreement beyond the accuracy bound: which one claims the nearer hit
                    // (OCCT's intersector misses some near roots, on grazing rays over folded faces).
                    if (d > 1e-6) (ours.image.z[p] < h.t ? interior_ours_nearer : interior_occt_nearer)++;
                }
                if (d <= 1e-6) ++within_1e6;
                if (static_cast<int>(ours.image.face[p]) == h.face) ++face_match;
            }
        }
        const double per_ray_ms = cast ? cast_ms / static_cast<double>(cast) : 0;
        const double occt_frame_ms = ref.load_ms() + per_ray_ms * static_cast<double>(npx);
        const double our_frame_ms = median(sc.exact_frame_ms);
        const long judged = cast - errors;
        rows.push_back({{"scene", sc.key},
                        {"rays", cast},
                        {"rays_per_frame", npx},
                        {"intersector_errors", errors},
                        {"occt_read_ms", ref.read_ms()},
                        {"occt_load_ms", ref.load_ms()},
                        {"occt_us_per_ray", 1e3 * per_ray_ms},
                        {"occt_frame_ms_extrapolated", occt_frame_ms},
                        {"ours_frame_ms", our_frame_ms},
                        {"ours_us_per_pixel", 1e3 * our_frame_ms / static_cast<double>(npx)},
                        {"occt_over_ours", our_frame_ms > 0 ? occt_frame_ms / our_frame_ms : 0.0},
                        {"hit_agreement_pct", judged ? 100.0 * agree / judged : 0.0},
                        {"ours_only_hits", ours_only},
                        {"occt_only_hits", occt_only},
                        {"both_hit", both_hit},
                        {"face_agreement_pct", both_hit ? 100.0 * face_match / both_hit : 0.0},
                        {"dt_rel_median", median(dt)},
                        {"dt_rel_p99", percentile(dt, 0.99)},
                        {"dt_rel_max", max_of(dt)},
                        {"dt_within_1e-6_pct", both_hit ? 100.0 * within_1e6 / both_hit : 0.0},
                        {"interior_rays", interior},
                        {"interior_hit_agreement_pct", interior ? 100.0 * interior_agree / interior : 0.0},
                        {"interior_dt_rel_median", median(dt_interior)},
                        {"interior_dt_rel_p99", percentile(dt_interior, 0.99)},
                        {"interior_dt_rel_max", max_of(dt_interior)},
                        {"interior_dt_over_1e-6_ours_nearer", interior_ours_nearer},
                        {"interior_dt_over_1e-6_occt_nearer", interior_occt_nearer}});
    }
    ctx.doc["occt"] = {{"width", ctx.size},
                       {"height", ctx.size},
                       {"threads_ours", ctx.opt.threads},
                       {"threads_occt", 1},
                       {"intersector_tolerance", ReferenceIntersector::kDefaultTolerance},
                       {"rows", rows}};
}

}  // namespace nurbsrt::bench
