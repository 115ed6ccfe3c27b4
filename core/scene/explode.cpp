// Exploded views (explode.h).
#include "core/scene/explode.h"

#include <cmath>
#include <utility>
#include <vector>

#include "core/scene/scene_ops.h"

namespace nurbsrt {

const char* explode_level_name(ExplodeLevel l) { return l == ExplodeLevel::leaves ? "leaves" : "top"; }

std::optional<ExplodeLevel> parse_explode_level(std::string_view name) {
    for (ExplodeLevel l : {ExplodeLevel::top, ExplodeLevel::leaves})
        if (name == explode_level_name(l)) return l;
    return std::nullopt;
}

namespace {

// Per part: whether it heads a group of `level` (see the header).
std::vector<uint8_t> group_heads(const Scene& s, ExplodeLevel level) {
    const size_t n = s.parts.size();
    std::vector<int> children(n, 0), only_child(n, -1);
    std::vector<int> roots;
    for (size_t k = 0; k < n; ++k) {
        const int32_t p = s.parts[k].parent;
        if (p < 0) {
            roots.push_back(static_cast<int>(k));
        } else {
            ++children[static_cast<size_t>(p)];
            only_child[static_cast<size_t>(p)] = static_cast<int>(k);
        }
    }
    std::vector<uint8_t> head(n, 0);
    if (level == ExplodeLevel::leaves) {
        for (size_t k = 0; k < n; ++k) head[k] = children[k] == 0;
        return head;
    }
    if (roots.size() > 1) {
        for (int r : roots) head[static_cast<size_t>(r)] = 1;
        return head;
    }
    if (roots.empty()) return head;
    int node = roots[0];
    while (children[static_cast<size_t>(node)] == 1) node = only_child[static_cast<size_t>(node)];
    for (size_t k = 0; k < n; ++k) head[k] = s.parts[k].parent == node;
    return head;
}

// Per body: its group (a part heading one, or the body itself without a tree),
// -1 for none.
std::vector<int64_t> body_groups(const Scene& scene, const std::vector<uint8_t>& head) {
    std::vector<int64_t> group(scene.bodies.size(), -1);
    for (size_t b = 0; b < scene.bodies.size(); ++b) {
        int32_t p = scene.bodies[b].part;
        while (p >= 0 && !head[static_cast<size_t>(p)]) p = scene.parts[static_cast<size_t>(p)].parent;
        group[b] = p >= 0 ? p : (scene.parts.empty() ? static_cast<int64_t>(scene.parts.size() + b) : -1);
    }
    return group;
}

// Per group: its offset (zero for a group at the centre or without faces).
std::vector<Vec3> group_offsets(const Scene& scene, const std::vector<int64_t>& group, double factor, size_t& moved) {
    const size_t ngroups = scene.parts.size() + scene.bodies.size();
    std::vector<BBox> box(ngroups);
    for (const Face& f : scene.faces)
        if (f.body < group.size() && group[f.body] >= 0)
            for (const Vec3& p : f.mesh.xyz) box[static_cast<size_t>(group[f.body])].extend(p);
    const Vec3 centre = scene.bbox.center();
    const double size = scene.bbox.diagonal();
    std::vector<Vec3> offset(ngroups, Vec3{0, 0, 0});
    moved = 0;
    for (size_t g = 0; g < ngroups; ++g) {
        if (box[g].empty()) continue;
        const Vec3 d = box[g].center() - centre;
        // A group centred on the assembly has no direction to move in.
        if (!(length(d) > 1e-9 * size)) continue;
        offset[g] = (factor * size / length(d)) * d;
        ++moved;
    }
    return offset;
}

// The groups of `level`, their offsets and each face's.
struct Explosion {
    std::vector<uint8_t> head;       // per part: heads a group
    std::vector<Vec3> group_offset;  // per group
    std::vector<Vec3> face_offset;   // per face; empty when nothing moves
    size_t moved = 0;
};

Explosion explosion(const Scene& scene, double factor, ExplodeLevel level) {
    Explosion e;
    if (!(factor > 0) || scene.bbox.empty()) return e;
    e.head = group_heads(scene, level);
    const std::vector<int64_t> group = body_groups(scene, e.head);
    e.group_offset = group_offsets(scene, group, factor, e.moved);
    if (e.moved == 0) return e;
    e.face_offset.reserve(scene.faces.size());
    for (const Face& f : scene.faces)
        e.face_offset.push_back(f.body < group.size() && group[f.body] >= 0
                                    ? e.group_offset[static_cast<size_t>(group[f.body])]
                                    : Vec3{0, 0, 0});
    return e;
}

}  // namespace

std::vector<Vec3> explode_offsets(const Scene& scene, double factor, ExplodeLevel level, size_t* moved) {
    Explosion e = explosion(scene, factor, level);
    if (moved) *moved = e.moved;
    return std::move(e.face_offset);
}

BBox moved_bbox(const Scene& scene, const std::vector<Vec3>& offsets) {
    if (offsets.empty()) return scene.bbox;
    BBox all;
    for (size_t i = 0; i < scene.faces.size(); ++i)
        for (const Vec3& p : scene.faces[i].mesh.xyz) all.extend(p + offsets[i]);
    return all.empty() ? scene.bbox : all;
}

size_t explode_scene(Scene& scene, double factor, ExplodeLevel level) {
    const Explosion e = explosion(scene, factor, level);
    if (e.face_offset.empty()) return 0;
    scene.bbox = moved_bbox(scene, e.face_offset);
    for (size_t i = 0; i < scene.faces.size(); ++i) {
        const Affine move = Affine::translation(e.face_offset[i]);
        for (Vec4& p : scene.faces[i].surface.cp) p = move.apply_h(p);
        for (Vec3& p : scene.faces[i].mesh.xyz) p = move.apply(p);
    }
    // Placements: a part's moves with its group (itself or its nearest head).
    for (size_t k = 0; k < scene.parts.size(); ++k) {
        int32_t p = static_cast<int32_t>(k);
        while (p >= 0 && !e.head[static_cast<size_t>(p)]) p = scene.parts[static_cast<size_t>(p)].parent;
        if (p < 0) continue;
        const Vec3 t = e.group_offset[static_cast<size_t>(p)];
        scene.parts[k].placement = (Affine::translation(t) * Affine{scene.parts[k].placement}).m;
    }
    summarize_parts(scene);
    return e.moved;
}

}  // namespace nurbsrt
