// Frame rendering: map, Newton, trim, rescue, shading, statistics (see render.h).
#include "renderer/render.h"

#include <OpenImageIO/imageio.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <atomic>
#include <cctype>
#include <chrono>
#include <cmath>
#include <limits>
#include <mutex>
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

// Per-pixel solve result of a pass.
struct PixelHit {
    uint32_t face = 0;       // 0: no hit
    float u = 0, v = 0;
    // Unit shading normal (oriented by the face) from the solve's last partials;
    // (0, 0, 0) where they were degenerate: shading then takes surface_normal's limits.
    float nx = 0, ny = 0, nz = 0;
    double t = std::numeric_limits<double>::infinity();
    uint8_t iterations = 0;
};

// Fills a hit of face `id` at (u, v), distance t, normal from the partials there.
void set_hit(const Face& f, uint32_t id, double u, double v, double t, Vec3 Cu, Vec3 Cv, PixelHit& hit) {
    hit.face = id;
    hit.u = static_cast<float>(u);
    hit.v = static_cast<float>(v);
    hit.t = t;
    Vec3 n;
    if (!normal_from_partials(f.surface, Cu, Cv, f.reversed, n)) n = {0, 0, 0};
    hit.nx = static_cast<float>(n.x);
    hit.ny = static_cast<float>(n.y);
    hit.nz = static_cast<float>(n.z);
}

enum Outcome : uint8_t { kNone, kConverged, kDiverged, kSingular, kMaxIter, kLeftDomain, kBehind, kTrimmed, kNearTrim };

struct Solver {
    const Scene& scene;
    const Camera& camera;
    const std::vector<PreparedFace>& faces;      // camera-independent (prepare())
    const std::vector<NurbsSurface>& projected;  // proposed: the paper's projection to R^2, per frame
    const RenderOptions& opt;
    NewtonParams params;

    // One Newton solve of face id at pixel (i, j) from (u0, v0); hit if converged and
    // inside the trim. With `near`, a hit converged outside the trim but within the
    // face's trim-tolerance band is also returned (as kNearTrim): the sampled loops of
    // two faces sharing an edge are each only within that tolerance of the true edge,
    // so a ray through the sliver between the two polylines is rejected by both (a crack).
    Outcome solve(uint32_t id, int i, int j, double u0, double v0, const NewtonParams& p, bool near,
                  PixelHit& hit) const {
        const PreparedFace& ff = faces[id - 1];
        const NewtonResult r =
            opt.method == NewtonMethod::proposed
                ? newton_proposed(projected[id - 1], camera, camera.pixel_screen(i, j), u0, v0, ff.box, p)
                : newton_martin(scene.faces[id - 1].surface, camera.pixel_ray(i, j), u0, v0, ff.box, p);
        hit.iterations = static_cast<uint8_t>(std::min(r.iterations, 255));
        if (near && r.status != NewtonStatus::converged && r.status != NewtonStatus::behind_eye &&
            border_gap_hit(id, i, j, r, hit))
            return kNearTrim;
        switch (r.status) {
            case NewtonStatus::converged: break;
            case NewtonStatus::diverged: return kDiverged;
            case NewtonStatus::singular: return kSingular;
            case NewtonStatus::max_iterations: return kMaxIter;
            case NewtonStatus::left_domain: return kLeftDomain;
            case NewtonStatus::behind_eye: return kBehind;
        }
        Outcome o = kConverged;
        if (!ff.trim.inside({r.u, r.v})) {
            if (!near || !(ff.trim.boundary_distance({r.u, r.v}, ff.near_uv) <= ff.near_uv)) return kTrimmed;
            o = kNearTrim;
        }
        set_hit(scene.faces[id - 1], id, r.u, r.v, r.t, r.Cu, r.Cv, hit);
        return o;
    }
    // Adjacent faces of a CAD model meet only within their edges' tolerance: a ray
    // through the gap makes Newton stop on the face's parameter-box border, short
    // of the ray (the exact hit lies on the surface's extension). Such a stop counts
    // as a near hit when the border point is within the trim band in (u,v) and
    // within the same band in model units (band x surface speed) of the ray.
    bool border_gap_hit(uint32_t id, int i, int j, const NewtonResult& r, PixelHit& hit) const {
        const PreparedFace& ff = faces[id - 1];
        const UvBox& b = ff.box;
        if (!(r.u == b.u0 || r.u == b.u1 || r.v == b.v0 || r.v == b.v1)) return false;
        if (!ff.trim.inside({r.u, r.v}) && !(ff.trim.boundary_distance({r.u, r.v}, ff.near_uv) <= ff.near_uv))
            return false;
        const CartesianDerivs c = cartesian_d1(scene.faces[id - 1].surface, r.u, r.v);
        const Ray ray = camera.pixel_ray(i, j);
        const Vec3 q = c.P - ray.origin;
        const double t = dot(q, ray.dir);
        const double gap = length(q - t * ray.dir);
        const double band = ff.near_uv * std::max(length(c.Pu), length(c.Pv));
        if (!(t > 0) || !(gap <= band)) return false;
        set_hit(scene.faces[id - 1], id, r.u, r.v, t, c.Pu, c.Pv, hit);
        return true;
    }
    Outcome solve(uint32_t id, int i, int j, double u0, double v0, PixelHit& hit) const {
        return solve(id, i, j, u0, v0, params, false, hit);
    }
};

