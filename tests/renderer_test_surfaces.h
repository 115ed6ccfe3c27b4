// Analytic test patches built in code, each with an exact ray intersection that
// does not use the NURBS evaluator (closed forms, or bisection on the implicit
// equation of a polynomial graph).
#pragma once

#include <cmath>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "renderer/camera.h"
#include "core/scene/nurbs.h"
#include "core/scene/scene.h"

namespace nurbsrt::testing {

struct AnalyticPatch {
    std::string name;
    NurbsSurface surface;
    BBox box;                                              // of the patch
    std::function<std::optional<double>(const Ray&)> hit;  // nearest t > 0 on the patch
    CameraSpec view;                                       // a camera that sees the patch
};

inline Vec4 hpt(Vec3 p, double w) { return {w * p.x, w * p.y, w * p.z, w}; }

inline std::vector<double> clamped_knots(int degree, const std::vector<double>& interior) {
    std::vector<double> k(degree + 1, 0.0);
    k.insert(k.end(), interior.begin(), interior.end());
    k.insert(k.end(), degree + 1, 1.0);
    return k;
}

inline CameraSpec look(Vec3 eye, Vec3 target, Vec3 up, double fov = 40) {
    CameraSpec s;
    s.eye = eye;
    s.target = target;
    s.up = up;
    s.fov_deg = fov;
    s.width = 61;
    s.height = 47;
    return s;
}

inline void finish_box(AnalyticPatch& p) {
    for (int i = 0; i <= 40; ++i)
        for (int j = 0; j <= 40; ++j) {
            const double u = p.surface.u_begin() + (p.surface.u_end() - p.surface.u_begin()) * i / 40;
            const double v = p.surface.v_begin() + (p.surface.v_end() - p.surface.v_begin()) * j / 40;
            p.box.extend(project(evaluate(p.surface, u, v)));
        }
}

// Planar parallelogram, degree 1 x 1: corner o, edges e1 (u) and e2 (v).
inline AnalyticPatch plane_patch() {
    AnalyticPatch p;
    p.name = "plane";
    const Vec3 o{-1, -0.5, 0.2}, e1{2.2, 0.3, 0.1}, e2{-0.2, 1.7, 0.4};
    NurbsSurface& s = p.surface;
    s.degree_u = s.degree_v = 1;
    s.num_u = s.num_v = 2;
    s.knots_u = s.knots_v = {0, 0, 1, 1};
    for (int i = 0; i < 2; ++i)
        for (int j = 0; j < 2; ++j) s.cp.push_back(hpt(o + double(i) * e1 + double(j) * e2, 1));
    p.hit = [o, e1, e2](const Ray& r) -> std::optional<double> {
        const Vec3 n = cross(e1, e2);
        const double den = dot(n, r.dir);
        if (den == 0) return std::nullopt;
        const double t = dot(n, o - r.origin) / den;
        const Vec3 q = r.origin + t * r.dir - o;
        // Solve q = a e1 + b e2 in the plane.
        const double a = dot(cross(q, e2), n) / dot(n, n), b = dot(cross(e1, q), n) / dot(n, n);
        if (t <= 0 || a < 0 || a > 1 || b < 0 || b > 1) return std::nullopt;
        return t;
    };
    finish_box(p);
    p.view = look({0.4, -1.0, 4.0}, {0.0, 0.4, 0.3}, {0, 1, 0});
    return p;
}

// Half cylinder x^2 + y^2 = R^2, y >= 0, 0 <= z <= H: two exact rational quarter
// arcs in u (degree 2, weights 1, sqrt(2)/2, 1), degree 1 in v.
inline AnalyticPatch cylinder_patch() {
    AnalyticPatch p;
    p.name = "cylinder";
    const double R = 2, H = 3, w = std::sqrt(0.5);
    NurbsSurface& s = p.surface;
    s.degree_u = 2;
    s.degree_v = 1;
    s.num_u = 5;
    s.num_v = 2;
    s.knots_u = {0, 0, 0, 0.5, 0.5, 1, 1, 1};
    s.knots_v = {0, 0, 1, 1};
    s.rational = true;
    const Vec3 arc[5] = {{R, 0, 0}, {R, R, 0}, {0, R, 0}, {-R, R, 0}, {-R, 0, 0}};
    const double ws[5] = {1, w, 1, w, 1};
    for (int i = 0; i < 5; ++i)
        for (int j = 0; j < 2; ++j) s.cp.push_back(hpt(arc[i] + Vec3{0, 0, H * j}, ws[i]));
    p.hit = [R, H](const Ray& r) -> std::optional<double> {
        const double a = r.dir.x * r.dir.x + r.dir.y * r.dir.y;
        const double b = 2 * (r.origin.x * r.dir.x + r.origin.y * r.dir.y);
        const double c = r.origin.x * r.origin.x + r.origin.y * r.origin.y - R * R;
        const double disc = b * b - 4 * a * c;
        if (a == 0 || disc < 0) return std::nullopt;
        const double sq = std::sqrt(disc);
        const double q = -0.5 * (b + std::copysign(sq, b));  // stable roots
        double t0 = q / a, t1 = c / q;
        if (t0 > t1) std::swap(t0, t1);
        for (double t : {t0, t1}) {
            const Vec3 x = r.origin + t * r.dir;
            if (t > 0 && x.y >= 0 && x.z >= 0 && x.z <= H) return t;
        }
        return std::nullopt;
    };
    finish_box(p);
    p.view = look({1.0, 9.0, 4.0}, {0.0, 0.0, 1.5}, {0, 0, 1});
    return p;
}

// Sphere octant x, y, z >= 0 of radius R: biquadratic rational, u along the
// meridian from the north pole (row u = 0 collapses to the pole: a degenerate
// edge), v around the z axis.
inline AnalyticPatch sphere_patch(double R = 1.5) {
    AnalyticPatch p;
    p.name = "sphere";
    const double w = std::sqrt(0.5);
    NurbsSurface& s = p.surface;
    s.degree_u = s.degree_v = 2;
    s.num_u = s.num_v = 3;
    s.knots_u = s.knots_v = {0, 0, 0, 1, 1, 1};
    s.rational = true;
    const double prof_x[3] = {0, R, R}, prof_z[3] = {R, R, 0}, prof_w[3] = {1, w, 1};
    const double rot_w[3] = {1, w, 1};
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) {
            const double x = prof_x[i];
            const Vec3 q = j == 0 ? Vec3{x, 0, prof_z[i]} : j == 1 ? Vec3{x, x, prof_z[i]} : Vec3{0, x, prof_z[i]};
            s.cp.push_back(hpt(q, prof_w[i] * rot_w[j]));
        }
    p.hit = [R](const Ray& r) -> std::optional<double> {
        const double b = dot(r.origin, r.dir), c = dot(r.origin, r.origin) - R * R;
        const double disc = b * b - c;
        if (disc < 0) return std::nullopt;
        const double sq = std::sqrt(disc);
        const double q = -(b + std::copysign(sq, b));
        double t0 = q, t1 = c / q;
        if (t0 > t1) std::swap(t0, t1);
        for (double t : {t0, t1}) {
            const Vec3 x = r.origin + t * r.dir;
            if (t > 0 && x.x >= 0 && x.y >= 0 && x.z >= 0) return t;
        }
        return std::nullopt;
    };
    finish_box(p);
    p.view = look({4.0, 3.0, 3.5}, {0.6, 0.6, 0.6}, {0, 0, 1});
    return p;
}

