// JSON -> Scene (see scene_json.h): the document scene_to_json writes, read
// back so that `nurbsrt render x.json` renders what `nurbsrt convert` wrote.
#include <cmath>
#include <sstream>

#include <nlohmann/json.hpp>

#include "core/error.h"
#include "core/json_limits.h"
#include "core/scene/nurbs.h"
#include "core/io/scene_io.h"
#include "core/io/scene_json.h"
#include "core/scene/trim.h"

namespace nurbsrt {
namespace {

using json = nlohmann::json;

[[noreturn]] void bad(const std::string& where, const std::string& what) {
    throw Error(ErrorCode::invalid_argument, "NURBS scene JSON: " + where + ": " + what);
}

const json& field(const json& o, const char* key, const std::string& where) {
    if (!o.is_object() || !o.contains(key)) bad(where, std::string("missing '") + key + "'");
    return o.at(key);
}

double number(const json& v, const std::string& where) {
    if (!v.is_number()) bad(where, "must be a number (non-finite values cannot be rendered)");
    return v.get<double>();
}

int integer(const json& v, const std::string& where) {
    if (!v.is_number_integer()) bad(where, "must be an integer");
    const auto n = v.get<long long>();
    if (n < 0 || n > 1'000'000'000) bad(where, "out of range");
    return static_cast<int>(n);
}

std::vector<double> numbers(const json& v, const std::string& where, size_t n) {
    if (!v.is_array() || (n && v.size() != n)) bad(where, "must be an array of " + std::to_string(n) + " numbers");
    std::vector<double> out;
    out.reserve(v.size());
    for (const json& x : v) out.push_back(number(x, where));
    return out;
}

std::string string_field(const json& o, const char* key) {
    return o.contains(key) && o.at(key).is_string() ? o.at(key).get<std::string>() : std::string();
}

void read_color(const json& c, bool& has, Color& out, const std::string& where) {
    has = !c.is_null();
    if (!has) return;
    const std::vector<double> v = numbers(c, where, 3);
    out = {static_cast<float>(v[0]), static_cast<float>(v[1]), static_cast<float>(v[2])};
}

void read_surface(const json& s, NurbsSurface& out, const std::string& where) {
    out.degree_u = integer(field(s, "degree_u", where), where + ".degree_u");
    out.degree_v = integer(field(s, "degree_v", where), where + ".degree_v");
    out.num_u = integer(field(s, "num_u", where), where + ".num_u");
    out.num_v = integer(field(s, "num_v", where), where + ".num_v");
    out.rational = field(s, "rational", where).is_boolean() && s.at("rational").get<bool>();
    out.knots_u = numbers(field(s, "knots_u", where), where + ".knots_u", 0);
    out.knots_v = numbers(field(s, "knots_v", where), where + ".knots_v", 0);
    const json& cps = field(s, "control_points", where);
    if (!cps.is_array()) bad(where, "control_points must be an array");
    out.cp.reserve(cps.size());
    for (const json& p : cps) {
        const std::vector<double> v = numbers(p, where + ".control_points", 4);
        out.cp.push_back({v[0], v[1], v[2], v[3]});
    }
}

Face read_face(const json& f, size_t i) {
    const std::string where = "faces[" + std::to_string(i) + "]";
    Face face;
    face.index = static_cast<uint32_t>(i + 1);  // the face-index contract: position in the list
    face.body = static_cast<uint32_t>(integer(field(f, "body", where), where + ".body"));
    face.name = string_field(f, "name");
    read_color(field(f, "color", where), face.has_color, face.color, where + ".color");
    face.reversed = field(f, "reversed", where).is_boolean() && f.at("reversed").get<bool>();
    read_surface(field(f, "surface", where), face.surface, where + ".surface");
    const std::vector<double> ur = numbers(field(f, "u_range", where), where + ".u_range", 2);
    const std::vector<double> vr = numbers(field(f, "v_range", where), where + ".v_range", 2);
    face.u_min = ur[0], face.u_max = ur[1], face.v_min = vr[0], face.v_max = vr[1];
    face.trim_tolerance_uv = number(field(f, "trim_tolerance_uv", where), where + ".trim_tolerance_uv");
    const json& loops = field(f, "trim_loops", where);
    if (!loops.is_array()) bad(where, "trim_loops must be an array");
    for (const json& l : loops) {
        TrimLoop loop;
        loop.outer = l.contains("outer") && l.at("outer").is_boolean() && l.at("outer").get<bool>();
        const json& pts = field(l, "points", where + ".trim_loops");
        if (!pts.is_array()) bad(where, "trim loop points must be an array");
        for (const json& p : pts) {
            const std::vector<double> v = numbers(p, where + ".trim_loops.points", 2);
            loop.points.push_back({v[0], v[1]});
        }
        face.loops.push_back(std::move(loop));
    }
    return face;
}

// The preliminary map needs a (u,v) mesh per face, which the JSON does not
// carry (it describes the exact geometry only): a regular grid over the face's
// parameter box, keeping the triangles whose centroid is inside the trim loops,
// as the importer does where BRepMesh fails. The map only seeds Newton, and
// the renderer's trim test and rescue passes decide the edges exactly.
constexpr int kGridCells = 48;

void grid_mesh(Face& f) {
    FaceMesh& m = f.mesh;
    m = FaceMesh{};
    m.fallback_grid = true;
    const TrimTester trim = f.loops.empty() ? TrimTester() : TrimTester(f.loops);
    const int n = kGridCells + 1;
    std::vector<int> index(static_cast<size_t>(n) * n, -1);
    const auto uv_of = [&](int i, int j) {
        return Vec2{f.u_min + (f.u_max - f.u_min) * i / kGridCells, f.v_min + (f.v_max - f.v_min) * j / kGridCells};
    };
    const auto vertex = [&](int i, int j) -> uint32_t {
        int& idx = index[static_cast<size_t>(i) * n + j];
        if (idx < 0) {
            const Vec2 uv = uv_of(i, j);
            const Vec4 h = evaluate(f.surface, uv.x, uv.y);
            idx = static_cast<int>(m.uv.size());
            m.uv.push_back(uv);
            m.xyz.push_back({h.x / h.w, h.y / h.w, h.z / h.w});
        }
        return static_cast<uint32_t>(idx);
    };
    for (int i = 0; i < kGridCells; ++i)
        for (int j = 0; j < kGridCells; ++j) {
            const Vec2 a = uv_of(i, j), b = uv_of(i + 1, j), c = uv_of(i + 1, j + 1), d = uv_of(i, j + 1);
            if (trim.inside({(a.x + b.x + c.x) / 3, (a.y + b.y + c.y) / 3}))
                m.triangles.insert(m.triangles.end(), {vertex(i, j), vertex(i + 1, j), vertex(i + 1, j + 1)});
            if (trim.inside({(a.x + c.x + d.x) / 3, (a.y + c.y + d.y) / 3}))
                m.triangles.insert(m.triangles.end(), {vertex(i, j), vertex(i + 1, j + 1), vertex(i, j + 1)});
        }
}

}  // namespace

bool is_scene_json(const std::string& text) {
    const BoundedJson b = parse_json_bounded(text, kDocumentJsonLimits);
    const json& j = b.value;
    return b.ok() && j.is_object() && j.contains("format") && j.at("format") == kSceneJsonFormat;
}

Scene scene_from_json(const std::string& text) {
    const BoundedJson b = parse_json_bounded(text, kDocumentJsonLimits);
    if (!b.ok()) bad("document", b.detail);
    const json& j = b.value;
    if (!j.is_object()) bad("document", "not a JSON object");
    if (!j.contains("format") || j.at("format") != kSceneJsonFormat) bad("format", "not a nurbsrt NURBS scene");
    if (!j.contains("version") || j.at("version") != kSceneJsonVersion)
        bad("version", "only version " + std::to_string(kSceneJsonVersion) + " is known");
    Scene scene;
    const json& src = field(j, "source", "document");
    scene.source_name = string_field(src, "name");
    scene.format = string_field(src, "format");
    scene.units = string_field(src, "declared_units");
    const json& bodies = field(j, "bodies", "document");
    const json& faces = field(j, "faces", "document");
    if (!bodies.is_array() || !faces.is_array()) bad("document", "bodies and faces must be arrays");
    for (size_t b = 0; b < bodies.size(); ++b) {
        Body body;
        body.name = string_field(bodies[b], "name");
        read_color(field(bodies[b], "color", "bodies"), body.has_color, body.color,
                   "bodies[" + std::to_string(b) + "]");
        // Optional (documents written before it existed): an open body is cut without caps.
        if (bodies[b].contains("closed")) {
            const json& closed = bodies[b].at("closed");
            if (!closed.is_boolean()) bad("bodies[" + std::to_string(b) + "].closed", "must be true or false");
            body.closed = closed.get<bool>();
        }
        scene.bodies.push_back(std::move(body));
    }
    for (size_t i = 0; i < faces.size(); ++i) scene.faces.push_back(read_face(faces[i], i));
    if (j.contains("warnings") && j.at("warnings").is_array())
        for (const json& w : j.at("warnings"))
            if (w.is_string()) scene.warnings.push_back(w.get<std::string>());
    // Every structural rule a renderable Scene obeys (knot counts and order,
    // control point counts, parameter boxes, body indices) is checked once, by
    // the binary scene reader: round trip before meshing, which evaluates.
    scene = deserialize_scene(serialize_scene(scene));
    for (Face& f : scene.faces) {
        const std::string where = "faces[" + std::to_string(f.index - 1) + "]";
        const NurbsSurface& s = f.surface;
        const double tu = 1e-9 * (s.u_end() - s.u_begin()), tv = 1e-9 * (s.v_end() - s.v_begin());
        if (!(f.u_min < f.u_max && f.u_min >= s.u_begin() - tu && f.u_max <= s.u_end() + tu) ||
            !(f.v_min < f.v_max && f.v_min >= s.v_begin() - tv && f.v_max <= s.v_end() + tv))
            bad(where, "u_range / v_range must be a non-empty box inside the knot ranges");
        for (const Vec4& p : s.cp)
            if (!(p.w > 0)) bad(where, "control point weights must be positive");
        if (f.body >= scene.bodies.size() && !scene.bodies.empty()) bad(where, "body index out of range");
        grid_mesh(f);
        for (const Vec3& p : f.mesh.xyz) scene.bbox.extend(p);
    }
    return scene;
}

}  // namespace nurbsrt
