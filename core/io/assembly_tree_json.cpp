// The assembly tree as JSON (assembly_tree_json.h).
#include "core/io/assembly_tree_json.h"

#include <nlohmann/json.hpp>

namespace nurbsrt {
namespace {

nlohmann::json vec_json(Vec3 v) { return nlohmann::json::array({v.x, v.y, v.z}); }

}  // namespace

nlohmann::json assembly_tree_json(const Scene& scene) {
    using nlohmann::json;
    json parts = json::array();
    for (const Part& p : scene.parts) {
        const json color = p.has_color ? json::array({p.color.r, p.color.g, p.color.b}) : json(nullptr);
        const json bbox =
            p.bbox.empty() ? json(nullptr) : json{{"min", vec_json(p.bbox.lo)}, {"max", vec_json(p.bbox.hi)}};
        parts.push_back({{"id", p.id},
                         {"name", p.name},
                         {"parent", p.parent < 0 ? json(nullptr) : json(scene.parts[static_cast<size_t>(p.parent)].id)},
                         {"color", color},
                         {"placement", p.placement},
                         {"faces", p.faces},
                         {"bbox", bbox}});
    }
    return parts;
}

}  // namespace nurbsrt
