// Operations on whole Scenes: placing a copy under an affine transform and
// concatenating scenes (multi-model renders such as the 3x3x3 grid scene of Sisojevs & Glazs 2010).
#pragma once

#include <array>

#include "core/scene/scene.h"

namespace nurbsrt {

// Row-major 3x4 affine map p' = A p + t (the last row 0 0 0 1 is implied).
struct Affine {
    std::array<double, 12> m{1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0};

    static Affine translation(Vec3 t);
    static Affine scaling(double s);
    // Rotation by angles in degrees about X, then Y, then Z (p' = Rz Ry Rx p).
    static Affine rotation_xyz_deg(Vec3 deg);
    Affine operator*(const Affine& b) const;  // (this * b)(p) = this(b(p))
    Vec3 apply(Vec3 p) const;
    // On a homogeneous point (w x, w y, w z, w): A (w p) + t w, w unchanged, so a
    // rational surface maps exactly to the rational surface of the moved shape.
    Vec4 apply_h(Vec4 pw) const;
    // Determinant of A: a negative one mirrors, which flips face orientation.
    double determinant() const;
};

// Applies `xf` to every surface, mesh vertex and the box of `scene` in place;
// a mirroring transform toggles every face's `reversed` so normals stay outward.
void transform_scene(Scene& scene, const Affine& xf);

// Appends `src` to `dst`: faces renumbered after dst's (index contract: the
// concatenation order), bodies and parts appended (src's roots numbered after
// dst's in the part ids), boxes, timings and warnings merged.
void append_scene(Scene& dst, const Scene& src);

// Sets each part's face count and box from the faces of the bodies it places
// and of its children's (the importer calls it once its faces are meshed).
void summarize_parts(Scene& scene);

}  // namespace nurbsrt
