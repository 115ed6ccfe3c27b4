// The lights of every frame: a key light, a fill light and a hemispherical
// ambient term, fixed relative to the camera. CAD viewers turn their lights
// with the view, so every view of a model reads alike and no view is lit from
// behind. The classic three-point layout without the back light (which only
// separates a subject from its background, here transparent or flat): the key
// from the upper left in front of the model shapes it, the fill from the right
// and slightly below opens the key's dark side, and the ambient term, brighter
// on faces turned up than down (a sky and a ground), keeps the form readable
// where neither reaches. Exact shadows (shadow_rays.h) are cast by the key only.
#pragma once

#include "renderer/camera.h"
#include "core/vec.h"

namespace nurbsrt {

struct LightRig {
    Vec3 key;   // unit direction from the model towards the key light
    Vec3 fill;  // towards the fill light
    Vec3 sky;   // the camera's up: the ambient term's brighter hemisphere
};

inline LightRig light_rig(const Camera& camera) {
    const Vec3 f = camera.forward(), u = camera.up(), r = camera.right();
    return {normalize(-1.0 * f + 0.6 * u - 0.5 * r), normalize(-1.0 * f - 0.25 * u + 0.85 * r), u};
}

}  // namespace nurbsrt
