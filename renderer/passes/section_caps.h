// Caps of closed bodies cut by section planes (section.h). A ray whose first
// kept hit is the inside of a closed body (its outward normal turned away from
// the viewer) entered the body through the removed space, at the last plane
// crossing before that hit: the pixel shows the plane there, as the solid's cut
// face would (what a Boolean cut by the half-space makes, BRepAlgoAPI_Cut).
// Where bodies touch (a bolt in its hole), the body holding the ray may end on
// the surface of another that begins there, and the first kept hit is then the
// other's outside, by a rounding: the map's inside layer (PreliminaryMap::inside,
// the parity of each closed body's crossings) says which body the ray entered
// the kept space in, and that body's cap shows. Open shells have no inside:
// their back faces show as they are.
#pragma once

#include <cstdint>
#include <optional>
#include <vector>

#include "core/scene/scene.h"
#include "renderer/frame/frame.h"
#include "renderer/render.h"
#include "renderer/section.h"

namespace nurbsrt {

struct CapHit {
    double t = 0;  // along the ray
    Vec3 normal;   // the plane's, facing the viewer
    uint32_t body = 0;
    int plane = -1;
};

class SectionCaps {
public:
    // options: the sections, and the face colours a body's cap takes (its first
    // recoloured face's, else the body's own).
    SectionCaps(const Scene& scene, const RenderOptions& options, const PreliminaryMap& map);
    bool active() const { return sections_.active() && sections_.caps; }
    // Whether hit h of `ray`, through the map's pixel `pixel`, shows a cap
    // instead; then `cap` receives it.
    bool find(const PixelHit& h, const Ray& ray, size_t pixel, CapHit& cap) const;
    // The cap's colour before lighting: its body's, darkened, and hatched when asked.
    Color colour(const CapHit& cap, const Ray& ray) const;

private:
    const Scene& scene_;
    const Sections& sections_;
    const PreliminaryMap& map_;
    std::vector<std::optional<Color>> body_colors_;  // per body where a face of it is recoloured
};

// Open bodies that a section plane cuts (their map meshes have kept and
// removed vertices): cut without caps, counted in the statistics.
uint64_t open_bodies_cut(const Scene& scene, const Sections& sections, const std::vector<Vec3>& offsets = {});

}  // namespace nurbsrt