// Fraction-done reporting for RenderOptions::progress: rows are counted with one
// relaxed atomic add; a thread that crosses the next ~2% mark reports, serialized
// by a mutex it only try-locks (a busy reporter just skips one report).
class Progress {
public:
    Progress(const std::function<void(double)>& fn, int64_t total)
        : fn_(fn), total_(std::max<int64_t>(total, 1)), step_(std::max<int64_t>(total_ / 50, 1)), next_(step_) {}
    void add(int64_t n) {
        if (!fn_) return;
        const int64_t d = done_.fetch_add(n, std::memory_order_relaxed) + n;
        if (d < next_.load(std::memory_order_relaxed)) return;
        std::unique_lock<std::mutex> lock(m_, std::try_to_lock);
        if (!lock.owns_lock()) return;
        const int64_t now = done_.load(std::memory_order_relaxed);
        if (now < next_.load(std::memory_order_relaxed)) return;
        next_.store(now + step_, std::memory_order_relaxed);
        report(std::min(0.999, double(now) / double(total_)));
    }
    void finish() {
        if (!fn_) return;
        std::lock_guard<std::mutex> lock(m_);
        report(1.0);
    }

private:
    void report(double f) {
        if (f <= last_) return;
        last_ = f;
        fn_(f);
    }
    const std::function<void(double)>& fn_;
    const int64_t total_, step_;
    std::atomic<int64_t> done_{0}, next_;
    std::mutex m_;
    double last_ = 0;
};

// RenderOptions::cancel: blocks of rows are skipped once it is set, and the pass
// then ends with Error(canceled) (a partial pass is never used).
bool canceled(const RenderOptions& o) { return o.cancel && o.cancel->load(std::memory_order_relaxed); }
void throw_if_canceled(const RenderOptions& o) {
    if (canceled(o)) throw Error(ErrorCode::canceled, "the render was canceled");
}

