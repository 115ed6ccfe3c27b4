#include "cli/scene_file.h"

#include <nlohmann/json.hpp>

#include <filesystem>
#include <fstream>
#include <map>

#include "importer/isolated.h"
#include "renderer/error.h"
#include "renderer/scene_ops.h"

namespace nurbsrt::cli {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

bool is_scene_file(const std::string& path) {
    if (fs::path(path).extension() == ".json") return true;
    std::ifstream in(path, std::ios::binary);
    char c = 0;
    while (in.get(c) && std::isspace(static_cast<unsigned char>(c))) {}
    return c == '{';
}

Vec3 vec3_of(const json& j, const char* key, Vec3 fallback) {
    if (!j.contains(key)) return fallback;
    const json& a = j.at(key);
    if (!a.is_array() || a.size() != 3 || !a[0].is_number() || !a[1].is_number() || !a[2].is_number())
        throw Error(ErrorCode::invalid_argument, std::string("scene file: '") + key + "' must be [x, y, z]");
    return {a[0].get<double>(), a[1].get<double>(), a[2].get<double>()};
}

struct Placement {
    std::string file;
    Affine xf;
};

std::vector<Placement> read_scene_file_entries(const std::string& path) {
    std::ifstream in(path);
    json doc;
    try {
        doc = json::parse(in);
    } catch (const json::exception& e) {
        throw Error(ErrorCode::invalid_argument, "scene file " + path + ": " + e.what());
    }
    if (!doc.is_object() || !doc.contains("models") || !doc["models"].is_array() || doc["models"].empty())
        throw Error(ErrorCode::invalid_argument, "scene file " + path + ": needs a non-empty \"models\" array");
    const fs::path base = fs::path(path).parent_path();
    std::vector<Placement> out;
    for (const json& m : doc["models"]) {
        if (!m.is_object() || !m.contains("file") || !m["file"].is_string())
            throw Error(ErrorCode::invalid_argument, "scene file " + path + ": every model needs a \"file\"");
        fs::path file = m["file"].get<std::string>();
        if (file.is_relative()) file = base / file;
        const double scale = m.value("scale", 1.0);
        if (!(scale > 0)) throw Error(ErrorCode::invalid_argument, "scene file: 'scale' must be positive");
        // p' = T R S p: scale about the model origin, rotate, then place.
        const Affine xf = Affine::translation(vec3_of(m, "translate", {})) *
                          Affine::rotation_xyz_deg(vec3_of(m, "rotate_deg", {})) * Affine::scaling(scale);
        out.push_back({file.string(), xf});
    }
    return out;
}

}  // namespace

Scene load_models(const std::vector<std::string>& inputs, const LoadOptions& options) {
    std::vector<Placement> placements;
    for (const std::string& in : inputs) {
        if (is_scene_file(in)) {
            for (Placement& p : read_scene_file_entries(in)) placements.push_back(std::move(p));
        } else {
            placements.push_back({in, Affine{}});
        }
    }
    std::map<std::string, Scene> imported;  // each distinct file is imported once
    Scene result;
    for (const Placement& p : placements) {
        Scene copy;
        if (auto it = imported.find(p.file); it != imported.end()) {
            copy = it->second;
            copy.timings = {};  // a further copy costs no import stage
        } else {
            IsolationLimits limits;
            limits.time_limit_s = options.time_limit_s;
            copy = options.isolated ? import_isolated(p.file, options.import, limits)
                                    : import_file(p.file, options.import);
            imported.emplace(p.file, copy);
        }
        transform_scene(copy, p.xf);
        append_scene(result, copy);
    }
    return result;
}

}  // namespace nurbsrt::cli
