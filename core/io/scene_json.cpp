// Scene -> JSON (see scene_json.h). Built as an ordered_json so that the keys
// appear in the documented order, which makes the files readable by people.
#include "core/io/scene_json.h"

#include <cmath>
#include <fstream>

#include <nlohmann/json.hpp>

#include "core/error.h"

namespace nurbsrt {
namespace {

using json = nlohmann::ordered_json;

// nlohmann would silently print NaN/inf as null too; doing it here makes the
// rule visible and independent of the library's default.
json num(double v) { return std::isfinite(v) ? json(v) : json(nullptr); }

json vec(std::initializer_list<double> values) {
    json a = json::array();
    for (double v : values) a.push_back(num(v));
    return a;
}

json numbers(const std::vector<double>& values) {
    json a = json::array();
    for (double v : values) a.push_back(num(v));
    return a;
}

json color(bool has, const Color& c) { return has ? vec({c.r, c.g, c.b}) : json(nullptr); }

json surface_json(const NurbsSurface& s) {
    json cps = json::array();
    for (const Vec4& p : s.cp) cps.push_back(vec({p.x, p.y, p.z, p.w}));
    return {{"degree_u", s.degree_u},
            {"degree_v", s.degree_v},
            {"num_u", s.num_u},
            {"num_v", s.num_v},
            {"rational", s.rational},
            {"knots_u", numbers(s.knots_u)},
            {"knots_v", numbers(s.knots_v)},
            {"control_points", std::move(cps)}};
}

json face_json(const Face& f) {
    json loops = json::array();
    for (const TrimLoop& l : f.loops) {
        json pts = json::array();
        for (const Vec2& p : l.points) pts.push_back(vec({p.x, p.y}));
        loops.push_back({{"outer", l.outer}, {"points", std::move(pts)}});
    }
    return {{"index", f.index},
            {"body", f.body},
            {"name", f.name},
            {"color", color(f.has_color, f.color)},
            {"reversed", f.reversed},
            {"surface", surface_json(f.surface)},
            {"u_range", vec({f.u_min, f.u_max})},
            {"v_range", vec({f.v_min, f.v_max})},
            {"trim_tolerance_uv", num(f.trim_tolerance_uv)},
            {"trim_loops", std::move(loops)}};
}

json scene_json(const Scene& scene) {
    json bodies = json::array();
    for (const Body& b : scene.bodies)
        bodies.push_back({{"name", b.name}, {"color", color(b.has_color, b.color)}, {"closed", b.closed}});
    json faces = json::array();
    for (const Face& f : scene.faces) faces.push_back(face_json(f));
    const json bbox = scene.bbox.empty() ? json(nullptr)
                                         : json{{"min", vec({scene.bbox.lo.x, scene.bbox.lo.y, scene.bbox.lo.z})},
                                                {"max", vec({scene.bbox.hi.x, scene.bbox.hi.y, scene.bbox.hi.z})}};
    return {{"format", kSceneJsonFormat},
            {"version", kSceneJsonVersion},
            {"source", {{"name", scene.source_name}, {"format", scene.format}, {"declared_units", scene.units}}},
            {"units", "mm"},
            {"bbox", bbox},
            {"patches", scene.faces.size()},
            {"bodies", std::move(bodies)},
            {"faces", std::move(faces)},
            {"warnings", scene.warnings}};
}

// Names and warnings come from CAD files and may hold bytes that are not UTF-8
// (Latin-1 names in old IGES files): replace them rather than fail the dump.
std::string dump(const json& j, int indent) { return j.dump(indent, ' ', false, json::error_handler_t::replace); }

}  // namespace

std::string scene_to_json(const Scene& scene, int indent) { return dump(scene_json(scene), indent); }

void write_scene_json(const Scene& scene, std::ostream& out) {
    out << scene_to_json(scene) << '\n';
    if (!out) throw Error(ErrorCode::io, "cannot write the scene JSON");
}

void write_scene_json_file(const Scene& scene, const std::string& path) {
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    if (!out) throw Error(ErrorCode::io, "cannot write '" + path + "'");
    write_scene_json(scene, out);
    out.close();
    if (!out) throw Error(ErrorCode::io, "cannot write '" + path + "'");
}

}  // namespace nurbsrt
