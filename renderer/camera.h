// The camera and its pixel rays (a fixed contract the
// AOVs, the bench and the tests rely on), the named views fitted to a bounding box, and the paper's
// projection of homogeneous control points to the image plane (Sisojevs & Glazs 2010,
// "Projection to R^2", the x, y, w of eq. 8).
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "core/scene/scene.h"
#include "core/vec.h"

namespace nurbsrt {

enum class Projection { perspective, orthographic };

// What a user specifies. `width` x `height` is the image in pixels; the
// orthographic view height (model units) is `ortho_height` (the contract's
// `height` for orthographic cameras).
struct CameraSpec {
    Vec3 eye{0, 0, 1};
    Vec3 target{0, 0, 0};
    Vec3 up{0, 1, 0};
    Projection projection = Projection::perspective;
    double fov_deg = 40;      // vertical field of view, perspective
    double ortho_height = 1;  // view height in model units, orthographic
    int width = 512;
    int height = 512;
};

struct Ray {
    Vec3 origin;
    Vec3 dir;  // unit length; hit = origin + t * dir
};

// Image-plane coordinates of the contract: sx in [-a, a] (a = W/H), sy in [-1, 1].
struct ScreenPoint {
    double sx = 0, sy = 0;
};

class Camera {
public:
    // Throws Error(invalid_argument) for a degenerate spec (eye == target, up
    // parallel to the view direction, non-positive size/fov/height).
    explicit Camera(const CameraSpec& spec);

    const CameraSpec& spec() const { return spec_; }
    int width() const { return spec_.width; }
    int height() const { return spec_.height; }
    bool perspective() const { return spec_.projection == Projection::perspective; }
    Vec3 forward() const { return f_; }  // f
    Vec3 right() const { return r_; }    // r
    Vec3 up() const { return u_; }       // u = r x f
    double aspect() const { return aspect_; }
    double tan_half_fov() const { return tan_half_; }

    // sx, sy of a continuous pixel position: column i + 0.5 is the centre of column i.
    ScreenPoint screen(double px, double py) const {
        return {(2.0 * px / spec_.width - 1.0) * aspect_, 1.0 - 2.0 * py / spec_.height};
    }
    // sx, sy of the centre of pixel (i, j): the contract's 0.5 offsets.
    ScreenPoint pixel_screen(int i, int j) const { return screen(i + 0.5, j + 0.5); }
    // screen() inverted, one coordinate each: the continuous pixel position of
    // sx and of sy (pixel i spans [i, i + 1), its centre at i + 0.5).
    double pixel_x(double sx) const { return (sx / aspect_ + 1.0) * 0.5 * spec_.width; }
    double pixel_y(double sy) const { return (1.0 - sy) * 0.5 * spec_.height; }

    // Inline: the shading pass and Martin's solves ask for one per pixel and solve.
    Ray ray(ScreenPoint s) const {
        if (perspective())  // dir = normalize(f + tan(fov/2) (sx r + sy u))
            return {spec_.eye, normalize(f_ + tan_half_ * (s.sx * r_ + s.sy * u_))};
        // origin = eye + (height/2) (sx r + sy u); dir = f
        return {spec_.eye + 0.5 * spec_.ortho_height * (s.sx * r_ + s.sy * u_), f_};
    }
    Ray pixel_ray(int i, int j) const { return ray(pixel_screen(i, j)); }

    // The paper's projection to R^2 as a linear map on a homogeneous point
    // P^w = (wx, wy, wz, w), with d = P^w.xyz - w * eye:
    //   perspective:  X = r.d / tan(fov/2),  Y = u.d / tan(fov/2),  D = f.d,  4th = w
    //                 -> X/D = sx, Y/D = sy, depth along f = D / w
    //   orthographic: X = r.d / (h/2),       Y = u.d / (h/2),        D = w,    4th = f.d
    //                 -> X/D = sx, Y/D = sy, depth along f = (f.d) / w = 4th / D
    // (for orthographic D = w already carries the weight, so the 4th slot holds
    // the depth numerator instead of repeating w). Being linear, it maps control
    // points to control points: the projected surface is a NURBS surface with the
    // same knots whose (X, Y, D) are the paper's (x, y, w) of eq. (8)-(11).
    Vec4 project_h(Vec4 pw) const;

    // The model-space rational partials C_u, C_v of C = S / w at a point of a
    // projected surface (project_surface), from its projected homogeneous point P
    // and partials P_u, P_v: project_h is linear and invertible, so the model
    // partials are its inverse applied to P_u, P_v, and by the quotient rule
    // (Piegl & Tiller, The NURBS Book, eq. 4.7) C_u = (d_u - (d / w) w_u) / w with
    // d = S.xyz - w eye (the eye cancels, so no large coordinates are subtracted).
    void model_partials(const Vec4& P, const Vec4& Pu, const Vec4& Pv, Vec3& Cu, Vec3& Cv) const;

