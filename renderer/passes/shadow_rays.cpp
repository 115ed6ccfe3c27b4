// KeyLightShadows: the light's preliminary map and Newton along light rays (see shadow_rays.h).
#include "renderer/passes/shadow_rays.h"

#include <algorithm>
#include <cmath>

#include "core/scene/nurbs.h"

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
// The light map shows a point's own face at the point itself when the map's
// (u, v) at the point's pixel is within this many pixel steps of the point's:
// the point lies within half a pixel of the pixel centre, and the map's
// interpolated (u, v) is off by the mesh's deflection, well under a pixel. A
// part of the face folded in front of the point has its (u, v) far away.
constexpr double kOwnReachPixels = 1.5;
// Within a 3x3 of one smooth part of a face, pixel steps in (u, v) differ by the
// perspective and the parametrization's stretch over 3 pixels: a few percent to
// a factor ~2 on a strongly non-uniform B-spline. Beyond 4x it is two parts.
constexpr double kMaxStepSpread = 4;
// The 3x3 around a pixel, the centre first, then the 4-neighbours, then the corners.
constexpr int kFirstRing = 9;
constexpr int kRingOrder[kFirstRing][2] = {{0, 0},   {-1, 0}, {1, 0},  {0, -1}, {0, 1},
                                           {-1, -1}, {1, -1}, {-1, 1}, {1, 1}};
// Where the 3x3 shows a face in front of the point that the light ray does not
// cross (its map mesh covers where the exact face does not: a thin face, the
// band along a trim), the occluder may be a face hidden behind it in the map,
// adjacent to it. Those adjacent faces whose mesh comes within 2 light-map
// pixels of the point are tried, at most 4, nearest first (a plate with many
// holes has dozens of neighbours).
constexpr NearFaceBound kAdjacentFaces{4, 2.0};
// A screen distance bound of 0 for nearest_starts: only mesh triangles that
// contain the light ray's screen point, i.e. the ray pierces the face's mesh.
constexpr double kPiercedOnly = 0.0;
// Where the point's own face was solved to the point itself, its mesh sheets
// in front of the point are tried (nearest to the light first, at most 2,
// within 2 light-map pixels, as the view's nearer-sheet pass does at a pit),
// only where the light grazes the point: there the ray stays near the surface,
// and Newton from a start on the part in front can run on to the point's root.
// At every angle this would cost far more light rays for no gain.
constexpr int kMaxOwnSheets = 2;
constexpr double kOwnSheetReachPixels = 2.0;
constexpr double kGrazingCosine = 0.2;

// The view's robust Newton with the default backtracking (NewtonParams::backtracks):
// a light ray has one start per face, and one grazing an occluder converges only
// through the deeper halvings (the view rescue's two let light leak).
NewtonParams light_ray_params(const NewtonParams& view_robust) {
    NewtonParams p = view_robust;
    p.backtracks = NewtonParams{}.backtracks;
    return p;
}

// Whether a hit lies on its face's parameter-box border (PixelHit keeps (u, v) as
// floats: the clamped border value rounds the same way).
bool on_box_border(const UvBox& b, const PixelHit& h) {
    auto f = [](double x) { return static_cast<float>(x); };
    return h.u == f(b.u0) || h.u == f(b.u1) || h.v == f(b.v0) || h.v == f(b.v1);
}

}  // namespace

