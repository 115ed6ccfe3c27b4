// Per-face cameras of moved faces (face_cameras.h).
#include "renderer/frame/face_cameras.h"

#include <map>
#include <tuple>

namespace nurbsrt {

FaceCameras::FaceCameras(const Camera& base, const std::vector<Vec3>& offsets) : base_(base) {
    if (offsets.empty()) return;
    std::map<std::tuple<double, double, double>, uint32_t> index;  // exact offsets: a group's are equal
    group_.reserve(offsets.size());
    for (const Vec3& t : offsets) {
        const auto [it, added] = index.try_emplace({t.x, t.y, t.z}, static_cast<uint32_t>(cameras_.size()));
        if (added) {
            CameraSpec spec = base.spec();
            spec.eye = spec.eye - t;
            spec.target = spec.target - t;
            cameras_.emplace_back(spec);
        }
        group_.push_back(it->second);
    }
}

}  // namespace nurbsrt
