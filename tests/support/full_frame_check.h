// The full-frame check of a rendered frame against the exact reference
// (importer/reference/reference_intersector.h): instead of sampling pixels, it looks at
// EVERY pixel of the frame for the two defects a user sees as dots:
//
//  * hole: a pixel we show as background although the exact ray hits a face.
//    Candidates: background pixels with hits on both sides within kEnclosureRadius
//    pixels along a row, a column or a diagonal (enclosed by the object: a crack
//    along a shared edge, a pinhole in a face).
//  * wrong-sheet speckle: a pixel whose hit is farther than a hit the exact ray
//    has (by more than the noise floor, and on its own face by more than one
//    contact's spread at grazing incidence, kContactSpreadMargin). Candidates: depth spikes, hits farther than BOTH neighbours of a row or
//    column pair by more than the depth noise floor (kDepthNoiseRelative); and
//    the far side of every depth step between sheets (kStepFootprints,
//    kStepAsymmetry): a run of several far-sheet pixels has no spike in it, but
//    its end pixels are such steps (a pixel farther than the neighbour on one
//    side, level with the one on the other).
//  * off-ray hit: a pixel showing a point of its face that does not lie on the
//    pixel's ray (a phantom: a face drawn where the ray passes it by). Checked on
//    EVERY hit pixel, without the intersector: the point at the pixel's (face, u,
//    v) AOVs, evaluated by OCCT (Geom_BSplineSurface of the face's NURBS), must
//    lie within kOffRayPixels pixel footprints (or the face's tolerance) of the
//    ray. A crack filled within the model's tolerance passes; a Newton iterate
//    stuck on a face's border pixels short of the ray does not.
//
// Every candidate is re-cast as the SAME contract pixel ray (Camera::pixel_ray)
// against the original OCCT shape. Disputes are settled as in
// tests/render_accuracy_test.cpp: IntCurvesFace_ShapeIntersector misses a root now
// and then and can report a point off its face, so a reference hit counts only if
// BRepExtrema_DistShapeShape puts it on its face (within the face's tolerance).
// Each hole and speckle found gets a diagnosis from the renderer's own parts (map
// start, Newton from the neighbours' hits, the nearest root on the reference face
// and where it lies relative to our trim loops and their tolerance band).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "renderer/camera.h"
#include "renderer/render.h"
#include "core/scene/scene.h"

namespace nurbsrt {
class ReferenceIntersector;
namespace occt {
struct OcctModel;
}
}  // namespace nurbsrt

