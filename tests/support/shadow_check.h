// The key light's shadows over the whole frame, against the exact reference:
// every hit pixel facing the light whose shadow flag (RenderImage::shadow)
// differs from all its neighbours', every kShadowedStride-th other shadowed one
// and every kLitStride-th other lit one has its light ray cast again with OCCT's
// IntCurvesFace_ShapeIntersector on the original shape, from its point a little
// towards the light (past the point's own surface).
//
//  * false shadow: we show it shadowed, the exact light ray is free (acne: a
//    surface shadowing itself; or a phantom occluder);
//  * leak: we show it lit, the exact light ray is blocked.
//
// A disagreement at a pixel with a neighbour flagged the other way lies within a
// pixel of the shadow's boundary (a light ray grazing an occluder's silhouette,
// where Newton along it may not converge, or passing within the trim tolerance
// of an occluder's edge): counted apart. Anywhere else it is a speckle or a
// patch a user sees, and the test demands none.
#pragma once

#include <string>

#include "renderer/camera.h"
#include "renderer/render.h"
#include "renderer/scene.h"

namespace nurbsrt {
class ReferenceIntersector;
}

namespace nurbsrt::test {

// Every this-many-th shadowed and lit pixel facing the light is re-cast: acne and
// leaks that are not single pixels (those are all re-cast) are patches or lines
// of pixels, which a sample finds; all of them would cost minutes per frame on
// the models whose reference rays are slow (~1 ms).
constexpr int kShadowedStride = 3, kLitStride = 16;
// Time budget of one frame's shadow check; the pixels left are counted, never dropped silently.
constexpr double kShadowCheckBudgetSeconds = 12.0;

struct ShadowCheckReport {
    long facing = 0;          // hit pixels facing the key light
    long shadowed = 0;        // of them, flagged shadowed
    long checked = 0;         // re-cast against the reference
    long false_shadows = 0;   // away from the shadow's boundary
    long leaks = 0;           // away from the shadow's boundary
    long boundary_false_shadows = 0, boundary_leaks = 0;  // within a pixel of it
    long ref_errors = 0;      // the intersector threw
    long unchecked = 0;       // left when the time budget ran out
    double check_s = 0;
    std::string detail;       // the first few disagreements away from the boundary
    std::string text(const std::string& label) const;
};

ShadowCheckReport shadow_check(const Scene& scene, ReferenceIntersector& inter, const Camera& camera,
                               const RenderImage& image);

}  // namespace nurbsrt::test
