// The assembly tree of a scene as JSON, depth first, each node naming its parent
// by id: what `nurbsrt info --json` prints as `parts` and a stored file's summary
// carries (POST /v1/files), so that clients name parts as renders take them.
#pragma once

#include <nlohmann/json_fwd.hpp>

#include "core/scene/scene.h"

namespace nurbsrt {

// [{"id", "name", "parent" (id or null), "color" ([r, g, b] or null), "placement"
// (3x4 row-major), "faces", "bbox" ({min, max} or null), "face_ranges"}, ...]:
// face_ranges lists the faces the part places itself (not through a child) as
// [first, last] runs of face indices 1..N, the face AOV's numbers, so that a
// client maps a face under the pointer to its part.

nlohmann::json assembly_tree_json(const Scene& scene);

}  // namespace nurbsrt
