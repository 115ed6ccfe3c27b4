// One Newton solve of a face at a pixel, with the trim test: what every pass of
// the frame that solves (primary, rescue, nearer sheet) calls.
#pragma once

#include <cstdint>
#include <vector>

#include "renderer/frame/frame.h"
#include "renderer/solve/newton.h"

namespace nurbsrt {

// proposed: the paper's projection of every face to R^2 (project_surface), made
// per frame; empty for martin. Of a face with power-form patches, only those
// are projected (project_patches: all its Newton steps evaluate); of one
// without, the control points.
struct ProjectedFaces {
    std::vector<SurfacePatches> patches;
    std::vector<NurbsSurface> surfaces;
};
ProjectedFaces project_faces(const FrameContext& ctx);

struct Solver {
    const FrameContext& ctx;
    const ProjectedFaces& projected;
    NewtonParams params;  // the primary solves (the paper's criteria)
    NewtonParams robust;  // the rescue's solves (NewtonParams::robust)

    // One Newton solve of face id at the centre of pixel (i, j) from (u0, v0); hit if converged and
    // inside the trim. With `near`, a hit converged outside the trim but within the
    // face's trim-tolerance band is also returned (as kNearTrim): the sampled loops of
    // two faces sharing an edge are each only within that tolerance of the true edge,
    // so a ray through the sliver between the two polylines is rejected by both (a crack).
    // `crossing`: as below.
    Outcome solve(uint32_t id, int i, int j, double u0, double v0, const NewtonParams& p, bool near, PixelHit& hit,
                  double* crossing = nullptr) const {
        return solve(id, ctx.camera.pixel_screen(i, j), u0, v0, p, near, hit, nullptr, crossing);
    }
    Outcome solve(uint32_t id, int i, int j, double u0, double v0, PixelHit& hit) const {
        return solve(id, i, j, u0, v0, params, false, hit);
    }
    // The same for the ray through any screen point (a sub-pixel sample).
    // `start`: start_derivs(id, u0, v0), when several rays are solved from that start.
    // `crossing`: where Newton converged, inside the trim or not, the distance
    // along the ray at which it meets the surface (else left as it is).
    Outcome solve(uint32_t id, ScreenPoint sp, double u0, double v0, const NewtonParams& p, bool near, PixelHit& hit,
                  const SurfaceDerivs* start = nullptr, double* crossing = nullptr) const;
    // The derivatives the method's Newton iteration evaluates first when it
    // starts face id at (u0, v0) (newton.h, `start`): of the frame's projected
    // surface for proposed, of the model surface for martin.
    SurfaceDerivs start_derivs(uint32_t id, double u0, double v0) const;

private:
    // The surface the method's Newton iterates on: the frame's projection of
    // face id (proposed) or its model surface (martin).
    const NurbsSurface& iterated_surface(uint32_t id) const;
    // Its power-form patches, or null where it has none.
    const SurfacePatches* iterated_patches(uint32_t id) const;
    // Whether the point at distance t on the ray through sp is removed by a
    // section plane (section.h): such a root is rejected like one outside the trim.
    bool removed_by_sections(ScreenPoint sp, double t) const;
    bool border_gap_hit(uint32_t id, ScreenPoint sp, const NewtonResult& r, PixelHit& hit) const;
};

}  // namespace nurbsrt
