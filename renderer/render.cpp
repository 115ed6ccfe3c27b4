// Frame rendering: map, Newton, trim, rescue, shading, statistics (see render.h).
#include "renderer/render.h"

#include <OpenImageIO/imageio.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cmath>
#include <limits>
#include <thread>

#include "renderer/error.h"
#include "renderer/nurbs.h"
#include "renderer/trim.h"

namespace nurbsrt {

namespace {

using Clock = std::chrono::steady_clock;
double ms_since(Clock::time_point t0) {
    return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

// Everything a pixel solve needs of one face, prepared once per frame.
struct FaceFrame {
    NurbsSurface projected;  // proposed: the paper's projection to R^2 (camera.h)
    TrimTester trim;
    UvBox box;
};

// Per-pixel solve result of a pass.
struct PixelHit {
    uint32_t face = 0;       // 0: no hit
    float u = 0, v = 0;
    double t = std::numeric_limits<double>::infinity();
    uint8_t iterations = 0;
};

enum Outcome : uint8_t { kNone, kConverged, kDiverged, kSingular, kMaxIter, kLeftDomain, kBehind, kTrimmed };

struct Solver {
    const Scene& scene;
    const Camera& camera;
    const std::vector<FaceFrame>& frames;
    const RenderOptions& opt;
    NewtonParams params;

    // One Newton solve of face id at pixel (i, j) from (u0, v0); hit if converged and inside the trim.
    Outcome solve(uint32_t id, int i, int j, double u0, double v0, PixelHit& hit) const {
        const FaceFrame& ff = frames[id - 1];
        const NewtonResult r =
            opt.method == NewtonMethod::proposed
                ? newton_proposed(ff.projected, camera, camera.pixel_screen(i, j), u0, v0, ff.box, params)
                : newton_martin(scene.faces[id - 1].surface, camera.pixel_ray(i, j), u0, v0, ff.box, params);
        hit.iterations = static_cast<uint8_t>(std::min(r.iterations, 255));
        switch (r.status) {
            case NewtonStatus::converged: break;
            case NewtonStatus::diverged: return kDiverged;
            case NewtonStatus::singular: return kSingular;
            case NewtonStatus::max_iterations: return kMaxIter;
            case NewtonStatus::left_domain: return kLeftDomain;
            case NewtonStatus::behind_eye: return kBehind;
        }
        if (!ff.trim.inside({r.u, r.v})) return kTrimmed;
        hit.face = id;
        hit.u = static_cast<float>(r.u);
        hit.v = static_cast<float>(r.v);
        hit.t = r.t;
        return kConverged;
    }
};

template <class F>
void parallel_rows(int height, tbb::task_arena& arena, F&& fn) {
    arena.execute([&] {
        tbb::parallel_for(tbb::blocked_range<int>(0, height, 4), [&](const tbb::blocked_range<int>& r) {
            for (int j = r.begin(); j < r.end(); ++j) fn(j);
        });
    });
}

}  // namespace

RenderResult render(const Scene& scene, const Camera& camera, const RenderOptions& options) {
    const auto t_total = Clock::now();
    const int W = camera.width(), H = camera.height();
    const size_t npx = static_cast<size_t>(W) * H;
    for (size_t k = 0; k < scene.faces.size(); ++k)
        if (scene.faces[k].index != k + 1)
            throw Error(ErrorCode::invalid_argument, "scene: faces[i].index must be i + 1");
    const int threads = options.threads > 0 ? options.threads
                                            : static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
    tbb::task_arena arena(threads);

    RenderResult res;
    RenderStats& st = res.stats;
    st.method = newton_method_name(options.method);
    st.width = W;
    st.height = H;
    st.threads = threads;
    st.faces = st.patches = scene.faces.size();

    // 1-2. Preliminary map (PAPER.md eq. 4).
    auto t0 = Clock::now();
    const PreliminaryMap map = render_preliminary_map(scene, camera, options.map_precision);
    st.preliminary_map_ms = ms_since(t0);

    // 3-4. Newton per pixel from the map's start, trim test, then rescue.
    t0 = Clock::now();
    std::vector<FaceFrame> frames(scene.faces.size());
    arena.execute([&] {
        tbb::parallel_for(size_t(0), scene.faces.size(), [&](size_t k) {
            const Face& f = scene.faces[k];
            if (options.method == NewtonMethod::proposed) frames[k].projected = project_surface(camera, f.surface);
            frames[k].trim = TrimTester(f.loops);
            frames[k].box = {f.u_min, f.u_max, f.v_min, f.v_max};
        });
    });
    Solver solver{scene, camera, frames, options, options.newton};
    if (!(solver.params.eps > 0)) solver.params.eps = default_newton_eps(scene.bbox);

    std::vector<PixelHit> first(npx);
    std::vector<uint8_t> outcome(npx, kNone);
    parallel_rows(H, arena, [&](int j) {
        for (int i = 0; i < W; ++i) {
            const size_t k = map.index(i, j);
            const uint32_t id = map.face[k];
            if (id == 0 || id > scene.faces.size()) continue;
            outcome[k] = solver.solve(id, i, j, map.u[k], map.v[k], first[k]);
        }
    });

    // Rescue: a pixel without a hit tries the faces of its 8 neighbours (map faces
    // and first-pass hits), started from the neighbour's (u, v); the nearest hit
    // wins. Reads only first-pass data, so the result is thread-count independent.
    std::vector<PixelHit> final_hits = first;
    std::vector<uint8_t> rescued(npx, 0);
    if (options.rescue) {
        parallel_rows(H, arena, [&](int j) {
            for (int i = 0; i < W; ++i) {
                const size_t k = map.index(i, j);
                if (first[k].face) continue;
                PixelHit best;
                uint32_t tried[18];
                int ntried = 0;
                if (map.face[k]) tried[ntried++] = map.face[k];  // already solved in pass 1
                for (int dj = -1; dj <= 1; ++dj)
                    for (int di = -1; di <= 1; ++di) {
                        const int ni = i + di, nj = j + dj;
                        if ((di == 0 && dj == 0) || ni < 0 || nj < 0 || ni >= W || nj >= H) continue;
                        const size_t n = map.index(ni, nj);
                        // Candidates: the neighbour's hit (its converged uv), then its map face (map uv).
                        const PixelHit& nh = first[n];
                        const std::pair<uint32_t, std::pair<float, float>> cands[2] = {
                            {nh.face, {nh.u, nh.v}}, {map.face[n], {map.u[n], map.v[n]}}};
                        for (const auto& [id, uv] : cands) {
                            if (id == 0 || id > scene.faces.size()) continue;
                            if (std::find(tried, tried + ntried, id) != tried + ntried) continue;
                            tried[ntried++] = id;
                            PixelHit h;
                            if (solver.solve(id, i, j, uv.first, uv.second, h) == kConverged && h.t < best.t) best = h;
                        }
                    }
                if (best.face) {
                    final_hits[k] = best;
                    rescued[k] = 1;
                }
            }
        });
    }
    st.newton_ms = ms_since(t0);

    // 5. Shading from the exact normal; AOVs.
    t0 = Clock::now();
    RenderImage& img = res.image;
    img.width = W;
    img.height = H;
    img.rgba.assign(4 * npx, 0.0f);
    img.z.assign(npx, std::numeric_limits<float>::infinity());
    img.face.assign(npx, 0);
    img.u.assign(npx, 0.0f);
    img.v.assign(npx, 0.0f);
    img.iterations.assign(npx, 0);
    // Key light from the upper left behind the viewer, plus a headlight along the ray.
    const Vec3 key = normalize(-1.0 * camera.forward() + 0.6 * camera.up() - 0.5 * camera.right());
    parallel_rows(H, arena, [&](int j) {
        for (int i = 0; i < W; ++i) {
            const size_t k = map.index(i, j);
            const PixelHit& h = final_hits[k];
            float* px = &img.rgba[4 * k];
            img.iterations[k] = h.iterations;
            if (!h.face) {
                px[0] = options.background.r;
                px[1] = options.background.g;
                px[2] = options.background.b;
                px[3] = 0.0f;
                continue;
            }
            const Face& f = scene.faces[h.face - 1];
            const Vec3 dir = camera.pixel_ray(i, j).dir;
            Vec3 n = surface_normal(f.surface, h.u, h.v, f.reversed);
            if (dot(n, dir) > 0) n = -n;  // two-sided: light the side facing the viewer
            Color c = f.color;
            if (!f.has_color && f.body < scene.bodies.size() && scene.bodies[f.body].has_color)
                c = scene.bodies[f.body].color;
            const double lambert = 0.15 + 0.55 * std::max(0.0, dot(n, key)) + 0.35 * std::max(0.0, -dot(n, dir));
            px[0] = static_cast<float>(c.r * lambert);
            px[1] = static_cast<float>(c.g * lambert);
            px[2] = static_cast<float>(c.b * lambert);
            px[3] = 1.0f;
            img.z[k] = static_cast<float>(h.t);
            img.face[k] = h.face;
            img.u[k] = h.u;
            img.v[k] = h.v;
        }
    });
    st.shade_ms = ms_since(t0);

    // Statistics (DESIGN.md): primary solves and their outcome, rescue, hits.
    st.iteration_histogram.assign(static_cast<size_t>(solver.params.max_iterations) + 1, 0);
    uint64_t solves = 0, its = 0;
    for (size_t k = 0; k < npx; ++k) {
        if (final_hits[k].face) ++st.pixels_hit;
        st.fallback += rescued[k];
        if (outcome[k] == kNone) continue;
        ++solves;
        its += first[k].iterations;
        const size_t b = std::min<size_t>(first[k].iterations, st.iteration_histogram.size() - 1);
        ++st.iteration_histogram[b];
        switch (outcome[k]) {
            case kConverged: ++st.converged; break;
            case kDiverged: ++st.diverged; break;
            case kSingular: ++st.singular; break;
            case kMaxIter: ++st.max_iterations; break;
            case kLeftDomain: ++st.left_domain; break;
            case kBehind: ++st.behind_eye; break;
            case kTrimmed: ++st.trimmed; break;
            default: break;
        }
    }
    st.mean_iterations = solves ? double(its) / solves : 0.0;
    st.map_triangles = 0;
    for (const Face& f : scene.faces) st.map_triangles += f.mesh.triangles.size() / 3;
    st.total_ms = ms_since(t_total);
    return res;
}

void write_image(const RenderImage& img, const std::string& path) {
    using namespace OIIO;
    const size_t dot_pos = path.rfind('.');
    std::string ext = dot_pos == std::string::npos ? "" : path.substr(dot_pos + 1);
    for (char& ch : ext) ch = static_cast<char>(std::tolower(static_cast<unsigned char>(ch)));
    auto out = ImageOutput::create(path);
    if (!out) throw Error(ErrorCode::unsupported_format, "cannot write image format of '" + path + "'");
    const size_t npx = static_cast<size_t>(img.width) * img.height;
    if (ext == "exr") {
        ImageSpec spec(img.width, img.height, 6, TypeDesc::FLOAT);
        spec.channelnames = {"R", "G", "B", "A", "Z", "face"};
        spec.channelformats = {TypeDesc::FLOAT, TypeDesc::FLOAT, TypeDesc::FLOAT, TypeDesc::FLOAT, TypeDesc::FLOAT,
                               TypeDesc::UINT32};
        spec.alpha_channel = 3;
        spec.z_channel = 4;
        struct Px {
            float r, g, b, a, z;
            uint32_t face;
        };
        static_assert(sizeof(Px) == 24);
        std::vector<Px> buf(npx);
        for (size_t k = 0; k < npx; ++k)
            buf[k] = {img.rgba[4 * k], img.rgba[4 * k + 1], img.rgba[4 * k + 2], img.rgba[4 * k + 3], img.z[k], img.face[k]};
        if (!out->open(path, spec) || !out->write_image(TypeDesc::UNKNOWN, buf.data()) || !out->close())
            throw Error(ErrorCode::io, "cannot write '" + path + "': " + out->geterror());
        return;
    }
    const int nch = ext == "jpg" || ext == "jpeg" ? 3 : 4;
    ImageSpec spec(img.width, img.height, nch, TypeDesc::UINT8);
    std::vector<uint8_t> buf(npx * nch);
    for (size_t k = 0; k < npx; ++k)
        for (int c = 0; c < nch; ++c) {
            const float x = std::clamp(img.rgba[4 * k + c], 0.0f, 1.0f);
            const float g = c == 3 ? x : std::pow(x, 1.0f / 2.2f);  // gamma for display formats
            buf[k * nch + c] = static_cast<uint8_t>(std::lround(g * 255.0f));
        }
    if (!out->open(path, spec) || !out->write_image(TypeDesc::UINT8, buf.data()) || !out->close())
        throw Error(ErrorCode::io, "cannot write '" + path + "': " + out->geterror());
}

}  // namespace nurbsrt
