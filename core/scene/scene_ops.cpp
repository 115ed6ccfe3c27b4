#include "core/scene/scene_ops.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "core/check.h"

namespace nurbsrt {

Affine Affine::translation(Vec3 t) {
    Affine a;
    a.m[3] = t.x;
    a.m[7] = t.y;
    a.m[11] = t.z;
    return a;
}

Affine Affine::scaling(double s) {
    Affine a;
    a.m[0] = a.m[5] = a.m[10] = s;
    return a;
}

Affine Affine::rotation_xyz_deg(Vec3 deg) {
    const double k = M_PI / 180.0;
    const double cx = std::cos(deg.x * k), sx = std::sin(deg.x * k);
    const double cy = std::cos(deg.y * k), sy = std::sin(deg.y * k);
    const double cz = std::cos(deg.z * k), sz = std::sin(deg.z * k);
    Affine rx, ry, rz;
    rx.m = {1, 0, 0, 0, 0, cx, -sx, 0, 0, sx, cx, 0};
    ry.m = {cy, 0, sy, 0, 0, 1, 0, 0, -sy, 0, cy, 0};
    rz.m = {cz, -sz, 0, 0, sz, cz, 0, 0, 0, 0, 1, 0};
    return rz * ry * rx;
}

Affine Affine::operator*(const Affine& b) const {
    Affine r;
    for (int i = 0; i < 3; ++i) {
        for (int j = 0; j < 4; ++j) {
            double s = j == 3 ? m[i * 4 + 3] : 0.0;
            for (int k = 0; k < 3; ++k) s += m[i * 4 + k] * b.m[k * 4 + j];
            r.m[i * 4 + j] = s;
        }
    }
    return r;
}

Vec3 Affine::apply(Vec3 p) const {
    return {m[0] * p.x + m[1] * p.y + m[2] * p.z + m[3], m[4] * p.x + m[5] * p.y + m[6] * p.z + m[7],
            m[8] * p.x + m[9] * p.y + m[10] * p.z + m[11]};
}

Vec4 Affine::apply_h(Vec4 q) const {
    return {m[0] * q.x + m[1] * q.y + m[2] * q.z + m[3] * q.w, m[4] * q.x + m[5] * q.y + m[6] * q.z + m[7] * q.w,
            m[8] * q.x + m[9] * q.y + m[10] * q.z + m[11] * q.w, q.w};
}

double Affine::determinant() const {
    return m[0] * (m[5] * m[10] - m[6] * m[9]) - m[1] * (m[4] * m[10] - m[6] * m[8]) +
           m[2] * (m[4] * m[9] - m[5] * m[8]);
}

void transform_scene(Scene& scene, const Affine& xf) {
    const bool mirror = xf.determinant() < 0;
    BBox box;
    for (Face& f : scene.faces) {
        for (Vec4& p : f.surface.cp) p = xf.apply_h(p);
        for (Vec3& p : f.mesh.xyz) {
            p = xf.apply(p);
            box.extend(p);
        }
        if (mirror) f.reversed = !f.reversed;
    }
    // The box of the mesh vertices of the moved faces; when a scene carries no
    // meshes, move the corners of the old box instead (still a valid bound).
    if (box.empty() && !scene.bbox.empty()) {
        for (int c = 0; c < 8; ++c)
            box.extend(xf.apply({c & 1 ? scene.bbox.hi.x : scene.bbox.lo.x, c & 2 ? scene.bbox.hi.y : scene.bbox.lo.y,
                                 c & 4 ? scene.bbox.hi.z : scene.bbox.lo.z}));
    }
    scene.bbox = box;
    for (Part& p : scene.parts) p.placement = (xf * Affine{p.placement}).m;
    summarize_parts(scene);
}

namespace {

// "3/1/2" with `more` added to its first position ("3" + 2 -> "5/1/2").
std::string renumbered_root(const std::string& id, size_t more) {
    const size_t slash = id.find('/');
    size_t root = 0;
    for (size_t i = 0; i < std::min(slash, id.size()); ++i) {
        if (id[i] < '0' || id[i] > '9') return id;  // not a path of positions: kept as it is
        root = root * 10 + static_cast<size_t>(id[i] - '0');
    }
    return std::to_string(root + more) + (slash == std::string::npos ? "" : id.substr(slash));
}

}  // namespace

void summarize_parts(Scene& scene) {
    for (Part& p : scene.parts) {
        p.faces = 0;
        p.bbox = BBox{};
    }
    for (const Face& f : scene.faces) {
        if (f.body >= scene.bodies.size()) continue;
        BBox box;
        for (const Vec3& v : f.mesh.xyz) box.extend(v);
        for (int32_t p = scene.bodies[f.body].part; p >= 0; p = scene.parts[static_cast<size_t>(p)].parent) {
            NURBSRT_CHECK(static_cast<size_t>(p) < scene.parts.size());
            ++scene.parts[static_cast<size_t>(p)].faces;
            scene.parts[static_cast<size_t>(p)].bbox.extend(box);
        }
    }
}

void append_scene(Scene& dst, const Scene& src) {
    const uint32_t face_offset = static_cast<uint32_t>(dst.faces.size());
    const uint32_t body_offset = static_cast<uint32_t>(dst.bodies.size());
    dst.faces.reserve(dst.faces.size() + src.faces.size());
    for (const Face& f : src.faces) {
        dst.faces.push_back(f);
        dst.faces.back().index = f.index + face_offset;
        dst.faces.back().body = f.body + body_offset;
    }
    const int32_t part_offset = static_cast<int32_t>(dst.parts.size());
    for (const Body& b : src.bodies) {
        dst.bodies.push_back(b);
        if (b.part >= 0) dst.bodies.back().part = b.part + part_offset;
    }
    // Part ids are paths from the first root: src's roots come after dst's.
    size_t roots = 0;
    for (const Part& p : dst.parts) roots += p.parent < 0;
    for (const Part& p : src.parts) {
        Part moved = p;
        if (p.parent >= 0) moved.parent = p.parent + part_offset;
        moved.id = renumbered_root(p.id, roots);
        dst.parts.push_back(std::move(moved));
    }
    dst.bbox.extend(src.bbox);
    dst.timings.read_ms += src.timings.read_ms;
    dst.timings.nurbs_convert_ms += src.timings.nurbs_convert_ms;
    dst.timings.mesh_ms += src.timings.mesh_ms;
    for (const std::string& w : src.warnings) dst.warnings.push_back(src.source_name + ": " + w);
    if (dst.source_name.empty()) {
        dst.source_name = src.source_name;
        dst.format = src.format;
        dst.units = src.units;
    } else if (dst.format != src.format) {
        dst.format = "mixed";
    }
}

}  // namespace nurbsrt