// Bernstein coefficient k (of degree n, over x in [-1, 1]) of the monomial x^m:
// the blossom e_m(x_1..x_n) / C(n, m) with n-k arguments -1 and k arguments +1.
inline double monomial_bernstein(int m, int n, int k) {
    // e_m of (n-k) copies of -1 and k copies of +1 = sum_i C(k, i) C(n-k, m-i) (-1)^(m-i)
    auto C = [](int a, int b) -> double {
        if (b < 0 || b > a) return 0;
        double r = 1;
        for (int i = 1; i <= b; ++i) r = r * (a - b + i) / i;
        return r;
    };
    double e = 0;
    for (int i = 0; i <= m; ++i) e += C(k, i) * C(n - k, m - i) * ((m - i) % 2 ? -1.0 : 1.0);
    return e / C(n, m);
}

// Polynomial graph z = sum c x^a y^b over [-1, 1]^2 as a Bezier patch of degree
// (nu, nv); the exact intersection is found by bisection on z - f(x, y) along the ray.
struct Term {
    double c;
    int a, b;
};
inline AnalyticPatch graph_patch(const std::string& name, int nu, int nv, std::vector<Term> terms, CameraSpec view) {
    AnalyticPatch p;
    p.name = name;
    NurbsSurface& s = p.surface;
    s.degree_u = nu;
    s.degree_v = nv;
    s.num_u = nu + 1;
    s.num_v = nv + 1;
    s.knots_u = clamped_knots(nu, {});
    s.knots_v = clamped_knots(nv, {});
    for (int i = 0; i <= nu; ++i)
        for (int j = 0; j <= nv; ++j) {
            double z = 0;
            for (const Term& t : terms) z += t.c * monomial_bernstein(t.a, nu, i) * monomial_bernstein(t.b, nv, j);
            s.cp.push_back(hpt({monomial_bernstein(1, nu, i), monomial_bernstein(1, nv, j), z}, 1));
        }
    auto f = [terms](double x, double y) {
        long double z = 0;
        for (const Term& t : terms) {
            long double m = t.c;
            for (int k = 0; k < t.a; ++k) m *= x;
            for (int k = 0; k < t.b; ++k) m *= y;
            z += m;
        }
        return z;
    };
    p.hit = [f](const Ray& r) -> std::optional<double> {
        // g(t) = z(t) - f(x(t), y(t)) on the part of the ray over [-1,1]^2; first sign change.
        auto g = [&](long double t) {
            return (long double)r.origin.z + t * r.dir.z -
                   f(double(r.origin.x + t * r.dir.x), double(r.origin.y + t * r.dir.y));
        };
        auto inside = [&](long double t) {
            const double x = double(r.origin.x + t * r.dir.x), y = double(r.origin.y + t * r.dir.y);
            return std::abs(x) <= 1 && std::abs(y) <= 1;
        };
        const int N = 1000;
        const long double T = 20;
        long double prev_t = 0, prev_g = g(0);
        for (int k = 1; k <= N; ++k) {
            const long double t = T * k / N, gt = g(t);
            if ((gt > 0) != (prev_g > 0)) {
                long double lo = prev_t, hi = t;
                for (int it = 0; it < 90; ++it) {
                    const long double mid = 0.5L * (lo + hi);
                    ((g(mid) > 0) == (prev_g > 0) ? lo : hi) = mid;
                }
                const long double th = 0.5L * (lo + hi);
                if (inside(th)) return double(th);
            }
            prev_t = t;
            prev_g = gt;
        }
        return std::nullopt;
    };
    finish_box(p);
    p.view = view;
    return p;
}

