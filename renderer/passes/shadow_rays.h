// Exact shadows from the key light, by the paper's own method turned towards the
// light (Sisojevs & Glazs 2010, "Preprocessing" and eq. 3-12, with the light as
// the camera): a second preliminary map, rendered from the key light's point of
// view, gives a shaded point the faces near it as the light sees them, each with
// a (u, v) start; Newton along the light ray through the point finds where those
// faces cross the ray, and a hit inside a trim between the point and the light
// blocks it.
//
// The decision is the light ray's exact intersection, not a comparison with a
// depth buffer. A shadow map compares the point's depth with a depth sampled at
// the map's resolution and needs a bias: too small and a lit surface shadows
// itself in stripes (acne), too large and light leaks under contact. Here the
// only tolerance is the solve's own (12): the point's own surface crosses the
// light ray at the point itself, within the solve tolerance divided by the
// cosine between the normal and the light (a plane's crossing moves that much
// along the ray when the plane moves by the tolerance), and only crossings
// beyond a few of those count.
#pragma once

#include <atomic>
#include <cstdint>
#include <vector>

#include "renderer/frame/frame.h"
#include "renderer/frame/mesh_screen_points.h"
#include "renderer/frame/pixel_solver.h"

namespace nurbsrt {

// The light map's size (square) for a view of width x height.
int light_map_size(int width, int height);

class KeyLightShadows {
public:
    // Renders the light's map: a square orthographic view along the key light
    // framing the scene's bounding sphere, about as many pixels across as the
    // view (its pixels then cover about as much of the model as the view's).
    // The solves use the view's method and tolerances.
    KeyLightShadows(const FrameContext& view, const Solver& view_solver, Vec3 key);
    KeyLightShadows(const KeyLightShadows&) = delete;  // its members refer to each other
    KeyLightShadows& operator=(const KeyLightShadows&) = delete;

    // Whether a face blocks the key light at surface point p, at (u, v) of
    // face `face`, with shading normal n. False where the point faces away from
    // the light: the shading gives it no key light anyway.
    bool blocked(Vec3 p, Vec3 n, uint32_t face, double u, double v) const;

    uint64_t rays() const { return rays_.load(std::memory_order_relaxed); }  // Newton solves so far
    int map_size() const { return size_; }

private:
    static CameraSpec light_view(const BBox& box, Vec3 key, int size);
    // Whether the map's pixel (ci, cj) shows face `face` at (u, v) itself (see the .cpp).
    bool own_face_first(int ci, int cj, uint32_t face, double u, double v) const;
    // Model units per unit of (u, v) on face id at hit h: the surface's faster
    // speed there (the larger of |Pu| and |Pv|).
    double speed(uint32_t id, const PixelHit& h) const;
    Vec3 key_;
    int size_;
    Camera camera_;
    FaceCameras face_cameras_;  // the light's camera per moved face (face_cameras.h)
    PreliminaryMap map_;
    std::function<void(double)> no_progress_;
    Progress progress_;
    FrameContext ctx_;
    ProjectedFaces projected_;
    Solver solver_;
    MeshScreenPoints screen_points_;  // the map mesh in the light's view: starts on faces no map pixel shows
    double contact_;                  // one light-map pixel, model units
    mutable std::atomic<uint64_t> rays_{0};
};

}  // namespace nurbsrt
