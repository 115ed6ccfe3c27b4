// The Scene: everything the renderer needs from a CAD file, as plain C++ data.
// No OCCT types; the importer fills it, scene_io.h serializes it, the renderer
// reads it. One Face per CAD face, numbered as the face AOV shows them
// (faces[i].index == i + 1; 0 is background).
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "core/vec.h"

namespace nurbsrt {

// A clamped, non-periodic, tensor-product (rational) B-spline surface
//   S(u,v) = sum_i sum_j N_i,p(u) N_j,q(v) P^w_ij          (homogeneous form)
// with P^w_ij = (w_ij x_ij, w_ij y_ij, w_ij z_ij, w_ij); the Cartesian surface
// is S^w / w (Sisojevs & Glazs 2010, eq. 2). Control points are stored u-major:
// cp[i * num_v + j] for i in [0, num_u), j in [0, num_v).
struct NurbsSurface {
    int degree_u = 0, degree_v = 0;
    int num_u = 0, num_v = 0;     // control points in u and v
    std::vector<double> knots_u;  // num_u + degree_u + 1 values, clamped
    std::vector<double> knots_v;  // num_v + degree_v + 1 values, clamped
    std::vector<Vec4> cp;         // num_u * num_v homogeneous control points
    bool rational = false;        // false: every weight is 1

    const Vec4& at(int i, int j) const { return cp[static_cast<size_t>(i) * num_v + j]; }
    double u_begin() const { return knots_u[degree_u]; }
    double u_end() const { return knots_u[num_u]; }
    double v_begin() const { return knots_v[degree_v]; }
    double v_end() const { return knots_v[num_v]; }
};

// One boundary loop of a face in (u,v): a closed polyline, the closing segment
// from back() to front() implied (front() != back()). Inside/outside is decided
// by the even-odd rule over all loops of a face, so loop orientation does not
// matter for classification; `outer` is kept for information and statistics.
struct TrimLoop {
    std::vector<Vec2> points;
    bool outer = false;
};

// Triangle mesh of a face used only for the preliminary map: every vertex has
// its (u,v) on the surface and its 3D position (instance transform applied).
struct FaceMesh {
    std::vector<Vec2> uv;
    std::vector<Vec3> xyz;
    std::vector<uint32_t> triangles;  // 3 indices per triangle, into uv/xyz
    bool fallback_grid = false;       // true when BRepMesh failed and a trimmed uv grid was used
};

struct Color {
    float r = 0.8f, g = 0.8f, b = 0.8f;  // linear RGB in [0,1]
};

struct Face {
    uint32_t index = 0;            // 1..N, the face-index contract
    NurbsSurface surface;          // the face's converted surface, instance transform baked in
    double u_min = 0, u_max = 0;   // parameter box of the face (BRepTools::UVBounds of the
    double v_min = 0, v_max = 0;   // converted face), inside the surface's knot range
    bool reversed = false;         // face orientation REVERSED: outward normal is -(S_u x S_v)
    std::vector<TrimLoop> loops;   // empty: untrimmed, the whole parameter box
    double trim_tolerance_uv = 0;  // uv distance within which the trim test is uncertain
    FaceMesh mesh;
    bool has_color = false;
    Color color;
    std::string name;   // face or, failing that, its body's name; may be empty
    uint32_t body = 0;  // index into Scene::bodies (source solid/shell instance)
};

// A source body: a solid, shell or free face group of the file, one per assembly
// instance (an assembly part placed twice yields two bodies with their own faces).
struct Body {
    std::string name;
    bool has_color = false;
    Color color;
    int32_t part = -1;  // the leaf of Scene::parts that places it; -1 when the file was read without its tree
    // Every shell of it closed (each edge shared by two of its faces): a section
    // plane through it shows a cap where the ray is inside (renderer/section.h).
    bool closed = false;
};

// A node of the file's assembly tree (XDE), in depth-first order: an assembly,
// or a part that an assembly places (its faces are the bodies whose `part` it
// is). `id` is the path of child positions from the first root ("0", "0/3/1"),
// the same for every import of the same file; a scene of several files numbers
// their roots on ("1", "2", ...).
struct Part {
    std::string id;
    std::string name;
    int32_t parent = -1;  // index into Scene::parts, always lower than this one's; -1 for a root
    bool has_color = false;
    Color color;
    // Where the file places it: a 3x4 row-major rigid transform into the
    // file's world, millimetres (rows: x, y, z; columns: the axes, then the origin).
    std::array<double, 12> placement{1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0};
    uint32_t faces = 0;  // faces of the scene under this node (summarize_parts)
    BBox bbox;           // of those faces' map meshes
};

// Wall-clock times of the import stages, milliseconds (reported in the render statistics).
struct ImportTimings {
    double read_ms = 0;
    double nurbs_convert_ms = 0;
    double mesh_ms = 0;
};

struct Scene {
    std::string source_name;  // file name as given (no directories needed)
    std::string format;       // "STEP" or "IGES"
    std::string units;        // length unit declared by the file ("mm", "inch", ...); coordinates are mm
    BBox bbox;                // of all faces (surfaces' trimmed extent, via the meshes)
    std::vector<Face> faces;
    std::vector<Body> bodies;
    std::vector<Part> parts;  // the assembly tree; empty when read without attributes
    ImportTimings timings;
    std::vector<std::string> warnings;  // things the import worked around (mesh fallback, healed loops, ...)
};

}  // namespace nurbsrt
