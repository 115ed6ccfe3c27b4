#include "cli/scene_file.h"

#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

#include "cli/scene_placements.h"
#include "importer/isolated.h"
#include "core/error.h"
#include "core/io/scene_json.h"
#include "core/scene/scene_ops.h"

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

std::string read_text(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    std::ostringstream text;
    text << in.rdbuf();
    if (!in && !in.eof()) throw Error(ErrorCode::io, "cannot read '" + path + "'");
    return text.str();
}

// A CAD file, or the NURBS scene JSON that `nurbsrt convert` writes.
Scene import_one(const std::string& path, const LoadOptions& options, IsolationTimings* isolation) {
    if (is_scene_file(path)) {
        const std::string text = read_text(path);
        if (is_scene_json(text)) {
            Scene s = scene_from_json(text);
            s.source_name = fs::path(path).filename().string();
            return s;
        }
    }
    IsolationLimits limits;
    limits.time_limit_s = options.time_limit_s;
    if (!options.isolated) return import_file(path, options.import);
    IsolationTimings t;
    Scene scene = import_isolated(path, options.import, limits, &t);
    if (isolation) {
        isolation->prescan_ms += t.prescan_ms;
        isolation->isolation_ms += t.isolation_ms;
        isolation->transfer_ms += t.transfer_ms;
        isolation->total_ms += t.total_ms;
    }
    return scene;
}

}  // namespace

Scene load_models(const std::vector<std::string>& inputs, const LoadOptions& options, IsolationTimings* isolation) {
    std::vector<Placement> placements;
    for (const std::string& in : inputs) {
        std::string text;
        if (is_scene_file(in) && !is_scene_json(text = read_text(in))) {
            std::istringstream file(text);
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
            copy = import_one(p.file, options, isolation);
            imported.emplace(p.file, copy);
        }
        transform_scene(copy, p.xf);
        append_scene(result, copy);
    }
    return result;
}

}  // namespace nurbsrt::cli
