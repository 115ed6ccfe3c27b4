// Newton iteration (Sisojevs & Glazs 2010, eq. 5-14 and Martin et al.): accuracy against exact
// ray intersections of analytic patches, equality of the proposed step with the
// textbook Newton step, agreement of the two methods, termination criteria.
#include <gtest/gtest.h>

#include <cstdio>
#include <random>

#include "renderer/solve/newton.h"
#include "renderer_test_surfaces.h"

using namespace nurbsrt;
using namespace nurbsrt::testing;

namespace {

UvBox full_box(const NurbsSurface& s) { return {s.u_begin(), s.u_end(), s.v_begin(), s.v_end()}; }

CameraSpec ortho_of(const AnalyticPatch& p) {
    CameraSpec s = p.view;
    s.projection = Projection::orthographic;
    s.ortho_height = 1.1 * p.box.diagonal();
    s.eye = s.target - 2.0 * p.box.diagonal() * normalize(s.target - s.eye);
    return s;
}

struct Tally {
    int hits = 0, converged = 0;
    long iterations = 0;
    double max_t_err = 0;      // relative to the patch diagonal
    double max_t_err_cos = 0;  // times |cos(incidence)|
    int over_1e9 = 0, other_root = 0;
};

}  // namespace

TEST(RendererNewton, TestPatchesAreExact) {
    const AnalyticPatch cyl = cylinder_patch(), sph = sphere_patch(1.5);
    for (double u = 0; u <= 1; u += 0.05)
        for (double v = 0; v <= 1; v += 0.1) {
            const Vec3 c = project(evaluate(cyl.surface, u, v));
            EXPECT_NEAR(std::hypot(c.x, c.y), 2.0, 1e-14);
            EXPECT_NEAR(length(project(evaluate(sph.surface, u, v))), 1.5, 1e-14);
        }
    // Monkey saddle control net reproduces z = x^3 - 3 x y^2.
    const AnalyticPatch sad = saddle_patch();
    for (double u = 0; u <= 1; u += 0.1)
        for (double v = 0; v <= 1; v += 0.1) {
            const Vec3 c = project(evaluate(sad.surface, u, v));
            EXPECT_NEAR(c.z, c.x * c.x * c.x - 3 * c.x * c.y * c.y, 1e-14);
        }
}

// Cramer's rule on eq. (6)-(7): (du, dv) = (w / M)(M_U, M_V) is exactly -J^{-1} F.
TEST(RendererNewton, ProposedStepEqualsTextbookStep) {
    std::mt19937_64 rng(11);
    std::uniform_real_distribution<double> U(0, 1);
    double worst = 0;
    int compared = 0;
    for (const AnalyticPatch& p : all_patches())
        for (const CameraSpec& spec : {p.view, ortho_of(p)}) {
            const Camera cam(spec);
            const NurbsSurface proj = project_surface(cam, p.surface);
            for (int k = 0; k < 300; ++k) {
                const double u = U(rng), v = U(rng);
                const ScreenPoint s = cam.screen(U(rng) * spec.width, U(rng) * spec.height);
                const SurfaceDerivs d = evaluate_d1(proj, u, v);
                Step a, b;
                const bool oka = proposed_step(d, s, 1e-12, a), okb = textbook_step(d, s, 1e-12, b);
                ASSERT_EQ(oka, okb) << p.name;
                if (!oka) continue;
                const double scale = std::hypot(b.du, b.dv) + 1e-300;
                const double diff = std::hypot(a.du - b.du, a.dv - b.dv) / scale;
                worst = std::max(worst, diff);
                ++compared;
                EXPECT_LT(diff, 1e-10) << p.name << " u=" << u << " v=" << v;
            }
        }
    std::printf("[ proposed vs textbook step ] %d steps, max relative difference %.3g\n", compared, worst);
}