template <class F>
void parallel_rows(int height, tbb::task_arena& arena, Progress* progress, const RenderOptions& options, F&& fn) {
    arena.execute([&] {
        tbb::parallel_for(tbb::blocked_range<int>(0, height, 4), [&](const tbb::blocked_range<int>& r) {
            if (canceled(options)) return;
            for (int j = r.begin(); j < r.end(); ++j) fn(j);
            if (progress) progress->add(r.end() - r.begin());
        });
    });
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
    const size_t npx = static_cast<size_t>(W) * H;
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
    throw_if_canceled(options);
    const PreliminaryMap map = render_preliminary_map(prepared, camera, options.map_precision);
    throw_if_canceled(options);
    st.preliminary_map_ms = ms_since(t0);

    // 3-4. Newton per pixel from the map's start, trim test, then rescue.
    // Progress units: rows of the three per-pixel passes (Newton, rescue, shading).
    Progress progress(options.progress, 3 * static_cast<int64_t>(H));
    t0 = Clock::now();
    // The per-face set-up that depends on the camera: proposed's projection of
    // the control points (the rest was done once by prepare()).
    std::vector<NurbsSurface> projected(options.method == NewtonMethod::proposed ? scene.faces.size() : 0);
    arena.execute([&] {
        tbb::parallel_for(size_t(0), projected.size(),
                          [&](size_t k) { projected[k] = project_surface(camera, scene.faces[k].surface); });
    });
    Solver solver{scene, camera, prepared.faces(), projected, options, options.newton};
    if (!(solver.params.eps > 0)) solver.params.eps = default_newton_eps(scene.bbox);
    st.tolerance = solver.params.eps;
    // Rescue solves: clamp-and-continue at face borders, backtracking, a few more steps.
    NewtonParams robust = solver.params;
    robust.robust = true;
    robust.max_iterations = std::max(robust.max_iterations, 16);
    const uint32_t nfaces = static_cast<uint32_t>(scene.faces.size());

    std::vector<PixelHit> first(npx);
    std::vector<uint8_t> outcome(npx, kNone);
    parallel_rows(H, arena, &progress, options, [&](int j) {
        for (int i = 0; i < W; ++i) {
            const size_t k = map.index(i, j);
            const uint32_t id = map.face[k];
            if (id == 0 || id > nfaces) continue;
            outcome[k] = solver.solve(id, i, j, map.u[k], map.v[k], first[k]);
        }
    });
    throw_if_canceled(options);
    st.newton_primary_ms = ms_since(t0);

    // Rescue of pixels without a first-pass hit. Reads only the map and first-pass
    // data, so every pixel's result is independent of the thread count.
    //  A (neighbour / silhouette): the faces of the 8 neighbours, started from their
    //    converged (u, v) (first-pass hits), then from their map (u, v); the pixel's
    //    own map face is retried from the neighbours' converged (u, v). Pixels the
    //    map calls background are tried the same way when they touch a hit: the
    //    exact silhouette is not the mesh's.
    //  B (general): if A found nothing and the pixel should be covered (its map face
    //    failed, or at least two 4-neighbours are hit), every face of the 5x5
    //    neighbourhood from several starts: the converged (u, v) of its pixels, its
    //    map (u, v), and the face's mesh vertex projected nearest to the pixel.
    //  Crack pixels (hit on opposite sides, or on 3 of 4 sides) also accept a hit
    //    just outside a trim loop, within the face's tolerance band (Solver::solve).
    // All rescue solves use the robust Newton (newton.h); the nearest hit wins.
    std::vector<PixelHit> final_hits = first;
    enum : uint8_t { kNoRescue, kRescueNeighbour, kRescueSilhouette, kRescueGeneral, kRescueTrimTol };
    std::vector<uint8_t> rescued(npx, kNoRescue);
    // One pixel's rescue from the hits `src` (and the map); returns its kind, or kNoRescue.
    // Screen positions (sx, sy) of each face's map-mesh vertices for the general
    // fallback's nearest-vertex start, projected once per face and frame on first
    // use instead of once per rescued pixel: the scan is O(vertices) and a face of
    // the ducks has ~4000, which made this search most of the rescue's time
    // (`nurbsrt bench`, docs/BENCHMARKS.md). Same arithmetic as projecting in place
    // (X/D, Y/D of Camera::project_h), so the chosen vertex is unchanged; NaN marks
    // a vertex behind the eye.
    struct MeshScreen {
        std::once_flag once;
        std::vector<Vec2> pts;
    };
    const std::unique_ptr<MeshScreen[]> mesh_screen(new MeshScreen[nfaces]);
    auto mesh_screen_points = [&](uint32_t id) -> const std::vector<Vec2>& {
        MeshScreen& ms = mesh_screen[id - 1];
        std::call_once(ms.once, [&] {
            const FaceMesh& mesh = scene.faces[id - 1].mesh;
            const size_t n = std::min(mesh.xyz.size(), mesh.uv.size());
            ms.pts.resize(n);
            for (size_t m = 0; m < n; ++m) {
                const Vec4 ph = camera.project_h(Vec4{mesh.xyz[m].x, mesh.xyz[m].y, mesh.xyz[m].z, 1.0});
                ms.pts[m] = camera.depth(ph) > 0 ? Vec2{ph.x / ph.z, ph.y / ph.z} : Vec2{NAN, NAN};
            }
        });
        return ms.pts;
    };
    auto rescue_pixel = [&](int i, int j, const std::vector<PixelHit>& src, PixelHit& out) -> uint8_t {
        struct Start {
            uint32_t id;
            float u, v;
        };
        constexpr int kMaxTried = 64;
        Start tried[kMaxTried];
        const size_t k = map.index(i, j);
        auto hit_at = [&](int a, int b) {
            return a >= 0 && b >= 0 && a < W && b < H && src[map.index(a, b)].face != 0;
        };
            const uint32_t id0 = map.face[k] <= nfaces ? map.face[k] : 0;
            bool touches = false;
            for (int dj = -1; dj <= 1 && !touches; ++dj)
                for (int di = -1; di <= 1; ++di)
                    if (hit_at(i + di, j + dj)) touches = true;
            if (!id0 && !touches) return kNoRescue;  // plain background
            const bool l = hit_at(i - 1, j), r = hit_at(i + 1, j), u = hit_at(i, j - 1), d = hit_at(i, j + 1);
            const int n4 = l + r + u + d;
            const bool crack = (l && r) || (u && d) || n4 >= 3;

            PixelHit best, best_near;
            int ntried = 0;
            // The own map start was solved in pass 1 (non-robust): retry it robustly.
            auto attempt = [&](uint32_t id, float su, float sv) {
                if (id == 0 || id > nfaces) return;
                for (int q = 0; q < ntried; ++q)
                    if (tried[q].id == id && tried[q].u == su && tried[q].v == sv) return;
                if (ntried == kMaxTried) return;
                tried[ntried++] = {id, su, sv};
                PixelHit h;
                const Outcome o = solver.solve(id, i, j, su, sv, robust, crack, h);
                if (o == kConverged && h.t < best.t) best = h;
                if (o == kNearTrim && h.t < best_near.t) best_near = h;
            };
            // A: converged neighbours first (their uv is on the exact surface, next to
            // this pixel), one start per face; then the map faces' starts.
            uint32_t faces_a[8];
            int nfa = 0;
            for (int pass = 0; pass < 2; ++pass)
                for (int dj = -1; dj <= 1; ++dj)
                    for (int di = -1; di <= 1; ++di) {
                        const int ni = i + di, nj = j + dj;
                        if ((di == 0 && dj == 0) || ni < 0 || nj < 0 || ni >= W || nj >= H) continue;
                        const size_t n = map.index(ni, nj);
                        const uint32_t id = pass == 0 ? src[n].face : map.face[n];
                        if (id == 0 || std::find(faces_a, faces_a + nfa, id) != faces_a + nfa) continue;
                        faces_a[nfa++] = id;
                        if (pass == 0) attempt(id, src[n].u, src[n].v);
                        else attempt(id, map.u[n], map.v[n]);
                    }
            if (id0) {
                attempt(id0, map.u[k], map.v[k]);
                for (int dj = -1; dj <= 1; ++dj)
                    for (int di = -1; di <= 1; ++di)
                        if (hit_at(i + di, j + dj) && src[map.index(i + di, j + dj)].face == id0) {
                            const PixelHit& nh = src[map.index(i + di, j + dj)];
                            attempt(id0, nh.u, nh.v);
                            di = dj = 2;  // one converged start of the own face is enough
                        }
            }
            uint8_t kind = id0 ? kRescueNeighbour : kRescueSilhouette;
            // B: the general fallback.
            if (!best.face && !best_near.face && (id0 || n4 >= 2)) {
                uint32_t faces_b[24];
                int nfb = 0;
                for (int dj = -2; dj <= 2; ++dj)
                    for (int di = -2; di <= 2; ++di) {
                        const int ni = i + di, nj = j + dj;
                        if (ni < 0 || nj < 0 || ni >= W || nj >= H) continue;
                        const size_t n = map.index(ni, nj);
                        for (const uint32_t id : {src[n].face, map.face[n]})
                            if (id && id <= nfaces && nfb < 24 &&
                                std::find(faces_b, faces_b + nfb, id) == faces_b + nfb)
                                faces_b[nfb++] = id;
                    }
                const ScreenPoint sp = camera.pixel_screen(i, j);
                for (int q = 0; q < nfb; ++q) {
                    const uint32_t id = faces_b[q];
                    for (int dj = -2; dj <= 2; ++dj)
                        for (int di = -2; di <= 2; ++di) {
                            const int ni = i + di, nj = j + dj;
                            if (ni < 0 || nj < 0 || ni >= W || nj >= H) continue;
                            const size_t n = map.index(ni, nj);
                            if (src[n].face == id) attempt(id, src[n].u, src[n].v);
                            if (map.face[n] == id) attempt(id, map.u[n], map.v[n]);
                        }
                    // The face's mesh vertex nearest to the pixel on screen (in front of the eye).
                    const FaceMesh& mesh = scene.faces[id - 1].mesh;
                    const std::vector<Vec2>& pts = mesh_screen_points(id);
                    double bd = HUGE_VAL;
                    size_t bv = mesh.uv.size();
                    for (size_t m = 0; m < pts.size(); ++m) {
                        const double dx = pts[m].x - sp.sx, dy = pts[m].y - sp.sy, dd = dx * dx + dy * dy;
                        if (dd < bd) {  // false for NaN: a vertex behind the eye
                            bd = dd;
                            bv = m;
                        }
                    }
                    if (bv < mesh.uv.size())
                        attempt(id, static_cast<float>(mesh.uv[bv].x), static_cast<float>(mesh.uv[bv].y));
                    const UvBox& bx = prepared.faces()[id - 1].box;  // and the middle of its box
                    attempt(id, static_cast<float>(0.5 * (bx.u0 + bx.u1)), static_cast<float>(0.5 * (bx.v0 + bx.v1)));
                }
                kind = kRescueGeneral;
            }
            // A hit inside a trim beats a near-trim one unless the latter is in front
            // (a crack in a front face must not show the face behind it).
            if (best_near.face && best_near.t < best.t) {
                best = best_near;
                kind = kRescueTrimTol;
            }
            if (!best.face) return kNoRescue;
            out = best;
            return kind;
    };
    if (options.rescue) {
        parallel_rows(H, arena, &progress, options, [&](int j) {
            for (int i = 0; i < W; ++i) {
                const size_t k = map.index(i, j);
                if (!first[k].face) rescued[k] = rescue_pixel(i, j, first, final_hits[k]);
            }
        });
        throw_if_canceled(options);
        // Silhouette growth: where the mesh is coarse, the exact silhouette can lie
        // several pixels outside the map's. Repeat the rescue on the background
        // pixels next to the last pass's new hits until none is added; each pass
        // reads only the previous state, so the result stays thread-independent.
        std::vector<size_t> fresh, cand;
        for (size_t k = 0; k < npx; ++k)
            if (rescued[k]) fresh.push_back(k);
        std::vector<uint8_t> queued(npx, 0);
        for (int pass = 0; pass < 64 && !fresh.empty(); ++pass) {
            throw_if_canceled(options);
            cand.clear();
            for (const size_t k : fresh) {
                const int i = static_cast<int>(k % W), j = static_cast<int>(k / W);
                for (int dj = -1; dj <= 1; ++dj)
                    for (int di = -1; di <= 1; ++di) {
                        const int ni = i + di, nj = j + dj;
                        if (ni < 0 || nj < 0 || ni >= W || nj >= H) continue;
                        const size_t n = map.index(ni, nj);
                        if (!final_hits[n].face && !queued[n]) {
                            queued[n] = 1;
                            cand.push_back(n);
                        }
                    }
            }
            std::sort(cand.begin(), cand.end());
            std::vector<PixelHit> got(cand.size());
            std::vector<uint8_t> kinds(cand.size(), kNoRescue);
            arena.execute([&] {
                tbb::parallel_for(size_t(0), cand.size(), [&](size_t q) {
                    const size_t k = cand[q];
                    // final_hits is only written after this loop: every pixel reads the previous pass.
                    kinds[q] = rescue_pixel(static_cast<int>(k % W), static_cast<int>(k / W), final_hits, got[q]);
                });
            });
            fresh.clear();
            for (size_t q = 0; q < cand.size(); ++q) {
                queued[cand[q]] = 0;
                if (!kinds[q]) continue;
                final_hits[cand[q]] = got[q];
                rescued[cand[q]] = kinds[q];
                fresh.push_back(cand[q]);
            }
        }
        throw_if_canceled(options);

        // Nearer sheet: where a surface folds over itself (or two faces lie closer
        // than the map mesh's deflection), the map can hand a pixel the farther of two
        // sheets, and Newton converges there; it shows as an isolated depth spike: a
        // hit deeper than the mean of both neighbours of a horizontal or vertical pair
        // by more than kSpike. Such pixels are solved again from those neighbours'
        // faces and (u, v); a hit on the pixel's own ray that is nearer by more than
        // kNearer (far above the Newton tolerance, so the same root never counts)
        // replaces it: the nearest intersection is the visible one. Reads only the
        // hits so far, so the result stays independent of the thread count.
        const double diag = std::max(scene.bbox.diagonal(), 1e-300);
        const double kSpike = 1e-5 * diag, kNearer = 1e-6 * diag;
        // A run of several pixels on the far sheet is peeled from its ends, one pixel
        // per pass: after the first pass (every pixel), only the 4-neighbours of the
        // pixels the last pass changed are examined again.
        auto nearer_hit = [&](int i, int j, PixelHit& out) {
            const PixelHit& p = final_hits[map.index(i, j)];
            if (!p.face) return false;
            PixelHit best = p;
            const int pairs[2][4] = {{i - 1, j, i + 1, j}, {i, j - 1, i, j + 1}};
            for (const auto& q : pairs) {
                if (q[0] < 0 || q[1] < 0 || q[2] >= W || q[3] >= H) continue;
                const PixelHit& a = final_hits[map.index(q[0], q[1])];
                const PixelHit& b = final_hits[map.index(q[2], q[3])];
                if (!a.face || !b.face || !(p.t > 0.5 * (a.t + b.t) + kSpike)) continue;
                // Only from a neighbour on another face, or on another sheet of the same
                // face: its (u, v) jumps (3x farther from the pixel's than the opposite
                // neighbour's). A smoothly curved concave sheet, where depth also rises
                // above the pair's mean, changes (u, v) evenly and is not solved again.
                auto uv_dist2 = [&](const PixelHit& x) {
                    const double du = double(x.u) - p.u, dv = double(x.v) - p.v;
                    return du * du + dv * dv;
                };
                for (const PixelHit* n : {&a, &b}) {
                    const PixelHit& other = n == &a ? b : a;
                    const bool jump = n->face != p.face || other.face != p.face || uv_dist2(*n) > 9.0 * uv_dist2(other);
                    PixelHit h;
                    if (jump && n->t < p.t - kNearer &&
                        solver.solve(n->face, i, j, n->u, n->v, solver.params, false, h) == kConverged &&
                        h.t < best.t - kNearer)
                        best = h;
                }
            }
            if (best.face == p.face && best.t == p.t) return false;
            out = best;
            return true;
        };
        // Replacements are collected per row (almost always none) and applied
        // between passes, so no frame-sized buffer is needed for a handful of pixels.
        struct Update {
            size_t k;
            PixelHit hit;
        };
        std::vector<std::vector<Update>> row_updates(H);
        parallel_rows(H, arena, nullptr, options, [&](int j) {
            for (int i = 0; i < W; ++i) {
                PixelHit h;
                if (nearer_hit(i, j, h)) row_updates[j].push_back({map.index(i, j), h});
            }
        });
        std::vector<Update> updates;
        for (const std::vector<Update>& r : row_updates) updates.insert(updates.end(), r.begin(), r.end());
        std::vector<size_t> cand_near;
        std::vector<PixelHit> cand_hit;
        std::vector<uint8_t> cand_changed;
        for (int pass = 0; pass < 32 && !updates.empty(); ++pass) {
            throw_if_canceled(options);
            cand_near.clear();
            for (const Update& u : updates) {
                final_hits[u.k] = u.hit;
                const int i = static_cast<int>(u.k % W), j = static_cast<int>(u.k / W);
                const int nb[4][2] = {{i - 1, j}, {i + 1, j}, {i, j - 1}, {i, j + 1}};
                for (const auto& q : nb)
                    if (q[0] >= 0 && q[1] >= 0 && q[0] < W && q[1] < H) cand_near.push_back(map.index(q[0], q[1]));
            }
            st.rescue_nearer += updates.size();
            std::sort(cand_near.begin(), cand_near.end());
            cand_near.erase(std::unique(cand_near.begin(), cand_near.end()), cand_near.end());
            cand_hit.assign(cand_near.size(), PixelHit{});
            cand_changed.assign(cand_near.size(), 0);
            arena.execute([&] {
                tbb::parallel_for(size_t(0), cand_near.size(), [&](size_t q) {
                    const size_t k = cand_near[q];
                    cand_changed[q] = nearer_hit(static_cast<int>(k % W), static_cast<int>(k / W), cand_hit[q]);
                });
            });
            updates.clear();
            for (size_t q = 0; q < cand_near.size(); ++q)
                if (cand_changed[q]) updates.push_back({cand_near[q], cand_hit[q]});
        }
    } else {
        progress.add(H);
    }
    st.newton_ms = ms_since(t0);

    // 5. Shading from the exact normal; AOVs.
    t0 = Clock::now();
    RenderImage& img = res.image;
    img.width = W;
    img.height = H;
    img.rgba.assign(4 * npx, 0.0f);
    img.z.assign(npx, std::numeric_limits<float>::infinity());
    img.normal.assign(3 * npx, 0.0f);
    img.face.assign(npx, 0);
    img.u.assign(npx, 0.0f);
    img.v.assign(npx, 0.0f);
    img.iterations.assign(npx, 0);
    // Key light from the upper left behind the viewer, plus a headlight along the ray.
    const Vec3 key = normalize(-1.0 * camera.forward() + 0.6 * camera.up() - 0.5 * camera.right());
    parallel_rows(H, arena, &progress, options, [&](int j) {
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
            // The solve's normal (exact at the double-precision hit); the limits
            // of surface_normal only where its partials were degenerate.
            Vec3 n{h.nx, h.ny, h.nz};
            if (n.x == 0 && n.y == 0 && n.z == 0) n = surface_normal(f.surface, h.u, h.v, f.reversed);
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
            img.normal[3 * k] = static_cast<float>(n.x);
            img.normal[3 * k + 1] = static_cast<float>(n.y);
            img.normal[3 * k + 2] = static_cast<float>(n.z);
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
        switch (rescued[k]) {
            case kRescueNeighbour: ++st.rescue_neighbour; break;
            case kRescueSilhouette: ++st.rescue_silhouette; break;
            case kRescueGeneral: ++st.rescue_general; break;
            case kRescueTrimTol: ++st.rescue_trim_tolerance; break;
            default: break;
        }
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
    st.fallback = st.rescue_neighbour + st.rescue_silhouette + st.rescue_general + st.rescue_trim_tolerance;
    st.mean_iterations = solves ? double(its) / solves : 0.0;
    for (int j = 0; j < H; ++j)
        for (int i = 0; i < W; ++i) {
            auto hit = [&](int a, int b) { return a >= 0 && b >= 0 && a < W && b < H && img.face[map.index(a, b)]; };
            if (!img.face[map.index(i, j)] && hit(i - 1, j) && hit(i + 1, j) && hit(i, j - 1) && hit(i, j + 1))
                ++st.holes;
        }
    st.map_triangles = prepared.map_mesh().triangles();
    st.total_ms = ms_since(t_total);
    throw_if_canceled(options);
    progress.finish();
    return res;
}

namespace {
// The sRGB transfer function (IEC 61966-2-1): linear segment near black, then 1/2.4 power.
float srgb_encode(float x) {
    return x <= 0.0031308f ? 12.92f * x : 1.055f * std::pow(x, 1.0f / 2.4f) - 0.055f;
}
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
    std::vector<uint8_t> buf(npx * nch);
    for (size_t k = 0; k < npx; ++k)
        for (int c = 0; c < nch; ++c) {
            const float x = std::clamp(img.rgba[4 * k + c], 0.0f, 1.0f);
            const float g = c == 3 ? x : srgb_encode(x);  // display formats are sRGB; alpha stays linear
            buf[k * nch + c] = static_cast<uint8_t>(std::lround(g * 255.0f));
        }
    if (!out->open(path, spec) || !out->write_image(TypeDesc::UINT8, buf.data()) || !out->close())
        throw Error(ErrorCode::io, "cannot write '" + path + "': " + out->geterror());
}

}  // namespace nurbsrt