namespace nurbsrt::test {

// A background pixel is enclosed when hits lie on both sides of it within this
// many pixels along one of the 4 lines through it: a crack up to 3 pixels wide
// (2 px cracks were seen where a vertex blend meets two fillets) is enclosed, the
// open background beyond a silhouette is not.
constexpr int kEnclosureRadius = 2;
// Depth noise floor, relative to the bounding-box diagonal: the accuracy bound of
// a hit distance (render_accuracy_test: |t - t_occt| <= 1e-6 diag). A spike
// smaller than that, or a reference hit nearer by less, is not evidence of a
// farther sheet.
constexpr double kDepthNoiseRelative = 1e-6;
// A speckle needs the reference nearer by more than the spread of one contact
// at grazing incidence: every point of the surface within a solver's tolerance
// of the ray counts as its root, and along a ray meeting the surface at
// cos(a) = |n . d| (n the unit normal, d the ray's direction) such points span
// (tol / cos(a)) to either side of the exact root (the tangent plane rises from
// the ray by cos(a) per unit along it). Two correct roots of one contact can so
// differ in t by (our tolerance + the reference's) / cos(a): at cos(a) = 0.002
// on a dense coil seen edge-on (step/bug29715_slow.stp front), 9e-4, five times
// the noise floor above. This factor of margin covers the perspective image
// plane's residual (proposed's (12) measures the offset perpendicular to the
// view axis, not the ray) and the surface's curvature along the contact.
constexpr double kContactSpreadMargin = 2.0;

// "Lies on its face": the distance from a hit point to the trimmed face is at most
// max(kDepthNoiseRelative x diag, kOnFaceTolFactor x BRep_Tool::Tolerance(face)):
// the modeller guarantees the face only to its tolerance, with a margin of 4 for
// DistShapeShape's own precision (as in render_accuracy_test).
constexpr double kOnFaceTolFactor = 4.0;

// Time budget of one frame's check (reference rays and settlements), seconds.
// A reference ray costs 0.1 ms to ~2 ms (ReferenceIntersector cuts dense
// B-spline faces into pieces), and every model's whole check takes well under
// this; it guards against a slow machine or a new slow model. Spike candidates
// left when it runs out (the shallowest, see the .cpp) are counted as unchecked
// and reported, never silently dropped.
constexpr double kCheckBudgetSeconds = 40.0;

// A depth step: a hit farther than a 4-neighbour's by more than this many pixel
// footprints at its depth (two sheets; a surface sloped 63 degrees from facing
// the eye steps 2 footprints per pixel along its slope) ...
constexpr double kStepFootprints = 2.0;
// ... and by more than this many times its difference from the opposite
// neighbour: on one smooth sheet, however steep (the orthographic views see
// faces edge-on), depth steps alike to both sides; at the end of a run of
// far-sheet pixels the near neighbour is a whole sheet gap away and the far
// one level. Without it the front views of the duck and cylinder block had
// 16,000 candidates each, over 20 s of reference rays.
constexpr double kStepAsymmetry = 4.0;

// An off-ray hit lies farther than this many pixel footprints from its ray
// (and farther than the face's tolerance, kOnFaceTolFactor x): the point is
// drawn in another pixel than its own. A true hit lies within the Newton
// tolerance (1e-8 of the diagonal) plus the rounding of the float (u, v) and
// depth AOVs, orders of magnitude below; a crack filled by a stop on a face's
// border (the renderer's border-gap hit) within half a footprint.
constexpr double kOffRayPixels = 1.0;

struct FullFrameFinding {
    enum class Kind { hole, speckle, off_ray };
    Kind kind = Kind::hole;
    int i = 0, j = 0;
    uint32_t face = 0;  // ours (0: background)
    double t = 0;       // ours
    int ref_face = 0;
    double ref_t = 0;
    double ref_on_face = 0;  // BRepExtrema distance of the reference hit to its face
    // off_ray: the shown point's distance from the ray, in model units and in
    // pixel footprints (the reference fields above stay unset).
    double off_distance = 0, off_footprints = 0;
    std::string cause;   // short classification (see diagnose in the .cpp)
    std::string detail;  // the evidence
};

struct FullFrameReport {
    std::string label;
    int width = 0, height = 0;
    long pixels_hit = 0;
    long enclosed = 0;  // hole candidates (enclosed background pixels)
    long spikes = 0;    // speckle candidates (depth spikes)
    long steps = 0;     // speckle candidates (far sides of depth steps, not spikes)
    long holes = 0, speckles = 0;
    long off_ray = 0;       // hit pixels showing a point off their ray (every hit pixel checked)
    long grazing = 0;       // reference nearer, on our face, within the contact's spread (not speckles)
    long ref_errors = 0;    // candidates the intersector threw on (no reference)
    long ref_spurious = 0;  // reference hits settled as not on their face
    long unchecked = 0;     // candidates left when kCheckBudgetSeconds ran out
    std::vector<FullFrameFinding> findings;  // every hole, speckle and off-ray hit, in that order
    double check_s = 0;                      // time of the reference rays and settlements

    // Counts, then up to max_listed findings with their diagnosis.
    std::string text(size_t max_listed = 12) const;
};

// Checks `image` (rendered by `camera` from `scene`) against `model` (the same file
// as OCCT reads it, face-index contract) with `inter` (built on `model`), within
// budget_seconds.
FullFrameReport full_frame_check(const std::string& label, const Scene& scene, const occt::OcctModel& model,
                                 ReferenceIntersector& inter, const Camera& camera, const RenderImage& image,
                                 double budget_seconds = kCheckBudgetSeconds, size_t max_diagnosed = 12);

// The ray length that bounds every hit of the scene from the camera.
double reference_ray_limit(const Scene& scene, const Camera& camera);

}  // namespace nurbsrt::test
