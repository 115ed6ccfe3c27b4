// Prepare once, render many: everything a frame needs of a Scene that does not
// depend on the camera, built once by prepare() and then only read by any number
// of frames, from any number of threads at once (the split of Embree's
// rtcCommitScene / rtcIntersect). Per face: the trim test's acceleration grid,
// the parameter box with its seams, the trim-tolerance band; for the preliminary
// map: every face's map mesh merged into one indexed triangle list with its
// per-vertex (u, v) and face id (a frame only transforms the positions).
//
// What stays per frame (render.cpp): the projection of the patches' coefficients
// (proposed), the preliminary map itself, the screen positions of mesh vertices
// for the rescue's start search: all depend on the camera.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

#include "core/scene/scene.h"

namespace nurbsrt {

// The renderer's own camera-independent data: solve/prepared_data.h.
struct PreparedFace;
struct MapMesh;
struct PreparedData;

class PreparedScene {
public:
    PreparedScene(PreparedScene&&) noexcept;
    PreparedScene& operator=(PreparedScene&&) noexcept;
    ~PreparedScene();
    PreparedScene(const PreparedScene&) = delete;
    PreparedScene& operator=(const PreparedScene&) = delete;

    const Scene& scene() const { return *scene_; }
    // Defined in solve/prepared_data.h, which the renderer's rooms include.
    inline const std::vector<PreparedFace>& faces() const;
    inline const MapMesh& map_mesh() const;
    // Unique per prepare() call in this process (never reused, unlike an
    // address): lets a GL context keep this scene's map mesh uploaded between frames.
    uint64_t id() const { return id_; }
    // Wall-clock time prepare() took, milliseconds.
    double prepare_ms() const { return prepare_ms_; }
    // Approximate heap memory of the prepared data (not counting the Scene).
    size_t memory_bytes() const;

private:
    friend struct PreparedSceneBuilder;  // prepared_scene.cpp
    PreparedScene();

    const Scene* scene_ = nullptr;
    std::shared_ptr<const Scene> owner_;  // set when prepare() was given shared ownership
    std::unique_ptr<PreparedData> data_;
    uint64_t id_ = 0;
    double prepare_ms_ = 0;
};

// Builds the prepared data with up to `threads` threads (0: all hardware
// threads); the result does not depend on the thread count. Throws
// Error(invalid_argument) unless faces[i].index == i + 1.
// The first form refers to `scene`, which must outlive the result and not
// change; the second keeps the scene alive itself.
PreparedScene prepare(const Scene& scene, int threads = 0);
PreparedScene prepare(std::shared_ptr<const Scene> scene, int threads = 0);

}  // namespace nurbsrt