    // Depth along f of a projected homogeneous point (any point of the projected surface).
    double depth(Vec4 projected) const { return perspective() ? projected.z / projected.w : projected.w / projected.z; }
    // Hit distance t (along the unit pixel ray) of a point on the ray through screen point s,
    // from its depth along f: perspective t = depth / (f . dir); orthographic t = depth.
    double hit_distance_from_depth(double depth_along_f, ScreenPoint s) const;

    // Size in model units of one unit of image-plane residual at a given depth:
    // perspective depth * tan(fov/2), orthographic h/2. Converts the `proposed`
    // residual |F| (image-plane units) into model units.
    double image_to_model_scale(double depth_along_f) const {
        return perspective() ? depth_along_f * tan_half_ : 0.5 * spec_.ortho_height;
    }

    // OpenGL clip coordinates of a model point for the preliminary map, laid out
    // so that GL pixel centres coincide with the contract's pixel rays: x_ndc = sx/a,
    // y_ndc = sy (GL row 0 is the bottom row, i.e. contract row H-1), and depth in
    // [near, far] along f mapped to [-1, 1].
    Vec4 clip(Vec3 p, double near_depth, double far_depth) const;

private:
    CameraSpec spec_;
    Vec3 f_, r_, u_;
    double aspect_ = 1, tan_half_ = 0;
};

// The projected copy of a surface (same degrees and knots, control points mapped
// by Camera::project_h). Made once per frame per patch.
NurbsSurface project_surface(const Camera& camera, const NurbsSurface& s);

// Named views fitted to the model (renderer/view_fit.cpp). View directions
// (from eye towards target, model axes; Z is up for every view except
// top/bottom, whose up is +Y):
//   front  looks along +Y (eye at -Y)     back   along -Y (eye at +Y)
//   left   looks along +X (eye at -X)     right  along -X (eye at +X)
//   top    looks along -Z (eye at +Z)     bottom along +Z (eye at -Z)
//   iso    looks along (-1,-1,-1)/sqrt(3) (eye at +X+Y+Z), up +Z
// Fit, for any aspect: perspective puts the eye where the frustum, narrowed by
// the margin, touches the points on its binding pair of sides (the exact
// solution of the four plane constraints, not an iteration), centred across
// the other pair; orthographic takes the smallest view height holding the
// points' extent across the view, centred on it, with the eye plane one box
// diagonal before the centre.
//
// The margin: the fraction of the frame's width and of its height left empty
// on each side of the fitted model. 5 % keeps a thumbnail's silhouette clear
// of the border (and of the edge anti-aliasing's reach) while the model still
// fills 90 % of the frame along its binding axis.
inline constexpr double kDefaultFitMargin = 0.05;
// Beyond this the model would shrink to under a tenth of the frame.
inline constexpr double kMaxFitMargin = 0.45;

// `projection`, fov, width and height are taken from `base`; returns the full
// spec. Throws Error(invalid_argument) for an unknown name, an empty box or a
// margin outside [0, kMaxFitMargin].
CameraSpec named_view(const std::string& name, const BBox& box, const CameraSpec& base,
                      double margin = kDefaultFitMargin);
// The same fit for a set of points (their extent in the view, not their box).
// `slack` is how far the true surface may lie outside the points (it widens
// every point to a ball of that radius).
CameraSpec named_view(const std::string& name, const std::vector<Vec3>& points, const CameraSpec& base,
                      double margin = kDefaultFitMargin, double slack = 0);
// The named view fitted to the scene's geometry (its preliminary-map mesh
// vertices, widened by the mesh's deflection; the box when there are none).
CameraSpec fit_view(const std::string& name, const Scene& scene, const CameraSpec& base,
                    double margin = kDefaultFitMargin);
bool is_named_view(const std::string& name);

// What a user asks of the camera: a named view, optionally overridden vector
// by vector. An eye without a target looks at the model's centre (the middle
// of its box), and an orthographic view height not given is fitted to the
// model as seen from there; a target or up given replace the fitted ones.
struct ViewRequest {
    std::string view = "iso";
    std::optional<Vec3> eye, target, up;
    std::optional<double> ortho_height;
    double fit_margin = kDefaultFitMargin;
};
// The camera of `request` over `scene` (the scene's geometry as fit_view uses
// it), without the faces `hidden_faces` marks and with the faces moved by
// `face_offsets` (each per face, or empty): a view frames what it shows.
CameraSpec fitted_camera(const ViewRequest& request, const Scene& scene, const CameraSpec& base,
                         const std::vector<uint8_t>& hidden_faces = {}, const std::vector<Vec3>& face_offsets = {});
// The same over a box (its 8 corners), for checks made before any model exists.
CameraSpec fitted_camera(const ViewRequest& request, const BBox& box, const CameraSpec& base);

}  // namespace nurbsrt
