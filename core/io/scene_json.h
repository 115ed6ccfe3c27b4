// The Scene as a JSON document: every face's exact NURBS patch (degrees, knots,
// homogeneous control points), its trim loops and attributes, for tools outside
// nurbsrt. `nurbsrt convert IN OUT.json` and POST /v1/conversions?format=json
// write it; `nurbsrt render OUT.json` reads it back (scene_json_read.cpp). The document is described by api_schema/nurbs_scene.schema.json
// (draft 2020-12); keep the two in step.
//
// JSON has no NaN or infinity: a non-finite number (which a sane import never
// produces, but a corrupt one might) is written as null, so the output always
// parses; the schema allows null exactly where numbers are.
#pragma once

#include <ostream>
#include <string>

#include "core/scene/scene.h"

namespace nurbsrt {

// Identifies the document; bumped when a field changes meaning or disappears.
inline constexpr const char* kSceneJsonFormat = "nurbsrt-nurbs-scene";
inline constexpr int kSceneJsonVersion = 1;

// Compact (indent < 0) or pretty-printed JSON text of the scene.
std::string scene_to_json(const Scene& scene, int indent = -1);
// Streams the same text; throws Error(io) when the stream fails.
void write_scene_json(const Scene& scene, std::ostream& out);
// Writes the JSON to `path`; throws Error(io) when it cannot be written.
void write_scene_json_file(const Scene& scene, const std::string& path);

// True when `text` is a JSON document of this format (any version).
bool is_scene_json(const std::string& text);
// The scene a document of this format describes, for rendering: faces are
// numbered by their position, and each gets a trimmed (u,v) grid as its
// preliminary-map mesh (the document carries no mesh). Throws
// Error(invalid_argument) naming the first bad field, or Error(corrupt_scene)
// for geometry the renderer cannot take (knot counts, control point counts).
Scene scene_from_json(const std::string& text);

}  // namespace nurbsrt
