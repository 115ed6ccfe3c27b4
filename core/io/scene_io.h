// Compact binary serialization of a Scene, so that an import can run in a child
// process and hand its scene back, and so that imported scenes can be cached.
//
// Format (all integers and doubles little-endian, as on every supported host):
//   "NRBSCENE" (8 bytes) | u32 format version | u64 payload size | payload | u64 FNV-1a of payload
// The reader checks magic, version, sizes against the bytes actually present,
// and the checksum; anything off throws Error(ErrorCode::corrupt_scene), never
// reads out of bounds and never allocates more than the input could describe.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "core/scene/scene.h"

namespace nurbsrt {

// 2: bodies name their part, and the assembly tree (Scene::parts) follows them.
// 3: bodies say whether they are closed (Body::closed).
constexpr unsigned kSceneFormatVersion = 3;

std::string serialize_scene(const Scene& scene);
// The format's checksum of the payload (FNV-1a, 64 bits), stored after it.
uint64_t scene_checksum(const char* payload, size_t n);
Scene deserialize_scene(const std::string& bytes);

// File helpers (throw Error(ErrorCode::io) when the file cannot be written/read).
void write_scene_file(const Scene& scene, const std::string& path);
Scene read_scene_file(const std::string& path);

}  // namespace nurbsrt
