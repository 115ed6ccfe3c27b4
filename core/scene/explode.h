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
#include <vector>

#include "core/scene/scene.h"

namespace nurbsrt {

enum class ExplodeLevel : uint8_t { top, leaves };
const char* explode_level_name(ExplodeLevel l);  // "top", "leaves"
std::optional<ExplodeLevel> parse_explode_level(std::string_view name);

// The largest factor: ten assembly sizes apart is already parts out of sight
// of each other; more is a mistake.
inline constexpr double kMaxExplode = 10;

// Per face (index - 1): how far the groups of `level` move, factor x the
// scene's box diagonal along centre -> group centre; empty when nothing moves
// (factor 0, or every group at the centre). `moved`: how many groups move.
// A renderer draws the faces translated by these without changing the scene
// (RenderOptions::face_offsets), so one prepared scene serves every factor.
std::vector<Vec3> explode_offsets(const Scene& scene, double factor, ExplodeLevel level, size_t* moved = nullptr);

// The box of the scene's faces moved by `offsets` (per face, or empty: the
// scene's own box).
BBox moved_bbox(const Scene& scene, const std::vector<Vec3>& offsets);

// Moves the geometry itself by explode_offsets: control points, map meshes,
// placements and the box; returns how many groups moved.
size_t explode_scene(Scene& scene, double factor, ExplodeLevel level);

}  // namespace nurbsrt
