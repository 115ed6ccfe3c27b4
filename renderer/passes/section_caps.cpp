// Caps of cut closed bodies (section_caps.h).
#include "renderer/passes/section_caps.h"

#include <cmath>
#include <vector>

#include "core/scene/nurbs.h"
#include "renderer/map/preliminary_map.h"

namespace nurbsrt {

namespace {

// A cap is its body's colour darkened, so that the cut face reads apart from the
// body's lit outside at any light angle (drawings shade cut faces likewise).
constexpr float kCapShade = 0.7f;
// Hatching (Sections::hatch): lines at 45 degrees in the plane, this many across
// the scene's diagonal, each kHatchDuty of its period wide and this much darker.
constexpr double kHatchLinesPerDiagonal = 60;
constexpr double kHatchDuty = 0.18;
constexpr float kHatchShade = 0.45f;

// Two unit axes in the plane of normal n.
void plane_axes(Vec3 n, Vec3& a, Vec3& b) {
    const Vec3 helper = std::fabs(n.x) < 0.9 ? Vec3{1, 0, 0} : Vec3{0, 1, 0};
    a = normalize(cross(n, helper));
    b = cross(n, a);
}

}  // namespace

SectionCaps::SectionCaps(const Scene& scene, const RenderOptions& options, const PreliminaryMap& map)
    : scene_(scene), sections_(options.sections), map_(map) {
    if (!active() || options.face_colors.empty()) return;
    body_colors_.assign(scene.bodies.size(), std::nullopt);
    for (size_t i = 0; i < scene.faces.size() && i < options.face_colors.size(); ++i) {
        const uint32_t b = scene.faces[i].body;
        if (b < body_colors_.size() && !body_colors_[b] && options.face_colors[i])
            body_colors_[b] = options.face_colors[i];
    }
}

bool SectionCaps::find(const PixelHit& h, const Ray& ray, size_t pixel, CapHit& cap) const {
    if (!active() || !h.face) return false;
    const Face& f = scene_.faces[h.face - 1];
    uint32_t body = f.body;
    bool inside = false;
    if (body < scene_.bodies.size() && scene_.bodies[body].closed) {
        Vec3 n{h.nx, h.ny, h.nz};  // oriented outward by the face (pixel_solver.cpp set_hit)
        if (n.x == 0 && n.y == 0 && n.z == 0) n = surface_normal(f.surface, h.u, h.v, f.reversed);
        inside = dot(n, ray.dir) > 0;  // the inside of the body, exactly
    }
    if (!inside && pixel < map_.inside.size() && map_.inside[pixel] != 0 && map_.inside[pixel] != body + 1 &&
        map_.inside[pixel] <= scene_.bodies.size()) {
        // The outside of another body, where the inside layer says the ray
        // entered this one: they touch there (see the header).
        body = map_.inside[pixel] - 1;
        inside = scene_.bodies[body].closed;
    }
    if (!inside) return false;
    const std::optional<Sections::Entry> entry = sections_.entry_before(ray, h.t);
    if (!entry) return false;
    cap.t = entry->t;
    cap.plane = entry->plane;
    cap.body = body;
    cap.normal = sections_.planes[static_cast<size_t>(entry->plane)].normal;
    if (dot(cap.normal, ray.dir) > 0) cap.normal = -cap.normal;
    return true;
}

Color SectionCaps::colour(const CapHit& cap, const Ray& ray) const {
    const Body& body = scene_.bodies[cap.body];
    Color c = body.has_color ? body.color : Color{};
    if (cap.body < body_colors_.size() && body_colors_[cap.body]) c = *body_colors_[cap.body];
    float shade = kCapShade;
    if (sections_.hatch) {
        const SectionPlane& plane = sections_.planes[static_cast<size_t>(cap.plane)];
        Vec3 a, b;
        plane_axes(plane.normal, a, b);
        const Vec3 p = ray.origin + cap.t * ray.dir - plane.point;
        const double period = std::max(scene_.bbox.diagonal(), 1e-12) / kHatchLinesPerDiagonal;
        const double phase = (dot(p, a) + dot(p, b)) / (std::sqrt(2.0) * period);
        if (phase - std::floor(phase) < kHatchDuty) shade *= kHatchShade;
    }
    return {c.r * shade, c.g * shade, c.b * shade};
}

uint64_t open_bodies_cut(const Scene& scene, const Sections& sections, const std::vector<Vec3>& offsets) {
    if (!sections.active()) return 0;
    // Per body: 1 has a kept vertex, 2 a removed one.
    std::vector<uint8_t> sides(scene.bodies.size(), 0);
    for (size_t i = 0; i < scene.faces.size(); ++i) {
        const Face& f = scene.faces[i];
        if (f.body >= scene.bodies.size() || scene.bodies[f.body].closed) continue;
        const Vec3 t = offsets.empty() ? Vec3{0, 0, 0} : offsets[i];
        for (const Vec3& p : f.mesh.xyz) sides[f.body] |= sections.removes(p + t) ? 2 : 1;
    }
    uint64_t n = 0;
    for (uint8_t s : sides) n += s == 3;
    return n;
}

}  // namespace nurbsrt
