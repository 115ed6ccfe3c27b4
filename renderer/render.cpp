// Frame rendering: camera set-up, the preliminary map, then the passes of passes.h
// in order, with the stage timings (see render.h); image output.
#include "renderer/render.h"

#include <OpenImageIO/imageio.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cmath>
#include <optional>
#include <thread>

#include "renderer/error.h"
#include "renderer/frame.h"
#include "renderer/mesh_screen_points.h"
#include "renderer/nurbs.h"
#include "renderer/passes.h"
#include "renderer/pixel_solver.h"
#include "renderer/shadow_rays.h"

namespace nurbsrt {

namespace {

using Clock = std::chrono::steady_clock;
double ms_since(Clock::time_point t0) {
    return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

// The rescue's solves may take more steps than the primary ones: they start
// farther from the root (a neighbour's (u, v), a mesh vertex) and backtrack.
constexpr int kRescueMinIterations = 16;

tbb::task_arena::priority arena_priority(RenderPriority p) {
    switch (p) {
        case RenderPriority::low: return tbb::task_arena::priority::low;
        case RenderPriority::high: return tbb::task_arena::priority::high;
        case RenderPriority::normal: break;
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

RenderResult render(const PreparedScene& prepared, const Camera& camera, const RenderOptions& options) {
    const auto t_total = Clock::now();
    const Scene& scene = prepared.scene();
    const int W = camera.width(), H = camera.height();
    const int threads = options.threads > 0 ? options.threads
                                            : static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
    tbb::task_arena arena(threads, 1, arena_priority(options.priority));

    RenderResult res;
    RenderStats& st = res.stats;
    st.method = newton_method_name(options.method);
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
    const PreliminaryMap map = render_preliminary_map(prepared, camera, options.map_precision);
    throw_if_canceled(options);
    st.preliminary_map_ms = lap();

    // 3-4. Newton per pixel from the map's start, trim test, then rescue.
    // Progress units: rows of the per-pixel passes (Newton, rescue, shading, and
    // anti-aliasing when asked for).
    Progress progress(options.progress, (options.antialias > 0 ? 4 : 3) * static_cast<int64_t>(H));
    const FrameContext ctx{prepared, scene, camera, map, options, arena, progress, W, H,
                           static_cast<uint32_t>(scene.faces.size())};
    FrameBuffers buf(ctx.pixels());
    st.setup_ms += lap();
    // The per-face set-up that depends on the camera: proposed's projection of
    // the control points (the rest was done once by prepare()).
    std::vector<NurbsSurface> projected(options.method == NewtonMethod::proposed ? scene.faces.size() : 0);
    arena.execute([&] {
        tbb::parallel_for(size_t(0), projected.size(),
                          [&](size_t k) { projected[k] = project_surface(camera, scene.faces[k].surface); });
    });
    Solver solver{ctx, projected, options.newton, {}};
    if (!(solver.params.eps > 0)) solver.params.eps = default_newton_eps(scene.bbox);
    st.tolerance = solver.params.eps;
    // Rescue solves: clamp-and-continue at face borders, backtracking, a few more steps.
    solver.robust = solver.params;
    solver.robust.robust = true;
    solver.robust.max_iterations = std::max(solver.robust.max_iterations, kRescueMinIterations);

    primary_pass(ctx, solver, buf);
    st.newton_primary_ms = ms_since(last);  // a part of newton_ms, not a stage of its own

    buf.hits = buf.first;
    if (options.rescue) {
        const MeshScreenPoints screen_points(ctx);
        rescue_pass(ctx, solver, screen_points, buf);
        st.rescue_nearer += nearer_sheet_pass(ctx, solver, screen_points, buf);
    } else {
        progress.add(H);
    }
    st.newton_ms = lap();

    // 5. Shading from the exact normal, with the key light's exact shadows
    // when asked for (their map drawn first); AOVs.
    std::optional<KeyLightShadows> shadows;
    st.shadows = options.shadows;
    if (options.shadows) {
        throw_if_canceled(options);
        shadows.emplace(ctx, solver, light_rig(camera).key);
        st.shadow_map_size = shadows->map_size();
        st.shadow_map_ms = lap();
    }
    const Shader shader(ctx, shadows ? &*shadows : nullptr);
    shade_pass(ctx, shader, buf, res.image);
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
        st.shadowed_pixels = static_cast<uint64_t>(std::count(res.image.shadow.begin(), res.image.shadow.end(), 1));
    }
    frame_statistics(ctx, buf, res.image, solver.params.max_iterations, st);
    st.map_triangles = prepared.map_mesh().triangles();
    throw_if_canceled(options);
    progress.finish();
    st.statistics_ms = lap();
    st.total_ms = std::chrono::duration<double, std::milli>(last - t_total).count();
    return res;
}

namespace {

// The 8-bit sRGB code (IEC 61966-2-1 transfer function) of a linear value in
// [0, 1], without a pow per channel (which took ~70 ms of an 800x600 PNG's
// encoding): code c is chosen when x lies at or above the linear value whose
// encoding is exactly halfway between codes c-1 and c, i.e. the result is
// round(255 encode(x)). A 4096-bin table gives the code at each bin's start; a
// bin spans less than one code (the steepest slope, 12.92 x 255 codes per unit
// near black, is 0.8 codes per bin), so at most one boundary needs checking.
class Srgb8 {
public:
    Srgb8() {
        auto decode = [](double y) { return y <= 0.04045 ? y / 12.92 : std::pow((y + 0.055) / 1.055, 2.4); };
        for (int c = 1; c < 256; ++c) bound_[c] = static_cast<float>(decode((c - 0.5) / 255.0));
        bound_[0] = 0.0f;
        bound_[256] = 2.0f;  // above every clamped input
        int c = 0;
        for (int b = 0; b < kBins; ++b) {
            const float x = static_cast<float>(b) / kBins;
            while (bound_[c + 1] <= x) ++c;
            bin_[b] = static_cast<uint8_t>(c);
        }
    }
    uint8_t operator()(float x) const {
        x = std::clamp(x, 0.0f, 1.0f);  // NaN stays NaN here and gives 0 below
        if (!(x > 0.0f)) return 0;
        int c = bin_[std::min(static_cast<int>(x * kBins), kBins - 1)];
        if (bound_[c + 1] <= x) ++c;
        return static_cast<uint8_t>(c);
    }

private:
    static constexpr int kBins = 4096;
    float bound_[257];
    uint8_t bin_[kBins];
};

// PNG rows unfiltered: the renders are flat background and smooth shading, where
// zlib alone compresses better than after libpng's adaptive filters, and in half
// the time (800x600 renders of three models: 21-69 KB instead of 25-69 KB,
// 49-130 ms instead of 103-225 ms, at zlib's default level 6).
constexpr int kPngFilterNone = 8;  // libpng's PNG_FILTER_NONE

}  // namespace

void write_image(const RenderImage& img, const std::string& path) {
    using namespace OIIO;
    const size_t dot_pos = path.rfind('.');
    std::string ext = dot_pos == std::string::npos ? "" : path.substr(dot_pos + 1);
    for (char& ch : ext) ch = static_cast<char>(std::tolower(static_cast<unsigned char>(ch)));
    auto out = ImageOutput::create(path);
    if (!out) throw Error(ErrorCode::unsupported_format, "cannot write image format of '" + path + "'");
    const size_t npx = static_cast<size_t>(img.width) * img.height;
    if (ext == "exr") {
        ImageSpec spec(img.width, img.height, 12, TypeDesc::FLOAT);
        spec.channelnames = {"R", "G", "B", "A", "Z", "face", "N.X", "N.Y", "N.Z", "u", "v", "iterations"};
        spec.channelformats = {TypeDesc::FLOAT, TypeDesc::FLOAT, TypeDesc::FLOAT, TypeDesc::FLOAT,
                               TypeDesc::FLOAT, TypeDesc::UINT32, TypeDesc::FLOAT, TypeDesc::FLOAT,
                               TypeDesc::FLOAT, TypeDesc::FLOAT, TypeDesc::FLOAT, TypeDesc::UINT32};
        spec.alpha_channel = 3;
        spec.z_channel = 4;
        struct Px {
            float r, g, b, a, z;
            uint32_t face;
            float nx, ny, nz, u, v;
            uint32_t iterations;
        };
        static_assert(sizeof(Px) == 48);
        const bool has_n = img.normal.size() == 3 * npx, has_uv = img.u.size() == npx && img.v.size() == npx;
        const bool has_it = img.iterations.size() == npx;
        std::vector<Px> buf(npx);
        for (size_t k = 0; k < npx; ++k)
            buf[k] = {img.rgba[4 * k], img.rgba[4 * k + 1], img.rgba[4 * k + 2], img.rgba[4 * k + 3], img.z[k], img.face[k],
                      has_n ? img.normal[3 * k] : 0.0f, has_n ? img.normal[3 * k + 1] : 0.0f,
                      has_n ? img.normal[3 * k + 2] : 0.0f, has_uv ? img.u[k] : 0.0f, has_uv ? img.v[k] : 0.0f,
                      has_it ? img.iterations[k] : 0u};
        if (!out->open(path, spec) || !out->write_image(TypeDesc::UNKNOWN, buf.data()) || !out->close())
            throw Error(ErrorCode::io, "cannot write '" + path + "': " + out->geterror());
        return;
    }
    const int nch = ext == "jpg" || ext == "jpeg" ? 3 : 4;
    ImageSpec spec(img.width, img.height, nch, TypeDesc::UINT8);
    if (ext == "png") spec.attribute("png:filter", kPngFilterNone);
    // The colour of a pixel is independent of its alpha (a background r,g,b,a is
    // that colour at that opacity), PNG's and TIFF's own convention: without this
    // OpenImageIO takes the data as premultiplied and divides the colour by alpha
    // (a 50 % grey background at alpha 0.5 came out white).
    if (nch == 4) spec.attribute("oiio:UnassociatedAlpha", 1);
    static const Srgb8 srgb8;
    std::vector<uint8_t> buf(npx * nch);
    for (size_t k = 0; k < npx; ++k)
        for (int c = 0; c < nch; ++c) {
            const float x = img.rgba[4 * k + c];
            // Display formats are sRGB; alpha stays linear.
            buf[k * nch + c] = c == 3 ? static_cast<uint8_t>(std::lround(std::clamp(x, 0.0f, 1.0f) * 255.0f)) : srgb8(x);
        }
    if (!out->open(path, spec) || !out->write_image(TypeDesc::UINT8, buf.data()) || !out->close())
        throw Error(ErrorCode::io, "cannot write '" + path + "': " + out->geterror());
}

}  // namespace nurbsrt
