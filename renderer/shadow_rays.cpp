// KeyLightShadows: the light's preliminary map and Newton along light rays (see shadow_rays.h).
#include "renderer/shadow_rays.h"

#include <algorithm>
#include <cmath>

namespace nurbsrt {

namespace {

// The light map's size follows the view's (so thin occluders the view resolves
// are resolved by the light too), within bounds: below 256 pixels the map's
// mesh starts miss small occluders; above 2048 the map costs more than the
// shadow solves it saves.
constexpr int kMinLightMap = 256, kMaxLightMap = 2048;
// The bounding sphere is framed with this much room, so faces on it stay inside
// the map's outer pixels.
constexpr double kLightMapMargin = 1.02;
// The point's own surface crosses its light ray within eps / cos of the point
// (see the header); crossings closer than this many of those are the point
// itself (or the edge it lies on), farther ones are occluders. 4: the point and
// the crossing each carry up to one tolerance, doubled for margin.
constexpr double kSelfCrossingTolerances = 4;
// Below this cosine between normal and light the key light contributes less
// than 1 % and the self-crossing distance eps / cos stops mattering.
constexpr double kMinCosine = 0.01;
// The 3x3 around a pixel, the centre first, then the 4-neighbours, then the corners.
constexpr int kFirstRing = 9;
constexpr int kRingOrder[kFirstRing][2] = {{0, 0}, {-1, 0}, {1, 0}, {0, -1}, {0, 1}, {-1, -1}, {1, -1}, {-1, 1}, {1, 1}};

// Whether a hit lies on its face's parameter-box border (PixelHit keeps (u, v) as
// floats: the clamped border value rounds the same way).
bool on_box_border(const UvBox& b, const PixelHit& h) {
    auto f = [](double x) { return static_cast<float>(x); };
    return h.u == f(b.u0) || h.u == f(b.u1) || h.v == f(b.v0) || h.v == f(b.v1);
}

}  // namespace

CameraSpec KeyLightShadows::light_view(const Scene& scene, Vec3 key, int size) {
    Vec3 centre{0, 0, 0};
    double radius = 1;
    if (!scene.bbox.empty()) {
        centre = 0.5 * (scene.bbox.lo + scene.bbox.hi);
        radius = std::max(0.5 * length(scene.bbox.hi - scene.bbox.lo), 1e-300);
    }
    CameraSpec s;
    s.projection = Projection::orthographic;
    s.eye = centre + 2 * radius * key;  // outside the sphere: every face is in front of the light
    s.target = centre;
    // Any up not along the light will do (the map's roll does not matter).
    const Vec3 ax = std::fabs(key.z) < 0.9 ? Vec3{0, 0, 1} : Vec3{1, 0, 0};
    s.up = ax;
    s.ortho_height = 2 * radius * kLightMapMargin;
    s.width = s.height = size;
    return s;
}

KeyLightShadows::KeyLightShadows(const FrameContext& view, const Solver& view_solver, Vec3 key)
    : key_(key),
      size_(std::clamp(std::max(view.width, view.height), kMinLightMap, kMaxLightMap)),
      camera_(light_view(view.scene, key, size_)),
      map_(render_preliminary_map(view.prepared, camera_, MapPrecision::float32)),
      progress_(no_progress_, 1),
      ctx_{view.prepared, view.scene, camera_, map_, view.options, view.arena, progress_, size_, size_, view.nfaces},
      projected_(view.options.method == NewtonMethod::proposed ? view.scene.faces.size() : 0),
      solver_{ctx_, projected_, view_solver.robust, view_solver.robust},
      contact_(camera_.spec().ortho_height / size_) {
    view.arena.execute([&] {
        tbb::parallel_for(size_t(0), projected_.size(),
                          [&](size_t k) { projected_[k] = project_surface(camera_, view.scene.faces[k].surface); });
    });
}

bool KeyLightShadows::blocked(Vec3 p, Vec3 n) const {
    const double cosine = dot(n, key_);
    if (!(cosine > 0)) return false;
    // p in the light's view: its screen point, its depth along the light, its map pixel.
    const Vec4 P = camera_.project_h({p.x, p.y, p.z, 1});
    const ScreenPoint sp{P.x / P.z, P.y / P.z};
    const double t_p = camera_.depth(P);
    const int ci = static_cast<int>(std::floor((sp.sx / camera_.aspect() + 1) * 0.5 * size_));
    const int cj = static_cast<int>(std::floor((1 - sp.sy) * 0.5 * size_));
    const double self = kSelfCrossingTolerances * solver_.params.eps / std::max(cosine, kMinCosine);
    // The faces of the 3x3 around that pixel, each once from its pixel nearest
    // the centre: the map's mesh covers a face's exact silhouette to within a
    // pixel, so a face the light ray crosses shows there. A face whose solve
    // did not converge (a light ray grazing an occluder's silhouette, where
    // Newton's Jacobian turns singular and a start a pixel away overshoots) is
    // tried again from each of its other pixels in the 5x5.
    uint32_t tried[kFirstRing], failed[kFirstRing];
    int ntried = 0, nfailed = 0;
    int first[kFirstRing];  // the 5x5 cells already tried
    auto occludes = [&](int i, int j, uint32_t id) {
        const size_t k = map_.index(i, j);
        PixelHit h;
        rays_.fetch_add(1, std::memory_order_relaxed);
        // A crossing inside the face's trim blocks the light. One just outside
        // it, within the trim band (Solver's near hit), only within a light-map
        // pixel of the point: where the point lies at a concave edge and the
        // adjacent face crosses the ray right beside it (both trim loops are
        // only within tolerance of the shared edge). Farther away it would widen
        // every occluder by its trim band, a phantom shadow line along each
        // free edge; and a stop on the face's parameter-box border near the ray
        // (Solver's border-gap hit) is never a crossing.
        const Outcome o = solver_.solve(id, sp, map_.u[k], map_.v[k], solver_.robust, true, h);
        if (o == kConverged) return h.t < t_p - self;
        if (o == kNearTrim)
            return h.t < t_p - self && h.t > t_p - contact_ && !on_box_border(ctx_.prepared.faces()[id - 1].box, h);
        if (o != kTrimmed && std::find(failed, failed + nfailed, id) == failed + nfailed) failed[nfailed++] = id;
        return false;
    };
    for (const auto& d : kRingOrder) {
        const int i = ci + d[0], j = cj + d[1];
        if (!ctx_.in_frame(i, j)) continue;
        const uint32_t id = map_.face[map_.index(i, j)];
        if (!id || std::find(tried, tried + ntried, id) != tried + ntried) continue;
        first[ntried] = (d[1] + 2) * 5 + d[0] + 2;
        tried[ntried++] = id;
        if (occludes(i, j, id)) return true;
    }
    if (!nfailed) return false;
    for (int dj = -2; dj <= 2; ++dj)
        for (int di = -2; di <= 2; ++di) {
            const int i = ci + di, j = cj + dj;
            if (!ctx_.in_frame(i, j)) continue;
            const uint32_t id = map_.face[map_.index(i, j)];
            if (!id || std::find(failed, failed + nfailed, id) == failed + nfailed ||
                std::find(first, first + ntried, (dj + 2) * 5 + di + 2) != first + ntried)
                continue;
            if (occludes(i, j, id)) return true;
        }
    return false;
}

}  // namespace nurbsrt