// Every pixel of a 61x47 view whose ray hits the analytic patch: both methods,
// started like the map (nearest grid cell centre), converge to the exact hit.
TEST(RendererNewton, HitsMatchAnalyticIntersection) {
    for (NewtonMethod method : {NewtonMethod::proposed, NewtonMethod::martin}) {
        Tally all;
        for (const AnalyticPatch& p : all_patches())
            for (const CameraSpec& spec : {p.view, ortho_of(p)}) {
                const Camera cam(spec);
                const NurbsSurface proj = project_surface(cam, p.surface);
                const GridStart grid(p.surface);
                NewtonParams params;
                params.eps = default_newton_eps(p.box, 1e-9);
                Tally tl;
                for (int j = 0; j < spec.height; ++j)
                    for (int i = 0; i < spec.width; ++i) {
                        const Ray ray = cam.pixel_ray(i, j);
                        const std::optional<double> ta = p.hit(ray);
                        if (!ta) continue;
                        ++tl.hits;
                        const Vec2 st = grid.nearest(ray.origin + *ta * ray.dir);
                        const NewtonResult r =
                            method == NewtonMethod::proposed
                                ? newton_proposed(proj, cam, cam.pixel_screen(i, j), st.x, st.y, full_box(p.surface),
                                                  params)
                                : newton_martin(p.surface, ray, st.x, st.y, full_box(p.surface), params);
                        if (r.status != NewtonStatus::converged) continue;
                        ++tl.converged;
                        tl.iterations += r.iterations;
                        // (12) bounds the hit point's distance from the ray by eps; along
                        // the ray that is an error of eps / |cos(incidence)|. So the test
                        // checks |t - t_exact| |cos| <= 1e-9 diag for every pixel, and
                        // records the plain |t - t_exact| as well.
                        const Vec3 c = project(evaluate(p.surface, r.u, r.v));
                        const double cosi = std::abs(dot(surface_normal(p.surface, r.u, r.v, false), ray.dir));
                        const double err = std::abs(r.t - *ta) / p.box.diagonal();
                        const double dist_from_ray = length(cross(c - ray.origin, ray.dir));
                        if (err * cosi > 1e-9 && dist_from_ray < 2 * params.eps && r.t > *ta) {
                            ++tl.other_root;  // a farther intersection of the same ray: valid, not the first
                            continue;
                        }
                        tl.max_t_err = std::max(tl.max_t_err, err);
                        tl.max_t_err_cos = std::max(tl.max_t_err_cos, err * cosi);
                        if (err > 1e-9) ++tl.over_1e9;
                        EXPECT_LT(err * cosi, 1e-9) << p.name << " pixel " << i << "," << j;
                        EXPECT_LT(dist_from_ray, params.eps) << p.name;
                    }
                EXPECT_GT(tl.hits, 300) << p.name;
                EXPECT_GE(tl.converged, tl.hits * 0.99) << p.name;
                EXPECT_LE(tl.other_root, tl.hits * 0.005) << p.name;
                std::printf(
                    "[ %-8s %-11s %-5s ] hits %4d conv %4d other root %d mean it %.2f max |dt|/diag %.2g "
                    "(x cos %.2g), %d over 1e-9\n",
                    newton_method_name(method), p.name.c_str(), cam.perspective() ? "persp" : "ortho", tl.hits,
                    tl.converged, tl.other_root, double(tl.iterations) / std::max(1, tl.converged), tl.max_t_err,
                    tl.max_t_err_cos, tl.over_1e9);
                all.hits += tl.hits;
                all.converged += tl.converged;
                all.iterations += tl.iterations;
                all.max_t_err = std::max(all.max_t_err, tl.max_t_err);
                all.over_1e9 += tl.over_1e9;
                all.other_root += tl.other_root;
            }
        std::printf(
            "[ %-8s all ] hits %d converged %d other root %d mean iterations %.3f max |dt|/diag %.2g, "
            "%d over 1e-9\n",
            newton_method_name(method), all.hits, all.converged, all.other_root, double(all.iterations) / all.converged,
            all.max_t_err, all.over_1e9);
    }
}

// Calls f(i, j, ray, t, start) for every pixel of `cam` whose ray hits the
// analytic patch at t, with the grid start nearest that exact hit.
template <class F>
void for_each_hit(const AnalyticPatch& p, const Camera& cam, const GridStart& grid, F&& f) {
    for (int j = 0; j < cam.height(); ++j)
        for (int i = 0; i < cam.width(); ++i) {
            const Ray ray = cam.pixel_ray(i, j);
            const std::optional<double> t = p.hit(ray);
            if (t) f(i, j, ray, *t, grid.nearest(ray.origin + *t * ray.dir));
        }
}

