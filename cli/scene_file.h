// Loading what `nurbsrt render` is given: CAD files, or a small JSON scene file
// that lists CAD files with transforms, e.g. the paper's "27 Ducks":
//   {"models": [{"file": "duck.igs", "translate": [0, 0, 0], "rotate_deg": [0, 0, 90], "scale": 1}, ...]}
// Relative paths are taken from the JSON file's folder. Each distinct file is
// imported once; copies are transformed duplicates of its scene. A file (given
// or listed) may also be the NURBS scene JSON that `nurbsrt convert` writes
// (core/io/scene_json.h), read without OCCT.
#pragma once

#include <string>
#include <vector>

#include "importer/importer.h"
#include "importer/isolated.h"

namespace nurbsrt::cli {

struct LoadOptions {
    ImportOptions import;
    bool isolated = false;      // import each file in a child process
    double time_limit_s = 300;  // per file, when isolated
};

// Throws nurbsrt::Error (invalid_argument for a malformed scene file).
// `isolation`, when given, gets the isolated imports' time beside their
// stages (Scene::timings), summed over the files.
Scene load_models(const std::vector<std::string>& inputs, const LoadOptions& options,
                  IsolationTimings* isolation = nullptr);

}  // namespace nurbsrt::cli
