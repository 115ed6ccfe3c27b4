// Per-pixel Newton iteration for the ray/patch intersection, two methods:
//
//  proposed  (Sisojevs & Glazs 2010, eq. 3, 8-11): on the patch projected into the image plane
//            (Camera::project_h; its (X, Y, D) are the paper's (x, y, w)), solve
//            F(u,v) = (X/D - xR, Y/D - yR) = 0 with the step
//              (du, dv) = (D / M) (M_U, M_V),                                  (9)
//            M = det[P, P_u, P_v], M_U = det[P, R, P_v], M_V = det[P, P_u, R]  (10, 11)
//            where P = (X, Y, D), R = (xR, yR, 1), columns. Only non-rational
//            (homogeneous) partials are needed. By Cramer's rule this equals the
//            textbook step -J^{-1} F of eq. (6)-(7) exactly (det J = M / D^3).
//  martin    (Martin et al. 2000): the ray is the intersection of two planes
//            N1.x + d1 = 0, N2.x + d2 = 0 (N1 perpendicular to the ray, N2 = N1 x dir,
//            both through the origin); F = (N1.C + d1, N2.C + d2) on the Cartesian
//            surface C = S / w, Jacobian from the rational partials
//            C_u = (S_u.xyz - C S_u.w) / w; step -J^{-1} F.
//
// Termination, identical rules for both methods (Sisojevs & Glazs 2010, "Termination Criteria"):
//   (12) success        ||F|| < eps, measured in MODEL units for both methods:
//                       martin's F is already the distance from C to the ray (two
//                       orthonormal plane distances); proposed's image-plane residual
//                       is scaled by the size of one image-plane unit at the point's
//                       depth (perspective: depth * tan(fov/2), orthographic: h/2),
//                       i.e. it is the point's distance from the ray measured in the
//                       plane perpendicular to f (equal to the perpendicular distance
//                       up to the cosine of the pixel's off-axis angle).
//   (13) diverged       the residual after a step is larger than before it.
//   (14) singular       |det| <= eps_det * (Hadamard bound of the matrix), i.e. a
//                       relative test, independent of units and parametrization scale:
//                       proposed |M| <= eps_det |P| |P_u| |P_v|,
//                       martin   |det J| <= eps_det |C_u| |C_v|.
//   left_domain         a step that leaves the face's parameter box is clamped back
//                       onto the box ONCE (a hit may lie on the box edge); leaving it
//                       a second time fails.
//   max_iterations      no success after max_iterations steps.
//   behind_eye          converged, but on the ray's line behind its origin (t <= 0).
//                       Both systems describe the whole line, not the half-ray.
// `iterations` counts Newton steps taken (0: the start already satisfied (12)).
//
// NewtonParams::robust (used only by the renderer's rescue of failed pixels, never
// for the primary map-started solves whose statistics the paper's criteria describe):
//   - a step that leaves the box is clamped onto the box and the iteration goes on
//     (the hit may lie exactly on the face border, or the start was across it);
//     left_domain only when the clamped iterate no longer moves;
//   - a step that increases the residual (13) is halved up to 4 times before
//     diverged is declared (backtracking; Newton overshoots near silhouettes,
//     where the Jacobian of (3) becomes singular).
//
// The iteration allocates nothing (nurbs.h evaluation is stack-only up to kMaxFastDegree).
#pragma once

#include <cstdint>
#include <optional>
#include <string_view>

#include "renderer/camera.h"
#include "renderer/method.h"
#include "core/scene/nurbs.h"
#include "core/scene/scene.h"
#include "renderer/solve/span_basis.h"
#include "renderer/solve/surface_patches.h"