TEST(RendererNewton, ProposedAndMartinAgree) {
    int compared = 0;
    double max_duv = 0, max_dt = 0;
    for (const AnalyticPatch& p : all_patches()) {
        const Camera cam(p.view);
        const NurbsSurface proj = project_surface(cam, p.surface);
        const GridStart grid(p.surface);
        NewtonParams params;
        params.eps = default_newton_eps(p.box, 1e-9);
        for_each_hit(p, cam, grid, [&](int i, int j, const Ray& ray, double ta, Vec2 st) {
            const NewtonResult a =
                newton_proposed(proj, cam, cam.pixel_screen(i, j), st.x, st.y, full_box(p.surface), params);
            const NewtonResult b = newton_martin(p.surface, ray, st.x, st.y, full_box(p.surface), params);
            if (a.status != NewtonStatus::converged || b.status != NewtonStatus::converged) return;
            if (std::abs(a.t - ta) > 1e-6 || std::abs(b.t - ta) > 1e-6) return;  // another root
            ++compared;
            const double cosi = std::abs(dot(surface_normal(p.surface, a.u, a.v, false), ray.dir));
            max_duv = std::max({max_duv, std::abs(a.u - b.u), std::abs(a.v - b.v)});
            max_dt = std::max(max_dt, std::abs(a.t - b.t) / p.box.diagonal() * cosi);
            EXPECT_NEAR(a.u, b.u, 1e-7) << p.name;
            EXPECT_NEAR(a.v, b.v, 1e-7) << p.name;
            EXPECT_LT(std::abs(a.t - b.t) / p.box.diagonal() * cosi, 2e-9) << p.name;
        });
    }
    EXPECT_GT(compared, 1000);
    std::printf("[ proposed vs martin ] %d pixels, max |duv| %.2g, max |dt| |cos|/diag %.2g\n", compared, max_duv,
                max_dt);
}

// Rays passing within a hair of the sphere octant's pole (a collapsed row of
// control points, where S_v vanishes) still converge to the exact hit.
TEST(RendererNewton, DegeneratePole) {
    const AnalyticPatch p = sphere_patch(1.5);
    CameraSpec spec = look({0.3, 0.25, 5.0}, {0.002, 0.003, 1.5}, {0, 1, 0}, 2.0);
    for (Projection proj : {Projection::perspective, Projection::orthographic}) {
        spec.projection = proj;
        spec.ortho_height = 0.05;
        const Camera cam(spec);
        const NurbsSurface ps = project_surface(cam, p.surface);
        const GridStart grid(p.surface, 200);
        NewtonParams params;
        params.eps = default_newton_eps(p.box, 1e-9);
        int hits = 0, conv = 0;
        for (int j = 0; j < spec.height; ++j)
            for (int i = 0; i < spec.width; ++i) {
                const Ray ray = cam.pixel_ray(i, j);
                const std::optional<double> ta = p.hit(ray);
                if (!ta) continue;
                ++hits;
                const Vec2 st = grid.nearest(ray.origin + *ta * ray.dir);
                const NewtonResult a =
                    newton_proposed(ps, cam, cam.pixel_screen(i, j), st.x, st.y, full_box(p.surface), params);
                const NewtonResult b = newton_martin(p.surface, ray, st.x, st.y, full_box(p.surface), params);
                for (const NewtonResult& r : {a, b}) {
                    if (r.status != NewtonStatus::converged) continue;
                    ++conv;
                    const double cosi = std::abs(dot(surface_normal(p.surface, r.u, r.v, false), ray.dir));
                    EXPECT_LT(std::abs(r.t - *ta) / p.box.diagonal() * cosi, 1e-9);
                }
            }
        EXPECT_GT(hits, 100);
        EXPECT_GE(conv, 2 * hits * 0.98);
        std::printf("[ pole %s ] hits %d, converged %d of %d runs\n", cam.perspective() ? "persp" : "ortho", hits, conv,
                    2 * hits);
    }
}

