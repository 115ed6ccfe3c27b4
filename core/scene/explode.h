// Exploded views of an assembly: each group of parts moved away from the
// assembly's centre, along the line from that centre to the group's, by a
// factor of the assembly's size. Groups are the top-level parts (the children
// of the first node of the tree that has several; the roots of a scene of
// several files) or the leaf parts; a file read without its tree explodes by
// body. The faces move rigidly (control points, map meshes, placements), so a
// moved scene renders as exactly as the file's.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string_view>

#include "core/scene/scene.h"

namespace nurbsrt {

enum class ExplodeLevel : uint8_t { top, leaves };
const char* explode_level_name(ExplodeLevel l);  // "top", "leaves"
std::optional<ExplodeLevel> parse_explode_level(std::string_view name);

// The largest factor: ten assembly sizes apart is already parts out of sight
// of each other; more is a mistake.
inline constexpr double kMaxExplode = 10;

// Moves the groups of `level` by factor x the scene's box diagonal; returns how
// many groups moved (a group at the centre stays). factor 0 changes nothing.
size_t explode_scene(Scene& scene, double factor, ExplodeLevel level);

}  // namespace nurbsrt
