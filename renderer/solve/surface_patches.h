// A surface's polynomial pieces in power form: on each pair of non-empty knot
// spans (k, l) the NURBS surface's homogeneous points are one polynomial
// patch, S(x, y) = sum_{a <= p, b <= q} C_ab x^a y^b in the spans' local
// parameters x, y in [-1, 1] (span_basis.h). Its coefficients are the span
// tables' basis coefficients contracted with the control points once, by
// prepare(): C_ab = sum_i sum_j c_u[i][a] c_v[j][b] P_ij (the conversion to
// piecewise power form of Piegl & Tiller, The NURBS Book, sec. 6.6). A Newton
// step then evaluates the point and both partials by Horner's rule (A1.1) on C
// alone, nested in y and x: about 2 (p+1) q + 3 p Vec4 multiply-adds, where the
// basis tables take 2 (p+1)^2 + 2 (q+1)^2 scalar ones for the basis and then
// 3 (p+1)(q+1) Vec4 ones for the tensor product. The projection of a frame
// (Camera::project_h) is linear in homogeneous coordinates, so the projected
// surface's patches are the projected coefficients (project_patches below).
#pragma once

#include <cstddef>
#include <vector>

#include "renderer/camera.h"
#include "renderer/solve/span_basis.h"

namespace nurbsrt {

struct SurfacePatches {
    int degree_u = 0, degree_v = 0;
    size_t spans_v = 0;      // non-empty v spans (the patches' row length)
    std::vector<Vec4> coef;  // per patch (k, l), at (k spans_v + l) (p+1)(q+1): C_ab at a (q+1) + b
    bool usable() const { return !coef.empty(); }
    size_t memory_bytes() const { return coef.capacity() * sizeof(Vec4); }
};

// The patches of s over its span tables; empty (not usable) where the tables
// are not, or where they would hold more than kMaxPatchCoefficients (the basis
// tables then serve: evaluate_d1 in span_basis.h).
SurfacePatches make_surface_patches(const NurbsSurface& s, const SurfaceSpans& spans);
// The number of coefficients make_surface_patches would make (0: none).
size_t patch_coefficients(const NurbsSurface& s, const SurfaceSpans& spans);

// evaluate_d1 (nurbs.h) from the patches: the same point and partials to
// rounding. spans: those the patches were made over (any surface with the same
// knots and degrees: the model surface's serve its projection's patches).
SurfaceDerivs evaluate_d1(const SurfacePatches& patches, const SurfaceSpans& spans, double u, double v);

// A surface's homogeneous point and partials by the cheapest way it offers:
// its power-form patches, else its span tables, else the knot search and A2.2
// (nurbs.h). The one place that chooses among them.
struct SurfaceEvaluation {
    const NurbsSurface& surface;
    const SurfaceSpans* spans;
    const SurfacePatches* patches;
    // Either pointer may be null; patches count only when usable and with spans.
    SurfaceEvaluation(const NurbsSurface& s, const SurfaceSpans* sp, const SurfacePatches* pa)
        : surface(s), spans(sp), patches(sp && pa && pa->usable() ? pa : nullptr) {}
    SurfaceDerivs d1(double u, double v) const {
        if (patches) return evaluate_d1(*patches, *spans, u, v);
        return spans ? evaluate_d1(surface, *spans, u, v) : evaluate_d1(surface, u, v);
    }
    // The Cartesian point and partials (cartesian_d1, nurbs.h) the same way.
    CartesianDerivs cartesian(double u, double v) const { return cartesian_from(d1(u, v)); }
};

// The patches of project_surface(camera, s) from those of s, made once per frame.
SurfacePatches project_patches(const Camera& camera, const SurfacePatches& patches);

}  // namespace nurbsrt
