#include "cli/scene_placements.h"

#include <nlohmann/json.hpp>

#include <filesystem>

#include "core/error.h"
#include "core/json_limits.h"

namespace nurbsrt::cli {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

Vec3 vec3_of(const json& j, const char* key, Vec3 fallback) {
    if (!j.contains(key)) return fallback;
    const json& a = j.at(key);
    if (!a.is_array() || a.size() != 3 || !a[0].is_number() || !a[1].is_number() || !a[2].is_number())
        throw Error(ErrorCode::invalid_argument, std::string("scene file: '") + key + "' must be [x, y, z]");
    return {a[0].get<double>(), a[1].get<double>(), a[2].get<double>()};
}

}  // namespace

std::vector<Placement> parse_scene_file(std::istream& in, const std::string& path) {
    const std::string text(std::istreambuf_iterator<char>(in), {});
    const BoundedJson parsed = parse_json_bounded(text, kDocumentJsonLimits);
    if (!parsed.ok()) throw Error(ErrorCode::invalid_argument, "scene file " + path + ": " + parsed.detail);
    const json& doc = parsed.value;
    if (!doc.is_object() || !doc.contains("models") || !doc["models"].is_array() || doc["models"].empty())
        throw Error(ErrorCode::invalid_argument, "scene file " + path + ": needs a non-empty \"models\" array");
    const fs::path base = fs::path(path).parent_path();
    std::vector<Placement> out;
    for (const json& m : doc["models"]) {
        if (!m.is_object() || !m.contains("file") || !m["file"].is_string())
            throw Error(ErrorCode::invalid_argument, "scene file " + path + ": every model needs a \"file\"");
        fs::path file = m["file"].get<std::string>();
        if (file.is_relative()) file = base / file;
        // Checked before it is read: nlohmann's value() throws its own type_error
        // for "scale": "2", which is not the invalid_argument callers handle.
        const json scale_json = m.contains("scale") ? m.at("scale") : json(1.0);
        if (!scale_json.is_number()) throw Error(ErrorCode::invalid_argument, "scene file: 'scale' must be a number");
        const double scale = scale_json.get<double>();
        if (!(scale > 0)) throw Error(ErrorCode::invalid_argument, "scene file: 'scale' must be positive");
        // p' = T R S p: scale about the model origin, rotate, then place.
        const Affine xf = Affine::translation(vec3_of(m, "translate", {})) *
                          Affine::rotation_xyz_deg(vec3_of(m, "rotate_deg", {})) * Affine::scaling(scale);
        out.push_back({file.string(), xf});
    }
    return out;
}

}  // namespace nurbsrt::cli
