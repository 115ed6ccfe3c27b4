// Section planes: half-spaces of the model removed from a frame, so that its
// inside shows. Each plane removes the side its normal points to; several planes
// remove the union of their half-spaces (SectionMode::union_of) or only their
// intersection (SectionMode::cutaway, the classic quarter cut-away of two or
// three planes). The removal is exact: the Newton acceptance test rejects a root
// on a removed side like one outside the trim (the plane joins the trimming as a
// constraint of the hit), and the preliminary map drops removed fragments, so
// the map's starts lie on the first kept surface.
//
// Caps: where the first kept hit of a ray is the inside of a closed body
// (Body::closed, the hit's outward normal turned away from the viewer), the ray
// entered that body through a section plane: the pixel shows the plane there
// (renderer/passes/section_caps.h), not the body's far wall.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string_view>
#include <vector>

#include "core/vec.h"
#include "renderer/camera.h"

namespace nurbsrt {

enum class SectionMode : uint8_t { union_of, cutaway };
const char* section_mode_name(SectionMode m);  // "union", "cutaway"
std::optional<SectionMode> parse_section_mode(std::string_view name);

// A plane through `point`; `normal` (unit) points into the removed half-space.
struct SectionPlane {
    Vec3 point;
    Vec3 normal{0, 0, 1};
    // Signed distance of p from the plane, positive on the removed side.
    double distance(Vec3 p) const { return dot(p - point, normal); }
};

// A CAD section shows one plane or a cut-away corner of up to three, and a few
// more for slabs and boxes; the map carries one clip distance per plane in six
// vertex attribute components (preliminary_map.cpp).
inline constexpr size_t kMaxSectionPlanes = 6;

struct Sections {
    std::vector<SectionPlane> planes;  // at most kMaxSectionPlanes, unit normals
    SectionMode mode = SectionMode::union_of;
    bool caps = true;    // caps on closed bodies (false: cut open, the insides show)
    bool hatch = false;  // hatching lines over the caps, as in a drawing's section view

    bool active() const { return !planes.empty(); }
    // Whether point p is removed.
    bool removes(Vec3 p) const;

    // Where a ray last passes from removed into kept space before distance
    // t_limit (> 0): the distance along the ray and the plane it crosses there;
    // nullopt when it does not (the ray starts in kept space and stays there up
    // to t_limit, or enters it only at or behind the eye).
    struct Entry {
        double t = 0;
        int plane = -1;
    };
    std::optional<Entry> entry_before(const Ray& ray, double t_limit) const;
};

}  // namespace nurbsrt