TEST(RendererNewton, TerminationCriteria) {
    const AnalyticPatch p = sphere_patch(1.5);
    const Camera cam(p.view);
    const NurbsSurface ps = project_surface(cam, p.surface);
    const UvBox box = full_box(p.surface);
    NewtonParams params;
    params.eps = default_newton_eps(p.box, 1e-9);
    // Singular (14): starting exactly on the pole row, where P_v is parallel to P
    // (proposed) and C_v = 0 (martin).
    const int ci = cam.width() / 2, cj = cam.height() / 2;
    EXPECT_EQ(newton_proposed(ps, cam, cam.pixel_screen(ci, cj), 0.0, 0.5, box, params).status, NewtonStatus::singular);
    EXPECT_EQ(newton_martin(p.surface, cam.pixel_ray(ci, cj), 0.0, 0.5, box, params).status, NewtonStatus::singular);
    // Max iterations: a budget of one step from a far start.
    NewtonParams one = params;
    one.max_iterations = 1;
    const NewtonResult m = newton_martin(p.surface, cam.pixel_ray(ci, cj), 0.9, 0.1, box, one);
    EXPECT_EQ(m.status, NewtonStatus::max_iterations);
    EXPECT_EQ(m.iterations, 1);
    // A ray that misses the octant (aimed at x < 0): no success, and a failure status.
    CameraSpec away = p.view;
    away.target = {-2.0, 0.6, 0.6};
    const Camera cam2(away);
    const NurbsSurface ps2 = project_surface(cam2, p.surface);
    const Ray miss = cam2.pixel_ray(cam2.width() / 2, cam2.height() / 2);
    ASSERT_FALSE(p.hit(miss));
    for (const NewtonResult& r :
         {newton_proposed(ps2, cam2, cam2.pixel_screen(cam2.width() / 2, cam2.height() / 2), 0.5, 0.1, box, params),
          newton_martin(p.surface, miss, 0.5, 0.1, box, params)}) {
        EXPECT_NE(r.status, NewtonStatus::converged);
        std::printf("[ miss ] status %s after %d iterations\n", newton_status_name(r.status), r.iterations);
    }
    // Already at the root: zero iterations.
    const Ray ray = cam.pixel_ray(ci, cj);
    const double ta = *p.hit(ray);
    const Vec2 st = GridStart(p.surface).nearest(ray.origin + ta * ray.dir);
    const NewtonResult first = newton_martin(p.surface, ray, st.x, st.y, box, params);
    ASSERT_EQ(first.status, NewtonStatus::converged);
    const NewtonResult again = newton_martin(p.surface, ray, first.u, first.v, box, params);
    EXPECT_EQ(again.status, NewtonStatus::converged);
    EXPECT_EQ(again.iterations, 0);
    // Behind the eye: from an origin moved past the hit, the same line's root lies
    // behind the ray's origin (both systems describe the whole line).
    const NewtonResult b =
        newton_martin(p.surface, Ray{ray.origin + (ta + 5) * ray.dir, ray.dir}, first.u, first.v, box, params);
    EXPECT_EQ(b.status, NewtonStatus::behind_eye);
}

// Iterations with a looser tolerance: the cost of eps = 1e-9 diag over 1e-6 diag.
TEST(RendererNewton, ToleranceCost) {
    for (double rel : {1e-6, 1e-9}) {
        long it = 0;
        int n = 0;
        for (const AnalyticPatch& p : all_patches()) {
            const Camera cam(p.view);
            const NurbsSurface proj = project_surface(cam, p.surface);
            const GridStart grid(p.surface);
            NewtonParams params;
            params.eps = rel * p.box.diagonal();
            for_each_hit(p, cam, grid, [&](int i, int j, const Ray&, double, Vec2 st) {
                const NewtonResult r =
                    newton_proposed(proj, cam, cam.pixel_screen(i, j), st.x, st.y, full_box(p.surface), params);
                if (r.status != NewtonStatus::converged) return;
                it += r.iterations;
                ++n;
            });
        }
        std::printf("[ eps %.0e diag ] mean proposed iterations %.3f over %d hits\n", rel, double(it) / n, n);
    }
}

