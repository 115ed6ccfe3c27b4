// Faces drawn moved (RenderOptions::face_offsets: an exploded view) without
// moving their data: a face translated by t, seen by a camera, is the face in
// place seen by that camera translated by -t. So every solve of a face uses its
// own camera, one per distinct offset (the ray transform of Embree's instances),
// and one prepared scene serves every explode factor. Screen points and hit
// distances are the same for both cameras; world points are the frame camera's.
#pragma once

#include <cstdint>
#include <vector>

#include "core/vec.h"
#include "renderer/camera.h"

namespace nurbsrt {

class FaceCameras {
public:
    // `offsets`: per face (index - 1), or empty: every face uses `base`, which
    // must outlive this.
    FaceCameras(const Camera& base, const std::vector<Vec3>& offsets);
    FaceCameras(const FaceCameras&) = delete;
    FaceCameras& operator=(const FaceCameras&) = delete;

    const Camera& of(uint32_t id) const { return group_.empty() ? base_ : cameras_[group_[id - 1]]; }

private:
    const Camera& base_;
    std::vector<Camera> cameras_;  // per distinct offset
    std::vector<uint32_t> group_;  // per face: its camera; empty without offsets
};

}  // namespace nurbsrt
