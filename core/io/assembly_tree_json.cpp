// The assembly tree as JSON (assembly_tree_json.h).
#include "core/io/assembly_tree_json.h"

#include <vector>

#include <nlohmann/json.hpp>

namespace nurbsrt {
namespace {

nlohmann::json vec_json(Vec3 v) { return nlohmann::json::array({v.x, v.y, v.z}); }

// Per part, the runs [first, last] (1-based face indices) of the faces whose
// body it places.
std::vector<nlohmann::json> own_face_ranges(const Scene& scene) {
    std::vector<nlohmann::json> ranges(scene.parts.size(), nlohmann::json::array());
    for (size_t i = 0; i < scene.faces.size(); ++i) {
        const uint32_t body = scene.faces[i].body;
        if (body >= scene.bodies.size()) continue;
        const int32_t part = scene.bodies[body].part;
        if (part < 0 || static_cast<size_t>(part) >= scene.parts.size()) continue;
        nlohmann::json& runs = ranges[static_cast<size_t>(part)];
        const auto index = static_cast<uint64_t>(i + 1);
        if (!runs.empty() && runs.back()[1].get<uint64_t>() + 1 == index)
            runs.back()[1] = index;
        else
            runs.push_back({index, index});
    }
    return ranges;
}

}  // namespace

nlohmann::json assembly_tree_json(const Scene& scene) {
    using nlohmann::json;
    json parts = json::array();
    const std::vector<json> ranges = own_face_ranges(scene);
    for (size_t k = 0; k < scene.parts.size(); ++k) {
        const Part& p = scene.parts[k];
        const json color = p.has_color ? json::array({p.color.r, p.color.g, p.color.b}) : json(nullptr);
        const json bbox =
            p.bbox.empty() ? json(nullptr) : json{{"min", vec_json(p.bbox.lo)}, {"max", vec_json(p.bbox.hi)}};
        parts.push_back({{"id", p.id},
                         {"name", p.name},
                         {"parent", p.parent < 0 ? json(nullptr) : json(scene.parts[static_cast<size_t>(p.parent)].id)},
                         {"color", color},
                         {"placement", p.placement},
                         {"faces", p.faces},
                         {"bbox", bbox},
                         {"face_ranges", ranges[k]}});
    }
    return parts;
}

}  // namespace nurbsrt