// Monkey saddle z = x^3 - 3 x y^2, bicubic.
inline AnalyticPatch saddle_patch() {
    return graph_patch("saddle", 3, 3, {{1, 3, 0}, {-3, 1, 2}}, look({0.8, -3.5, 6.0}, {0, 0, 0}, {0, 0, 1}, 35));
}

// A high-degree patch: degree (9, 7), z = 0.4 x^7 y^2 - 0.3 x y^6 + 0.5 x^2 + 0.2 y^5 x^3.
inline AnalyticPatch high_degree_patch() {
    return graph_patch("high_degree", 9, 7, {{0.4, 7, 2}, {-0.3, 1, 6}, {0.5, 2, 0}, {0.2, 3, 5}},
                       look({-1.0, -3.0, 5.0}, {0, 0, 0.2}, {0, 0, 1}, 40));
}

inline std::vector<AnalyticPatch> all_patches() {
    return {plane_patch(), cylinder_patch(), sphere_patch(), saddle_patch(), high_degree_patch()};
}

// A start like the preliminary map's: the (u, v) of the cell centre of an n x n
// grid whose point is nearest to a target (samples precomputed once).
struct GridStart {
    std::vector<Vec2> uv;
    std::vector<Vec3> xyz;
    GridStart(const NurbsSurface& s, int n = 24) {
        for (int i = 0; i < n; ++i)
            for (int j = 0; j < n; ++j) {
                const double u = s.u_begin() + (s.u_end() - s.u_begin()) * (i + 0.5) / n;
                const double v = s.v_begin() + (s.v_end() - s.v_begin()) * (j + 0.5) / n;
                uv.push_back({u, v});
                xyz.push_back(project(evaluate(s, u, v)));
            }
    }
    Vec2 nearest(Vec3 target) const {
        size_t best = 0;
        double bd = HUGE_VAL;
        for (size_t k = 0; k < xyz.size(); ++k) {
            const Vec3 d = xyz[k] - target;
            const double dd = dot(d, d);
            if (dd < bd) {
                bd = dd;
                best = k;
            }
        }
        return uv[best];
    }
};