CameraSpec KeyLightShadows::light_view(const BBox& box, Vec3 key, int size) {
    Vec3 centre{0, 0, 0};
    double radius = 1;
    if (!box.empty()) {
        centre = 0.5 * (box.lo + box.hi);
        radius = std::max(0.5 * length(box.hi - box.lo), 1e-300);
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

int light_map_size(int width, int height) { return std::clamp(std::max(width, height), kMinLightMap, kMaxLightMap); }

KeyLightShadows::KeyLightShadows(const FrameContext& view, const Solver& view_solver, Vec3 key)
    : key_(key),
      size_(light_map_size(view.width, view.height)),
      camera_(light_view(view.bbox, key, size_)),
      face_cameras_(camera_, view.options.face_offsets),
      map_(render_preliminary_map(view.prepared, camera_, MapPrecision::float32, {0, view.options.cancel.get()},
                                  {&view.options.sections, &view.options.hidden_faces, &view.options.face_offsets})),
      progress_(no_progress_, 1),
      ctx_{view.prepared, view.scene, camera_, face_cameras_, map_,        view.options,
           view.arena,    progress_,  size_,   size_,         view.nfaces, view.bbox},
      projected_(project_faces(ctx_)),
      solver_{ctx_, projected_, light_ray_params(view_solver.robust), light_ray_params(view_solver.robust)},
      screen_points_(ctx_),
      contact_(camera_.spec().ortho_height / size_) {}

bool KeyLightShadows::own_face_first(int ci, int cj, uint32_t face, double u, double v) const {
    // The (u, v) step of one map pixel on this face here: the largest difference
    // between 4-adjacent pixels of the 3x3 that both show the face.
    double du = 0, dv = 0, step_lo = HUGE_VAL, step_hi = 0;
    int pairs = 0;
    for (int dj = -1; dj <= 1; ++dj)
        for (int di = -1; di <= 1; ++di) {
            const int i = ci + di, j = cj + dj;
            if (!ctx_.in_frame(i, j) || map_.face[map_.index(i, j)] != face) continue;
            const size_t k = map_.index(i, j);
            for (const auto& [ni, nj] : {std::pair{i + 1, j}, std::pair{i, j + 1}}) {
                if (ni > ci + 1 || nj > cj + 1 || !ctx_.in_frame(ni, nj) || map_.face[map_.index(ni, nj)] != face)
                    continue;
                const size_t m = map_.index(ni, nj);
                const double pu = std::fabs(map_.u[m] - map_.u[k]), pv = std::fabs(map_.v[m] - map_.v[k]);
                du = std::max(du, pu);
                dv = std::max(dv, pv);
                step_lo = std::min(step_lo, pu + pv);
                step_hi = std::max(step_hi, pu + pv);
                ++pairs;
            }
        }
    // Steps that differ much mean two parts of the face (a fold seen from the
    // light, or a seam) meet in the 3x3: no telling which part the centre shows.
    if (!pairs || !ctx_.in_frame(ci, cj) || step_hi > kMaxStepSpread * step_lo) return false;
    const size_t c = map_.index(ci, cj);
    return map_.face[c] == face && std::fabs(map_.u[c] - u) <= kOwnReachPixels * du &&
           std::fabs(map_.v[c] - v) <= kOwnReachPixels * dv;
}

double KeyLightShadows::speed(uint32_t id, const PixelHit& h) const {
    const PreparedFace& f = ctx_.prepared.faces()[id - 1];
    const SurfaceEvaluation eval(ctx_.scene.faces[id - 1].surface, &f.spans, &f.patches);
    const CartesianDerivs c = eval.cartesian(h.u, h.v);
    return std::max(length(c.Pu), length(c.Pv));
}

bool KeyLightShadows::blocked(Vec3 p, Vec3 n, uint32_t face, double u, double v) const {
    const double cosine = dot(n, key_);
    if (!(cosine > 0)) return false;
    // p in the light's view: its screen point, its depth along the light, its map pixel.
    const Vec4 P = camera_.project_h({p.x, p.y, p.z, 1});
    const ScreenPoint sp{P.x / P.z, P.y / P.z};
    const double t_p = camera_.depth(P);
    const int ci = static_cast<int>(std::floor(camera_.pixel_x(sp.sx)));
    const int cj = static_cast<int>(std::floor(camera_.pixel_y(sp.sy)));
    const double self = kSelfCrossingTolerances * solver_.params.eps / std::max(cosine, kMinCosine);
    // The faces of the 3x3 around that pixel, each once from its pixel nearest
    // the centre: the map's mesh covers a face's exact silhouette to within a
    // pixel, so a face the light ray crosses shows there. Retrying failed faces
    // from their other pixels of the 5x5 cost much and changed almost nothing.
    uint32_t tried[kFirstRing];
    int ntried = 0;
    uint32_t near_face[kFirstRing];  // near crossings beyond contact, not blocking alone
    double near_t[kFirstRing];
    int nnear = 0;
    Outcome last = kNone;      // how occludes_from's solve ended
    double last_t = HUGE_VAL;  // and where
    auto occludes_from = [&](uint32_t id, double u0, double v0) {
        PixelHit h;
        rays_.fetch_add(1, std::memory_order_relaxed);
        // Crossings within a light-map pixel of the point (`contact`) are told
        // apart by their direction: the point's ray starts in the air, so its
        // first real crossing enters a solid; one that leaves a solid there is
        // the edge the point lies on. At a concave edge the adjacent face in
        // front of the point is crossed right beside it, within its trim band
        // (both trim loops are only within tolerance of the shared edge), and
        // only that close: at distance d the ray stands d * cos above the
        // point's surface, so a crossing of the adjacent face that high lies that
        // far inside it from the shared edge (below). A band crossing higher up
        // passes outside the face and would cast false shadows. Beyond contact a
        // band crossing blocks only beside another face's at the same depth (a
        // crack between two faces of an occluder): alone, the band would widen
        // every occluder into a phantom shadow line along its free edges. A stop
        // on the parameter-box border (Solver's border-gap hit) is no crossing.
        const Outcome o = last = solver_.solve(id, sp, u0, v0, solver_.robust, true, h);
        last_t = h.t;
        if (o != kConverged && o != kNearTrim) return false;
        if (!(h.t < t_p - self)) return false;
        const bool contact = h.t > t_p - contact_, entering = dot(Vec3{h.nx, h.ny, h.nz}, key_) < 0;
        if (o == kConverged) return !contact || entering;
        const PreparedFace& f = ctx_.prepared.faces()[id - 1];
        if (on_box_border(f.box, h)) return false;
        // The concave edge's crossing lies on the exact face, at least its
        // height above the point's surface inside it from the shared edge, and
        // the exact face ends within its trim uncertainty of the loops (trim_uv,
        // half the band, which allows for two faces' loops around a crack). So
        // the crossing lies at most trim_uv less that height (in (u, v): over the
        // surface's faster speed) outside the loops; farther out, the ray passes
        // beside the face (a grazing-lit wall under a ledge would be shadowed).
        if (contact) {
            const double reach = f.trim_uv - (t_p - h.t) * std::max(cosine, kMinCosine) / speed(id, h);
            return entering && reach >= 0 && std::isfinite(f.trim.boundary_distance({h.u, h.v}, reach));
        }
        // A near crossing of another face at the same depth: the ray passes
        // through the crack between two faces of an occluder, which it blocks.
        for (int q = 0; q < nnear; ++q)
            if (near_face[q] != id && std::fabs(near_t[q] - h.t) < contact_) return true;
        if (nnear < kFirstRing) near_face[nnear] = id, near_t[nnear++] = h.t;
        return false;
    };
    auto occludes_from_any = [&](uint32_t id, const Vec2* starts, int n) {
        for (int q = 0; q < n; ++q)
            if (occludes_from(id, starts[q].x, starts[q].y)) return true;
        return false;
    };
    auto occludes = [&](int i, int j, uint32_t id) {
        const size_t k = map_.index(i, j);
        if (occludes_from(id, map_.u[k], map_.v[k])) return true;
        // The point's own face, solved to the point itself (or beyond) from a
        // start the light map shows elsewhere on it: a ray leaving the face at a
        // grazing angle can cross it again nearer the light (a long hull lit
        // almost along it; never a plane), a root Newton ran past. Retried from
        // the face's mesh sheets more than a light-map pixel in front of the
        // point (the light is orthographic: depth along it is the ray's t).
        const bool found_itself = (last == kConverged || last == kNearTrim) && !(last_t < t_p - self);
        if (id == face && found_itself && cosine < kGrazingCosine && !ctx_.prepared.faces()[face - 1].planar) {
            Vec2 sheets[kMaxOwnSheets];
            const double reach = ctx_.screen_distance(kOwnSheetReachPixels);
            const int ns =
                screen_points_.starts_in_front(face, sp, reach * reach, t_p - contact_, sheets, kMaxOwnSheets);
            return occludes_from_any(face, sheets, ns);
        }
        // A solve that found no point at all (it diverged or ran off the
        // parameter box) set out from a start of the light map's pixel, which may
        // lie on another part of a strongly curved face than the one the ray
        // crosses: retried from the face's mesh where the ray pierces it. Only
        // there: retrying every failed solve from the nearest mesh point costs
        // many more rays, and most of what it finds lies where the ray pierces.
        if (!newton_failed(last)) return false;
        Vec2 starts[2];
        return occludes_from_any(id, starts, screen_points_.nearest_starts(id, sp, starts, nullptr, kPiercedOnly));
    };
    // Where the light map shows the point's own face at the point itself, the
    // face's solve would only find the point: skipped (most solves of a frame).
    if (own_face_first(ci, cj, face, u, v)) tried[ntried++] = face;
    uint32_t passed[kFirstRing];  // other faces of the 3x3, which the ray does not cross
    int npassed = 0;
    for (const auto& d : kRingOrder) {
        const int i = ci + d[0], j = cj + d[1];
        if (!ctx_.in_frame(i, j)) continue;
        const uint32_t id = map_.face[map_.index(i, j)];
        if (!id || std::find(tried, tried + ntried, id) != tried + ntried) continue;
        tried[ntried++] = id;
        if (occludes(i, j, id)) return true;
        // The point's own face counts as passed where the map shows another
        // part of it, in front of the point, that the ray passes beside: its
        // mesh covers the ray where the exact face ends, and can hide an
        // occluder joining it there.
        if (id != face || ((last == kTrimmed || last == kNearTrim) && last_t < t_p - contact_)) passed[npassed++] = id;
    }
    // Only where the map shows at the point's own pixel a face passed (another
    // face, or another part of the point's own): the light map's nearest
    // surface there is not the point's. Elsewhere (a face beside the point in
    // the 3x3, at every face border of the lit surfaces) the search is costly
    // and finds nothing.
    const uint32_t centre = ctx_.in_frame(ci, cj) ? map_.face[map_.index(ci, cj)] : 0;
    if (!centre || std::find(passed, passed + npassed, centre) == passed + npassed) return false;
    MeshScreenPoints::FarFace far[kAdjacentFaces.max_faces];
    const int nfar = screen_points_.adjacent_far_faces(passed, npassed, sp, far, kAdjacentFaces);
    for (int q = 0; q < nfar; ++q) {
        if (far[q].id == face || std::find(tried, tried + ntried, far[q].id) != tried + ntried) continue;
        if (occludes_from_any(far[q].id, far[q].starts, far[q].nstarts)) return true;
    }
    return false;
}

}  // namespace nurbsrt