// A full rational cylinder (radius 1, axis z, z in [0, 1]) whose seam is at u = 0 == u = 1,
// the point (1, 0, z). A ray hitting just past the seam (angle +0.05 rad, u ~ 0.0125),
// started just before it (u = 0.99): the step crosses u = 1. With the seam detected,
// Newton continues from u = 0 and converges; clamped at the box (the old behaviour)
// it stops on the seam, short of the ray.
TEST(RendererNewton, StepAcrossSeamWraps) {
    NurbsSurface s{.degree_u = 2,
                   .degree_v = 1,
                   .num_u = 9,
                   .num_v = 2,
                   .knots_u = {0, 0, 0, 0.25, 0.25, 0.5, 0.5, 0.75, 0.75, 1, 1, 1},
                   .knots_v = {0, 0, 1, 1},
                   .cp = {},
                   .rational = true};
    const double w = std::sqrt(0.5);
    const Vec3 circle[9] = {{1, 0, 0},   {1, 1, 0},  {0, 1, 0},  {-1, 1, 0}, {-1, 0, 0},
                            {-1, -1, 0}, {0, -1, 0}, {1, -1, 0}, {1, 0, 0}};
    for (int i = 0; i < 9; ++i)
        for (int j = 0; j < 2; ++j)
            s.cp.push_back(nurbsrt::testing::hpt(circle[i] + Vec3{0, 0, double(j)}, i % 2 ? w : 1.0));

    const UvBox box = face_uv_box(s, 0, 1, 0, 1, 1e-9);
    EXPECT_TRUE(box.wrap_u);
    EXPECT_FALSE(box.wrap_v);                                 // the circles z = 0 and z = 1 are distinct
    EXPECT_FALSE(face_uv_box(s, 0, 0.5, 0, 1, 1e-9).wrap_u);  // half a cylinder has no seam

    const double y = std::sin(0.05), x = std::cos(0.05);
    CameraSpec spec = nurbsrt::testing::look({5, y, 0.5}, {0, y, 0.5}, {0, 0, 1}, 10);
    spec.width = spec.height = 31;  // the centre pixel's ray is the axis of the view
    const Camera cam(spec);
    const int ci = 15, cj = 15;
    const Ray ray = cam.pixel_ray(ci, cj);
    const double ta = (5 - x) / std::abs(ray.dir.x);
    NewtonParams params;
    params.eps = 1e-10;
    const NurbsSurface ps = project_surface(cam, s);
    const NewtonResult a = newton_proposed(ps, cam, cam.pixel_screen(ci, cj), 0.99, 0.5, box, params);
    const NewtonResult b = newton_martin(s, ray, 0.99, 0.5, box, params);
    for (const NewtonResult& r : {a, b}) {
        ASSERT_EQ(r.status, NewtonStatus::converged) << newton_status_name(r.status);
        EXPECT_NEAR(r.t, ta, 1e-9);
        EXPECT_GT(r.u, 0.0);
        EXPECT_LT(r.u, 0.05);  // on the far side of the seam
    }
    UvBox clamped = box;
    clamped.wrap_u = false;
    EXPECT_NE(newton_martin(s, ray, 0.99, 0.5, clamped, params).status, NewtonStatus::converged);
}

// Every `stride`-th pixel (i, j) of the view whose right neighbour's ray hits
// the patch, with its ray and the start a pixel off: the (u, v) of that
// neighbour's exact hit (where the solves take several steps, some backtrack or fail).
template <class F>
void for_each_start_one_pixel_off(const AnalyticPatch& p, const Camera& cam, const GridStart& grid, int stride, F&& f) {
    for (int j = 0; j < cam.height(); j += stride)
        for (int i = 0; i < cam.width(); i += stride) {
            const Ray next = cam.pixel_ray(i + 1, j);
            const std::optional<double> ta = p.hit(next);
            if (ta) f(i, j, cam.pixel_ray(i, j), grid.nearest(next.origin + *ta * next.dir));
        }
}

// What both methods' solves on one analytic patch need: its view, the
// projected surface (proposed), the span tables, the whole parameter box, and
// the default tolerance.
struct SolveSetup {
    Camera cam;
    NurbsSurface proj;
    SurfaceSpans spans;
    UvBox box;
    NewtonParams params;
    explicit SolveSetup(const AnalyticPatch& p)
        : cam(p.view),
          proj(project_surface(cam, p.surface)),
          spans(make_surface_spans(p.surface)),
          box(full_box(p.surface)) {
        params.eps = default_newton_eps(p.box);
    }
};