// A Face for an analytic patch: whole parameter box, an n x n grid mesh of the
// patch (uv + exact 3D points) for the preliminary map.
inline Face make_face(const AnalyticPatch& p, uint32_t index, int n = 8) {
    Face f;
    f.index = index;
    f.surface = p.surface;
    f.u_min = p.surface.u_begin();
    f.u_max = p.surface.u_end();
    f.v_min = p.surface.v_begin();
    f.v_max = p.surface.v_end();
    for (int i = 0; i <= n; ++i)
        for (int j = 0; j <= n; ++j) {
            const double u = f.u_min + (f.u_max - f.u_min) * i / n, v = f.v_min + (f.v_max - f.v_min) * j / n;
            f.mesh.uv.push_back({u, v});
            f.mesh.xyz.push_back(project(evaluate(p.surface, u, v)));
        }
    for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j) {
            const uint32_t a = i * (n + 1) + j, b = a + (n + 1);
            f.mesh.triangles.insert(f.mesh.triangles.end(), {a, b, b + 1, a, b + 1, a + 1});
        }
    return f;
}

// The sphere octant, and a plane patch with a circular hole of radius 0.2 at
// (u, v) = (0.5, 0.5) cut by a 64-gon trim loop (plus the outer boundary loop).
inline Scene sphere_and_holed_plane(AnalyticPatch& sphere, AnalyticPatch& plane) {
    sphere = sphere_patch(1.5);
    plane = plane_patch();
    // Move the plane beside the sphere, scaled up, so both are well in view.
    const Vec3 off{-1.5, 1.5, -0.5};
    for (Vec4& c : plane.surface.cp)
        c = Vec4{1.5 * c.x + off.x * c.w, 1.5 * c.y + off.y * c.w, 1.5 * c.z + off.z * c.w, c.w};
    plane.box = BBox{};
    finish_box(plane);
    const auto hit = plane.hit;
    plane.hit = [hit, off](const Ray& r) {
        const std::optional<double> t = hit(Ray{(r.origin - off) / 1.5, r.dir});
        return t ? std::optional<double>(*t * 1.5) : std::nullopt;
    };
    Scene s;
    s.faces.push_back(make_face(sphere, 1, 12));
    Face pf = make_face(plane, 2, 12);
    TrimLoop outer, hole;
    outer.outer = true;
    outer.points = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
    for (int k = 0; k < 64; ++k)
        hole.points.push_back({0.5 + 0.2 * std::cos(2 * M_PI * k / 64), 0.5 + 0.2 * std::sin(2 * M_PI * k / 64)});
    pf.loops = {outer, hole};
    pf.color = {0.2f, 0.5f, 0.9f};
    pf.has_color = true;
    s.faces.push_back(pf);
    s.bbox.extend(sphere.box);
    s.bbox.extend(plane.box);
    return s;
}

// The CLI's default view of a scene (iso, perspective, 35 degrees), w x h pixels.
inline CameraSpec iso_view(const Scene& s, int w, int h) {
    CameraSpec base;
    base.width = w;
    base.height = h;
    base.fov_deg = 35;
    return named_view("iso", s.bbox, base);
}

}  // namespace nurbsrt::testing
