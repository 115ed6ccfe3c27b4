// Solver: a pixel's Newton solve of one face and its trim test (see pixel_solver.h).
#include "core/check.h"
#include "renderer/frame/pixel_solver.h"

#include <algorithm>
#include <cmath>

#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include "core/scene/nurbs.h"
#include "renderer/solve/span_basis.h"

namespace nurbsrt {

namespace {

// A border stop farther from its ray than this many pixel footprints is not
// taken for a hit in a crack, whatever the trim band allows: the point shown
// would lie visibly beside the pixel's ray. Half a pixel still fills faces
// whose NURBS stops short of the shape's face by a fraction of a pixel.
constexpr double kMaxBorderGapPixels = 0.5;
// Relative margin of that early decision for the rounding of the bounds (a few
// units in the last place) against the exact test's own.
constexpr double kBoundRounding = 1e-9;

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

}  // namespace

ProjectedFaces project_faces(const FrameContext& ctx) {
    ProjectedFaces p;
    if (ctx.options.method != NewtonMethod::proposed) return p;
    const size_t n = ctx.scene.faces.size();
    p.patches.resize(n);
    p.surfaces.resize(n);
    ctx.arena.execute([&] {
        tbb::parallel_for(size_t(0), n, [&](size_t k) {
            const SurfacePatches& model = ctx.prepared.faces()[k].patches;
            if (model.usable())
                p.patches[k] = project_patches(ctx.camera_of(static_cast<uint32_t>(k + 1)), model);
            else
                p.surfaces[k] =
                    project_surface(ctx.camera_of(static_cast<uint32_t>(k + 1)), ctx.scene.faces[k].surface);
        });
    });
    return p;
}

const NurbsSurface& Solver::iterated_surface(uint32_t id) const {
    const bool proposed = ctx.options.method == NewtonMethod::proposed;
    return proposed ? projected.surfaces[id - 1] : ctx.scene.faces[id - 1].surface;
}

const SurfacePatches* Solver::iterated_patches(uint32_t id) const {
    const bool proposed = ctx.options.method == NewtonMethod::proposed;
    const SurfacePatches& p = proposed ? projected.patches[id - 1] : ctx.prepared.faces()[id - 1].patches;
    return p.usable() ? &p : nullptr;
}

SurfaceDerivs Solver::start_derivs(uint32_t id, double u0, double v0) const {
    return SurfaceEvaluation(iterated_surface(id), &ctx.prepared.faces()[id - 1].spans, iterated_patches(id))
        .d1(u0, v0);
}

Outcome Solver::solve(uint32_t id, ScreenPoint sp, double u0, double v0, const NewtonParams& p, bool near,
                      PixelHit& hit, const SurfaceDerivs* start, double* crossing) const {
    NURBSRT_DCHECK(id >= 1 && id <= ctx.faces);  // face ids are 1-based, 0 is the background
    // A hidden face (RenderOptions::hidden_faces) has no points, like a trimmed-away part.
    if (!ctx.options.hidden_faces.empty() && ctx.options.hidden_faces[id - 1]) return kTrimmed;
    const PreparedFace& ff = ctx.prepared.faces()[id - 1];
    const Camera& camera = ctx.camera_of(id);  // the face's own: hit distances are the frame camera's
    const NurbsSurface& surface = iterated_surface(id);
    const SurfacePatches* patches = iterated_patches(id);
    const NewtonResult r = ctx.options.method == NewtonMethod::proposed
                               ? newton_proposed(surface, camera, sp, u0, v0, ff.box, p, &ff.spans, start, patches)
                               : newton_martin(surface, camera.ray(sp), u0, v0, ff.box, p, &ff.spans, start, patches);
    hit.iterations = static_cast<uint8_t>(std::min(r.iterations, 255));
    if (near && r.status != NewtonStatus::converged && r.status != NewtonStatus::behind_eye &&
        border_gap_hit(id, sp, r, hit))
        return kNearTrim;
    switch (r.status) {
        case NewtonStatus::converged:
            break;
        case NewtonStatus::diverged:
            return kDiverged;
        case NewtonStatus::singular:
            return kSingular;
        case NewtonStatus::max_iterations:
            return kMaxIter;
        case NewtonStatus::left_domain:
            return kLeftDomain;
        case NewtonStatus::behind_eye:
            return kBehind;
    }
    if (crossing) *crossing = r.t;
    if (removed_by_sections(sp, r.t)) return kTrimmed;
    Outcome o = kConverged;
    if (!ff.trim.inside({r.u, r.v})) {
        if (!near || !(ff.trim.boundary_distance({r.u, r.v}, ff.near_uv) <= ff.near_uv)) return kTrimmed;
        o = kNearTrim;
    }
    set_hit(ctx.scene.faces[id - 1], id, r.u, r.v, r.t, r.Cu, r.Cv, hit);
    return o;
}

bool Solver::removed_by_sections(ScreenPoint sp, double t) const {
    const Sections& sections = ctx.options.sections;
    if (!sections.active()) return false;
    const Ray ray = ctx.camera.ray(sp);
    return sections.removes(ray.origin + t * ray.dir);
}

// Adjacent faces of a CAD model meet only within their edges' tolerance: a ray
// through the gap makes Newton stop on the face's parameter-box border, short
// of the ray (the exact hit lies on the surface's extension). Such a stop counts
// as a near hit when the border point is within the trim band in (u,v) and, in
// model units, within the band times the surface's speed across the border it
// stopped on (|C_v| on a v border, |C_u| on a u border: how far a step of the
// band off that border goes), and within kMaxBorderGapPixels of the ray.
// With the larger speed of the two instead, faces much longer in one parameter
// than in the other accepted iterates stuck on a border for rays that miss the
// face by several pixels: phantom strips beside the face.
bool Solver::border_gap_hit(uint32_t id, ScreenPoint sp, const NewtonResult& r, PixelHit& hit) const {
    const PreparedFace& ff = ctx.prepared.faces()[id - 1];
    const UvBox& b = ff.box;
    const bool u_border = r.u == b.u0 || r.u == b.u1, v_border = r.v == b.v0 || r.v == b.v1;
    if (!u_border && !v_border) return false;
    // The test below, decided early and exactly where the stop's bounds already
    // fail it (NewtonResult::gap_bound, t_bound; the band never exceeds
    // kMaxBorderGapPixels footprints, which grow with t), without the trim test
    // and the surface evaluation.
    if (!(r.t_bound > 0) || r.gap_bound > (1 + kBoundRounding) * kMaxBorderGapPixels * ctx.pixel_footprint(r.t_bound))
        return false;
    if (!ff.trim.inside({r.u, r.v}) && !(ff.trim.boundary_distance({r.u, r.v}, ff.near_uv) <= ff.near_uv)) return false;
    const SurfaceEvaluation eval(ctx.scene.faces[id - 1].surface, &ff.spans, &ff.patches);
    const CartesianDerivs c = eval.cartesian(r.u, r.v);
    const Ray ray = ctx.camera_of(id).ray(sp);  // the face in place, the ray moved
    const Vec3 q = c.P - ray.origin;
    const double t = dot(q, ray.dir);
    const double gap = length(q - t * ray.dir);
    const double across = std::max(u_border ? length(c.Pu) : 0.0, v_border ? length(c.Pv) : 0.0);
    const double band = std::min(ff.near_uv * across, kMaxBorderGapPixels * ctx.pixel_footprint(t));
    if (!(t > 0) || !(gap <= band) || removed_by_sections(sp, t)) return false;
    set_hit(ctx.scene.faces[id - 1], id, r.u, r.v, t, c.Pu, c.Pv, hit);
    return true;
}

}  // namespace nurbsrt
