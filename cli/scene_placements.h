// The JSON scene file of `nurbsrt render` (see cli/scene_file.h): its models as
// file paths with placements. Only the text is read here, no CAD file, so the
// parser can be checked on its own.
#pragma once

#include <istream>
#include <string>
#include <vector>

#include "core/scene/scene_ops.h"

namespace nurbsrt::cli {

struct Placement {
    std::string file;  // relative paths are taken from the scene file's folder
    Affine xf;
};

// Parses the scene file text in `in`; `path` is the file's name (messages, and
// the folder of relative model paths). Throws Error(invalid_argument) for
// anything malformed.
std::vector<Placement> parse_scene_file(std::istream& in, const std::string& path);

}  // namespace nurbsrt::cli