namespace nurbsrt {

enum class NewtonStatus : uint8_t { converged, diverged, singular, max_iterations, left_domain, behind_eye };
constexpr int kNewtonStatusCount = 6;
const char* newton_status_name(NewtonStatus s);  // "converged", "diverged", ...

// The face's parameter box. wrap_u (wrap_v): the edges u = u0 and u = u1 (v = v0
// and v = v1) are the same curve in 3D, a seam (cylinders, spheres, tori and
// closed free-form faces converted from periodic surfaces). A step across a seam
// continues on the other side (u - (u1 - u0)) instead of stopping at the box: the
// hit just across the seam is the nearest one, and clamping would leave Newton
// stuck on the seam, short of the ray.
struct UvBox {
    double u0 = 0, u1 = 1, v0 = 0, v1 = 1;
    bool wrap_u = false, wrap_v = false;
};

// The box [u0,u1] x [v0,v1] of a face on surface s, with seams detected: the two
// opposite edges coincide within `tol` (model units) at 2 * (control points + 8)
// samples along them.
UvBox face_uv_box(const NurbsSurface& s, double u0, double u1, double v0, double v1, double tol);

struct NewtonResult {
    NewtonStatus status = NewtonStatus::max_iterations;
    int iterations = 0;
    double u = 0, v = 0;  // last iterate
    double t = 0;         // hit distance along the pixel ray (valid when converged)
    double residual = 0;  // ||F|| at (u, v), model units
    // Model-space rational partials of the face's surface at (u, v) when
    // converged (or behind_eye), from the last iterate's derivatives: the
    // shading normal needs no second evaluation of the surface.
    Vec3 Cu, Cv;
    // Where Newton stopped without converging: bounds, from the last iterate's
    // residual and depth alone, on the distance of its point from the ray (at
    // least gap_bound) and on where along the ray that point lies (at most
    // t_bound). For the border-gap test of a stop on the box border (Solver).
    double gap_bound = 0, t_bound = 0;
};

// proposed: `projected` is project_surface(camera, face.surface); s is the pixel's
// screen point (xR, yR); (u0, v0) the start (clamped into `box`). `spans`: the
// surface's per-span basis tables (span_basis.h; the same for the projected and
// the model surface), or null for the knot search and A2.2 in every step. Both
// give the same iterates to rounding.
// `start`: the derivatives evaluate_d1 gives at (u0, v0) on the surface the
// method iterates on (here `projected`), when the caller has them already: a
// start shared by several rays (the sub-pixel samples of anti-aliasing, solved
// from the same neighbours' hits) is then evaluated once, not once per ray. The
// iterates are the same as without (the same numbers, not recomputed). Ignored
// when (u0, v0) lies outside `box`, where the iteration starts from its clamp.
// `patches`: the power-form patches of `projected` over `spans`
// (surface_patches.h; project_patches of the model surface's), evaluated
// instead of the basis tables: the same iterates to rounding, fewer operations.
NewtonResult newton_proposed(const NurbsSurface& projected, const Camera& camera, ScreenPoint s, double u0, double v0,
                             const UvBox& box, const NewtonParams& params, const SurfaceSpans* spans = nullptr,
                             const SurfaceDerivs* start = nullptr, const SurfacePatches* patches = nullptr);

// martin: on the model-space surface and the pixel ray; `start` and `patches`
// as above, of `surface`.
NewtonResult newton_martin(const NurbsSurface& surface, const Ray& ray, double u0, double v0, const UvBox& box,
                           const NewtonParams& params, const SurfaceSpans* spans = nullptr,
                           const SurfaceDerivs* start = nullptr, const SurfacePatches* patches = nullptr);

// The two planes of Martin et al.: N1 perpendicular to dir (built from dir's two
// largest components), N2 = N1 x dir, d_i = -N_i . origin.
struct RayPlanes {
    Vec3 n1, n2;
    double d1 = 0, d2 = 0;
};
RayPlanes ray_planes(const Ray& ray);

// One step of each kind from evaluated derivatives, for tests and benchmarks.
// Return false when the system is singular by (14).
struct Step {
    double du = 0, dv = 0;
};
// eq. (9)-(11) on homogeneous image-plane derivatives (d.S = (X, Y, D, .)).
bool proposed_step(const SurfaceDerivs& d, ScreenPoint s, double eps_det, Step& out);
// eq. (6)-(7) literally: J of (X/D, Y/D) by the quotient rule, then -J^{-1} F.
bool textbook_step(const SurfaceDerivs& d, ScreenPoint s, double eps_det, Step& out);

}  // namespace nurbsrt
