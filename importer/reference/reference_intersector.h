// The exact reference for pixel rays: OCCT's IntCurvesFace_ShapeIntersector on
// the ORIGINAL shape as the file defines it (planes, cylinders, offset surfaces,
// ... not our NURBS conversion), trimmed by OCCT's own face classifier; a B-spline
// face of many spans is searched as exact pieces of itself (ShapeUpgrade's
// division), each hit reported on its face. Shares no
// code with the renderer or the importer's conversion, so it serves both as the
// accuracy oracle of tests/render_accuracy_test.cpp and as the "exact peer" of
// `nurbsrt bench`. OCCT-free header: rays in, hits out.
#pragma once

#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "renderer/camera.h"
#include "core/scene/scene_ops.h"

namespace nurbsrt {

namespace occt {
struct OcctModel;
}

struct ReferenceHit {
    bool error = false;  // the intersector threw on this ray: no reference for it
    bool hit = false;
    double t = std::numeric_limits<double>::infinity();  // nearest hit distance along the ray
    int face = 0;  // face index of the contract (copies numbered as append_scene does)
};

class ReferenceIntersector {
public:
    // Tolerance given to IntCurvesFace_ShapeIntersector::Load: the 2D classification
    // tolerance of hits against face boundaries. Precision::Confusion() (1e-7 mm)
    // keeps the trimming sharp.
    static constexpr double kDefaultTolerance = 1e-7;

    // Reads `path` (STEP/IGES by content). `placements`: one copy of the shape per
    // transform, faces numbered copy after copy like append_scene (empty: the file
    // as it is). Throws nurbsrt::Error (reading; invalid_argument for a placement
    // that is not a rigid motion: OCCT locations cannot scale, mirror or shear).
    explicit ReferenceIntersector(const std::string& path, const std::vector<Affine>& placements = {},
                                  double tolerance = kDefaultTolerance);
    // On a model already read (tests that also settle disputes on its faces).
    explicit ReferenceIntersector(const occt::OcctModel& model, double tolerance = kDefaultTolerance);
    ~ReferenceIntersector();
    ReferenceIntersector(const ReferenceIntersector&) = delete;
    ReferenceIntersector& operator=(const ReferenceIntersector&) = delete;

    // Nearest hit with 0 < t < t_max. Not thread-safe (the intersector keeps state).
    ReferenceHit cast(const Ray& ray, double t_max);
    int faces() const;
    double read_ms() const;  // reading the file (0 when constructed from a model)
    double load_ms() const;  // IntCurvesFace_ShapeIntersector::Load (classifier set-up)

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

}  // namespace nurbsrt
