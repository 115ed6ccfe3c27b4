#include "cli/scene_file.h"

#include <filesystem>
#include <fstream>
#include <map>

#include "cli/scene_placements.h"
#include "importer/isolated.h"
#include "renderer/error.h"
#include "renderer/scene_ops.h"

namespace nurbsrt::cli {
namespace {

namespace fs = std::filesystem;

bool is_scene_file(const std::string& path) {
    if (fs::path(path).extension() == ".json") return true;
    std::ifstream in(path, std::ios::binary);
    char c = 0;
    while (in.get(c) && std::isspace(static_cast<unsigned char>(c))) {}
    return c == '{';
}

}  // namespace

Scene load_models(const std::vector<std::string>& inputs, const LoadOptions& options) {
    std::vector<Placement> placements;
    for (const std::string& in : inputs) {
        if (is_scene_file(in)) {
            std::ifstream file(in);
            for (Placement& p : parse_scene_file(file, in)) placements.push_back(std::move(p));
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