// Newton on the power-form patches (surface_patches.h; the renderer's hot path)
// reaches the roots it reaches on the basis tables: the same outcome and
// steps, and the same root to far below the tolerance (the evaluations differ
// only in rounding). Proposed iterates on the projected coefficients
// (project_patches), Martin on the model's.
TEST(RendererNewton, PatchesGiveTheSameRoots) {
    int solves = 0, converged = 0;
    for (const AnalyticPatch& p : all_patches()) {
        const SolveSetup s(p);
        const auto& [cam, proj, spans, box, params] = s;
        const SurfacePatches patches = make_surface_patches(p.surface, spans);
        const SurfacePatches projected = project_patches(cam, patches);
        ASSERT_TRUE(patches.usable()) << p.name;
        for_each_start_one_pixel_off(p, cam, GridStart(p.surface), 2, [&](int i, int j, const Ray& ray, Vec2 st) {
            const ScreenPoint sp = cam.pixel_screen(i, j);
            const NewtonResult pairs[2][2] = {
                {newton_proposed(proj, cam, sp, st.x, st.y, box, params, &spans),
                 newton_proposed(proj, cam, sp, st.x, st.y, box, params, &spans, nullptr, &projected)},
                {newton_martin(p.surface, ray, st.x, st.y, box, params, &spans),
                 newton_martin(p.surface, ray, st.x, st.y, box, params, &spans, nullptr, &patches)}};
            for (const auto& r : pairs) {
                ++solves;
                converged += r[0].status == NewtonStatus::converged;
                EXPECT_EQ(r[0].status, r[1].status) << p.name;
                if (r[0].status != NewtonStatus::converged || r[1].status != NewtonStatus::converged) continue;
                EXPECT_EQ(r[0].iterations, r[1].iterations) << p.name;
                EXPECT_NEAR(r[0].u, r[1].u, 1e-9) << p.name;
                EXPECT_NEAR(r[0].v, r[1].v, 1e-9) << p.name;
                EXPECT_NEAR(r[0].t, r[1].t, 1e-3 * params.eps) << p.name;
            }
        });
    }
    std::printf("   %d solves on the patches and on the basis tables, %d converged\n", solves, converged);
    EXPECT_GT(solves, 1000);
    EXPECT_GT(converged, solves / 2);
}

// A start's derivatives handed in (`start`, as anti-aliasing does for the
// sub-pixel samples it solves from one neighbour's hit) give the very iterates
// of the solve that evaluates them itself: both methods, robust or not, from
// starts one pixel off.
TEST(RendererNewton, GivenStartDerivativesChangeNothing) {
    int solves = 0, converged = 0;
    for (const AnalyticPatch& p : all_patches()) {
        const SolveSetup s(p);
        const auto& [cam, proj, spans, box, defaults] = s;
        for (const bool robust : {false, true}) {
            NewtonParams params = defaults;
            params.robust = robust;
            for_each_start_one_pixel_off(p, cam, GridStart(p.surface), 3, [&](int i, int j, const Ray& ray, Vec2 st) {
                const SurfaceDerivs dp = evaluate_d1(proj, spans, st.x, st.y);
                const SurfaceDerivs dm = evaluate_d1(p.surface, spans, st.x, st.y);
                const ScreenPoint sp = cam.pixel_screen(i, j);
                const NewtonResult pairs[2][2] = {
                    {newton_proposed(proj, cam, sp, st.x, st.y, box, params, &spans),
                     newton_proposed(proj, cam, sp, st.x, st.y, box, params, &spans, &dp)},
                    {newton_martin(p.surface, ray, st.x, st.y, box, params, &spans),
                     newton_martin(p.surface, ray, st.x, st.y, box, params, &spans, &dm)}};
                for (const auto& r : pairs) {
                    ++solves;
                    converged += r[0].status == NewtonStatus::converged;
                    EXPECT_EQ(r[0].status, r[1].status) << p.name;
                    EXPECT_EQ(r[0].iterations, r[1].iterations) << p.name;
                    EXPECT_EQ(r[0].u, r[1].u) << p.name;
                    EXPECT_EQ(r[0].v, r[1].v) << p.name;
                    EXPECT_EQ(r[0].residual, r[1].residual) << p.name;
                    if (r[0].status == NewtonStatus::converged) {
                        EXPECT_EQ(r[0].t, r[1].t) << p.name;
                    }
                }
            });
        }
    }
    std::printf("   %d solves with and without the start's derivatives given, %d converged\n", solves, converged);
    EXPECT_GT(solves, 1000);
    EXPECT_GT(converged, solves / 2);
}
