// Frame rendering: camera set-up, the preliminary map, then the passes of passes.h
// in order, with the stage timings (see render.h).
#include "renderer/render.h"

#include <tbb/task_arena.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <optional>
#include <thread>

#include "core/check.h"
#include "core/error.h"
#include "renderer/frame/frame.h"
#include "renderer/frame/mesh_screen_points.h"
#include "core/scene/explode.h"
#include "core/scene/nurbs.h"
#include "renderer/passes/passes.h"
#include "renderer/frame/pixel_solver.h"
#include "renderer/passes/shadow_rays.h"

namespace nurbsrt {
namespace {

// RenderImage's contract (render.h): every buffer holds its values for every
// pixel, row-major; the shadow flags exactly when shadows were asked for.
void check_image_contract(const RenderImage& im, bool shadows) {
    const size_t n = static_cast<size_t>(im.width) * static_cast<size_t>(im.height);
    NURBSRT_CHECK(im.rgba.size() == 4 * n && im.z.size() == n && im.normal.size() == 3 * n);
    NURBSRT_CHECK(im.face.size() == n && im.u.size() == n && im.v.size() == n && im.iterations.size() == n);
    NURBSRT_CHECK(im.shadow.size() == (shadows ? n : 0));
}

using Clock = std::chrono::steady_clock;
double ms_since(Clock::time_point t0) { return std::chrono::duration<double, std::milli>(Clock::now() - t0).count(); }

// The rescue's solves may take more steps than the primary ones: they start
// farther from the root (a neighbour's (u, v), a mesh vertex) and backtrack.
constexpr int kRescueMinIterations = 16;
// ... and halve a step that raises the residual at most twice (1/4), not four
// times: a pixel's rescue tries many starts, and one whose step must shrink
// further is on its way off the surface (a silhouette the ray misses) while
// another start reaches the root. Shadow rays keep four (shadow_rays.cpp):
// light rays grazing an occluder leak with two.
constexpr int kRescueBacktracks = 2;

tbb::task_arena::priority arena_priority(RenderPriority p) {
    switch (p) {
        case RenderPriority::low:
            return tbb::task_arena::priority::low;
        case RenderPriority::high:
            return tbb::task_arena::priority::high;
        case RenderPriority::normal:
            break;
    }
    return tbb::task_arena::priority::normal;
}

}  // namespace

RenderResult render(const Scene& scene, const Camera& camera, const RenderOptions& options) {
    const auto t0 = Clock::now();
    const PreparedScene prepared = prepare(scene, options.threads);
    const double prepare_ms = ms_since(t0);
    RenderResult res = render(prepared, camera, options);
    res.stats.prepare_ms = prepare_ms;
    res.stats.total_ms += prepare_ms;
    return res;
}

namespace {

// One frame: the passes of passes.h (render() adds the ghosts' second frame).
RenderResult render_frame(const PreparedScene& prepared, const Camera& camera, const RenderOptions& options) {
    const auto t_total = Clock::now();
    const Scene& scene = prepared.scene();
    const int W = camera.width(), H = camera.height();
    const int threads =
        options.threads > 0 ? options.threads : static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
    tbb::task_arena arena(threads, 1, arena_priority(options.priority));

    RenderResult res;
    RenderStats& st = res.stats;
    st.method = options.method;
    st.width = W;
    st.height = H;
    st.threads = threads;
    st.faces = st.patches = scene.faces.size();

    // The stages are laps of one clock, end to end, so they sum to total_ms: the
    // set-up before a pass is part of that pass's time.
    Clock::time_point last = t_total;
    const auto lap = [&last] {
        const auto now = Clock::now();
        const double ms = std::chrono::duration<double, std::milli>(now - last).count();
        last = now;
        return ms;
    };
    st.setup_ms = lap();

    // 1-2. Preliminary map (Sisojevs & Glazs 2010, eq. 4).
    throw_if_canceled(options);
    NURBSRT_CHECK(options.face_offsets.empty() || options.face_offsets.size() == scene.faces.size());
    const PreliminaryMap map =
        render_preliminary_map(prepared, camera, options.map_precision, {0, options.cancel.get()},
                               {&options.sections, &options.hidden_faces, &options.face_offsets});
    throw_if_canceled(options);
    st.preliminary_map_ms = lap();

    // 3-4. Newton per pixel from the map's start, trim test, then rescue.
    // Progress units: rows of the per-pixel passes (Newton, rescue, shading, and
    // anti-aliasing when asked for).
    Progress progress(options.progress, (options.antialias > 0 ? 4 : 3) * static_cast<int64_t>(H));
    const FaceCameras face_cameras(camera, options.face_offsets);
    const FrameContext ctx{prepared,
                           scene,
                           camera,
                           face_cameras,
                           map,
                           options,
                           arena,
                           progress,
                           W,
                           H,
                           static_cast<uint32_t>(scene.faces.size()),
                           moved_bbox(scene, options.face_offsets)};
    FrameBuffers buf(ctx);
    st.setup_ms += lap();
    // The per-face set-up that depends on the camera: proposed's projection of
    // the faces' patches (the rest was done once by prepare()).
    const ProjectedFaces projected = project_faces(ctx);
    Solver solver{ctx, projected, options.newton, {}};
    if (!(solver.params.eps > 0)) solver.params.eps = default_newton_eps(ctx.bbox);
    st.tolerance = solver.params.eps;
    // Rescue solves: clamp-and-continue at face borders, backtracking, a few more steps.
    solver.robust = solver.params;
    solver.robust.robust = true;
    solver.robust.max_iterations = std::max(solver.robust.max_iterations, kRescueMinIterations);
    solver.robust.backtracks = kRescueBacktracks;

    primary_pass(ctx, solver, buf);
    st.newton_primary_ms = ms_since(last);  // a part of newton_ms, not a stage of its own

    if (options.rescue) {
        const MeshScreenPoints screen_points(ctx);
        rescue_pass(ctx, solver, screen_points, buf);
        throw_if_canceled(options);
        st.rescue_nearer += nearer_sheet_pass(ctx, solver, screen_points, buf);
    } else {
        progress.add(H);
    }
    st.newton_ms = lap();

    // 5. Shading from the exact normal, with the key light's exact shadows
    // when asked for (their map drawn first); AOVs.
    std::optional<KeyLightShadows> shadows;
    st.shadows = options.shadows || options.ground;  // the ground takes the key light's shadows
    if (st.shadows) {
        throw_if_canceled(options);
        shadows.emplace(ctx, solver, light_rig(camera).key);
        st.shadow_map_size = shadows->map_size();
        st.shadow_map_ms = lap();
    }
    const Shader shader(ctx, shadows ? &*shadows : nullptr);
    shade_pass(ctx, shader, buf, res.image);
    throw_if_canceled(options);
    st.shade_ms = lap();
    // Which neighbours differ: from the hits and normals, which the two passes
    // below leave as they are (anti-aliasing changes colours only).
    std::vector<uint8_t> diff;
    if (options.antialias > 0 || (options.edges && options.edge_width > 0))
        diff = neighbour_differences(ctx, buf, res.image);
    antialias_pass(ctx, solver, shader, buf, diff, res.image, st);
    st.antialias_ms = lap();
    edges_pass(ctx, diff, res.image);
    st.edges_ms = lap();

    if (shadows) {
        st.shadow_rays = shadows->rays();  // the pixel centres' and the anti-aliasing samples'
        // The ground's shadowed pixels are background in the AOVs (face 0).
        for (size_t k = 0; k < res.image.shadow.size(); ++k)
            if (res.image.shadow[k]) ++(res.image.face[k] ? st.shadowed_pixels : st.ground_shadowed_pixels);
    }
    frame_statistics(ctx, buf, res.image, solver.params.max_iterations, st);
    st.section_planes = static_cast<int>(options.sections.planes.size());
    st.open_bodies_cut = open_bodies_cut(scene, options.sections, options.face_offsets);
    st.ground = options.ground;
    st.hidden_faces = static_cast<uint64_t>(std::count(options.hidden_faces.begin(), options.hidden_faces.end(), 1));
    for (const std::optional<Color>& c : options.face_colors) st.recoloured_faces += c.has_value();
    for (const Vec3& t : options.face_offsets) st.moved_faces += t.x != 0 || t.y != 0 || t.z != 0;
    st.map_triangles = prepared.map_mesh().triangles();
    throw_if_canceled(options);
    progress.finish();
    st.statistics_ms = lap();
    st.total_ms = std::chrono::duration<double, std::milli>(last - t_total).count();
    check_image_contract(res.image, st.shadows);
    return res;
}

bool any_set(const std::vector<uint8_t>& v) { return std::find(v.begin(), v.end(), 1) != v.end(); }

}  // namespace

RenderResult render(const PreparedScene& prepared, const Camera& camera, const RenderOptions& options) {
    if (!any_set(options.ghost_faces)) return render_frame(prepared, camera, options);
    NURBSRT_CHECK(options.ghost_faces.size() == prepared.scene().faces.size());
    RenderResult front = render_frame(prepared, camera, options);
    // Behind the ghosts: the same frame with every ghost face left out too.
    RenderOptions behind_options = options;
    behind_options.ghost_faces.clear();
    behind_options.hidden_faces.resize(options.ghost_faces.size(), 0);
    for (size_t i = 0; i < options.ghost_faces.size(); ++i) behind_options.hidden_faces[i] |= options.ghost_faces[i];
    const RenderResult behind = render_frame(prepared, camera, behind_options);
    RenderImage& im = front.image;
    const float a = std::clamp(options.ghost_opacity, 0.0f, 1.0f);
    uint64_t ghost_pixels = 0;
    for (size_t k = 0; k < im.face.size(); ++k) {
        const uint32_t f = im.face[k];
        if (f < 1 || f > options.ghost_faces.size() || !options.ghost_faces[f - 1]) continue;
        ++ghost_pixels;
        // "over" with the ghost in front (Porter & Duff 1984), straight alpha in and out.
        float* px = &im.rgba[4 * k];
        const float* b = &behind.image.rgba[4 * k];
        const float alpha = a + (1 - a) * b[3];
        for (int c = 0; c < 3; ++c) px[c] = alpha > 0 ? (a * px[c] + (1 - a) * b[3] * b[c]) / alpha : 0.0f;
        px[3] = alpha;
    }
    RenderStats& st = front.stats;
    // The stages of both frames, so that they still sum to total_ms.
    const RenderStats& bs = behind.stats;
    for (double RenderStats::*stage :
         {&RenderStats::setup_ms, &RenderStats::preliminary_map_ms, &RenderStats::newton_ms,
          &RenderStats::shadow_map_ms, &RenderStats::shade_ms, &RenderStats::antialias_ms, &RenderStats::edges_ms,
          &RenderStats::statistics_ms, &RenderStats::newton_primary_ms})
        st.*stage += bs.*stage;
    st.ghost_faces = static_cast<uint64_t>(std::count(options.ghost_faces.begin(), options.ghost_faces.end(), 1));
    st.ghost_pixels = ghost_pixels;
    st.ghost_behind_ms = behind.stats.total_ms;
    st.total_ms += behind.stats.total_ms;
    return front;
}

}  // namespace nurbsrt
