// Small fixed-size vector types used across the renderer and the Scene.
// Plain aggregates (no SIMD, no templates) so that hot loops stay readable and
// the Scene stays trivially serializable.
#pragma once

#include <cmath>

namespace nurbsrt {

struct Vec2 {
    double x = 0, y = 0;
};

struct Vec3 {
    double x = 0, y = 0, z = 0;
};

// Homogeneous point (w*x, w*y, w*z, w) or a partial derivative of one.
struct Vec4 {
    double x = 0, y = 0, z = 0, w = 0;
};

inline Vec2 operator+(Vec2 a, Vec2 b) { return {a.x + b.x, a.y + b.y}; }
inline Vec2 operator-(Vec2 a, Vec2 b) { return {a.x - b.x, a.y - b.y}; }
inline Vec2 operator*(double s, Vec2 a) { return {s * a.x, s * a.y}; }

inline Vec3 operator+(Vec3 a, Vec3 b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
inline Vec3 operator-(Vec3 a, Vec3 b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
inline Vec3 operator-(Vec3 a) { return {-a.x, -a.y, -a.z}; }
inline Vec3 operator*(double s, Vec3 a) { return {s * a.x, s * a.y, s * a.z}; }
inline Vec3 operator*(Vec3 a, double s) { return s * a; }
inline Vec3 operator/(Vec3 a, double s) { return {a.x / s, a.y / s, a.z / s}; }
inline Vec3& operator+=(Vec3& a, Vec3 b) {
    a = a + b;
    return a;
}
inline double dot(Vec3 a, Vec3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
inline Vec3 cross(Vec3 a, Vec3 b) { return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x}; }
inline double length(Vec3 a) { return std::sqrt(dot(a, a)); }
inline Vec3 normalize(Vec3 a) {
    const double l = length(a);
    return l > 0 ? a / l : a;
}

inline Vec4 operator+(Vec4 a, Vec4 b) { return {a.x + b.x, a.y + b.y, a.z + b.z, a.w + b.w}; }
inline Vec4 operator-(Vec4 a, Vec4 b) { return {a.x - b.x, a.y - b.y, a.z - b.z, a.w - b.w}; }
inline Vec4 operator*(double s, Vec4 a) { return {s * a.x, s * a.y, s * a.z, s * a.w}; }
inline Vec4& operator+=(Vec4& a, Vec4 b) {
    a = a + b;
    return a;
}

// Cartesian point of a homogeneous one (divides by w).
inline Vec3 project(Vec4 h) { return {h.x / h.w, h.y / h.w, h.z / h.w}; }

// Axis-aligned bounding box; empty until the first extend().
struct BBox {
    Vec3 lo{HUGE_VAL, HUGE_VAL, HUGE_VAL};
    Vec3 hi{-HUGE_VAL, -HUGE_VAL, -HUGE_VAL};

    bool empty() const { return lo.x > hi.x; }
    void extend(Vec3 p) {
        lo = {std::fmin(lo.x, p.x), std::fmin(lo.y, p.y), std::fmin(lo.z, p.z)};
        hi = {std::fmax(hi.x, p.x), std::fmax(hi.y, p.y), std::fmax(hi.z, p.z)};
    }
    void extend(const BBox& b) {
        if (!b.empty()) {
            extend(b.lo);
            extend(b.hi);
        }
    }
    Vec3 center() const { return 0.5 * (lo + hi); }
    double diagonal() const { return empty() ? 0.0 : length(hi - lo); }
};

}  // namespace nurbsrt
