// The key light's shadows over the whole frame, against the exact reference:
// every hit pixel facing the light whose shadow flag (RenderImage::shadow)
// differs from all its neighbours', and even samples of the other shadowed and
// lit ones (counts below), has its light ray cast again with OCCT's
// IntCurvesFace_ShapeIntersector on the original shape, from its point a little
// towards the light (past the point's own surface).
//
//  * false shadow: we show it shadowed, the exact light ray is free (acne: a
//    surface shadowing itself; or a phantom occluder);
//  * leak: we show it lit, the exact light ray is blocked.
//
// The intersector can miss a crossing (seen on iges/marsCapsule.igs: a light
// ray through the interior of a face, 1e-10 from it by BRepExtrema, and no hit).
// So a pixel we shadow where it reports none is settled like the full-frame
// check's disputes: the distance of the light ray's segment from the shape by
// BRepExtrema_DistShapeShape; within the depth noise floor (kRayMeetsRelative)
// the ray meets a face and the shadow stands (counted as reference misses).
//
// A disagreement at a pixel with a neighbour flagged the other way lies within a
// pixel of the shadow's boundary (a light ray grazing an occluder's silhouette,
// where Newton along it may not converge, or passing within the trim tolerance
// of an occluder's edge): counted apart. Anywhere else it is a speckle or a
// patch a user sees, and the test demands none.
#pragma once

#include <string>

// The frame's check: the same inputs (scene, OCCT model, reference, camera, image).
#include "tests/support/full_frame_check.h"

namespace nurbsrt::test {

// How many pixels of a frame are re-cast, at most: every pixel whose flag
// differs from all its neighbours' (a speckle if wrong) up to kMaxSingles, then
// about this many samples of the shadowed and of the lit pixels, a fixed
// pseudo-random subset. Acne and leaks that are not single pixels are patches
// or lines, which such a sample finds;
// all pixels would cost minutes per frame on the models whose reference rays
// are slow (~1 ms). A fixed count, not a time budget, so that the counts a
// test compares are the same on any machine.
constexpr size_t kMaxSingles = 400, kMaxShadowedSamples = 800, kMaxLitSamples = 400;

struct ShadowCheckReport {
    long facing = 0;                                      // hit pixels facing the key light
    long shadowed = 0;                                    // of them, flagged shadowed
    long checked = 0;                                     // re-cast against the reference
    long false_shadows = 0;                               // away from the shadow's boundary
    long leaks = 0;                                       // away from the shadow's boundary
    long boundary_false_shadows = 0, boundary_leaks = 0;  // within a pixel of it
    long ref_errors = 0;                                  // the intersector threw
    long ref_misses = 0;  // we shadow, the intersector saw no hit, BRepExtrema finds the ray meets a face
    double check_s = 0;
    std::string detail;  // the first few disagreements away from the boundary
    std::string text(const std::string& label) const;
};

// `model`: the shape `inter` was made from, the referee of its misses.
ShadowCheckReport shadow_check(const Scene& scene, const occt::OcctModel& model, ReferenceIntersector& inter,
                               const Camera& camera, const RenderImage& image);

}  // namespace nurbsrt::test
