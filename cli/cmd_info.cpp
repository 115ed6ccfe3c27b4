// nurbsrt info FILE: what a CAD file holds once imported (format, units, box,
// counts of faces/patches/degrees/poles/trim loops), per-face details and the
// import's stage times, as text or JSON.
#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <optional>
#include <vector>
#include <chrono>
#include <cstdio>
#include <iostream>
#include <map>

#include "cli/commands.h"
#include "core/io/assembly_tree_json.h"
#include "importer/importer.h"
#include "importer/isolated.h"
#include "importer/shared_read.h"
#include "cli/validators.h"

namespace nurbsrt::cli {
namespace {

using nlohmann::json;

json vec_json(Vec3 v) { return json::array({v.x, v.y, v.z}); }

// The text form lists at most this many colours (the JSON all of them).
constexpr size_t kColoursListed = 8;

// "  0/1/2  name  N faces  colour r,g,b  at (x, y, z)", indented by depth.
void print_parts(const json& parts) {
    if (parts.empty()) return;
    std::printf("parts:       %zu in the assembly tree (id, name, faces, own colour, origin in mm)\n", parts.size());
    for (const json& p : parts) {
        const std::string id = p["id"].get<std::string>();
        const auto depth = static_cast<int>(std::count(id.begin(), id.end(), '/'));
        std::string color;
        if (!p["color"].is_null()) {
            char buf[64];
            std::snprintf(buf, sizeof buf, "  colour %.3g,%.3g,%.3g", p["color"][0].get<double>(),
                          p["color"][1].get<double>(), p["color"][2].get<double>());
            color = buf;
        }
        const json& m = p["placement"];
        std::printf(
            "  %*s%-*s %s  %u faces%s  at (%.6g, %.6g, %.6g)\n", 2 * depth, "", 10 - 2 * depth > 0 ? 10 - 2 * depth : 1,
            id.c_str(), p["name"].get<std::string>().empty() ? "(unnamed)" : p["name"].get<std::string>().c_str(),
            p["faces"].get<unsigned>(), color.c_str(), m[3].get<double>(), m[7].get<double>(), m[11].get<double>());
    }
}

json face_json(const Face& f, const Scene& scene) {
    const NurbsSurface& s = f.surface;
    size_t loop_points = 0;
    for (const TrimLoop& l : f.loops) loop_points += l.points.size();
    json j = {
        {"index", f.index},
        {"degree", {s.degree_u, s.degree_v}},
        {"poles", {s.num_u, s.num_v}},
        {"rational", s.rational},
        {"reversed", f.reversed},
        {"uv_box", {f.u_min, f.u_max, f.v_min, f.v_max}},
        {"trim_loops", f.loops.size()},
        {"trim_points", loop_points},
        {"trim_tolerance_uv", f.trim_tolerance_uv},
        {"mesh_triangles", f.mesh.triangles.size() / 3},
        {"mesh_fallback", f.mesh.fallback_grid},
        {"name", f.name},
    };
    if (f.body < scene.bodies.size()) j["body"] = scene.bodies[f.body].name;
    if (f.has_color) j["color"] = {f.color.r, f.color.g, f.color.b};
    return j;
}

// The faces' own colours, distinct (the same 8-bit colour is one; the first
// face's value shown), most used first.
json colours_json(const Scene& scene) {
    std::map<std::array<long, 3>, std::pair<Color, int>> count;
    for (const Face& f : scene.faces)
        if (f.has_color) {
            auto& [first, n] = count
                                   .try_emplace({std::lround(f.color.r * 255), std::lround(f.color.g * 255),
                                                 std::lround(f.color.b * 255)},
                                                f.color, 0)
                                   .first->second;
            ++n;
        }
    std::vector<std::pair<Color, int>> sorted;
    for (const auto& [key, value] : count) sorted.push_back(value);
    std::stable_sort(sorted.begin(), sorted.end(), [](const auto& a, const auto& b) { return a.second > b.second; });
    json colours = json::array();
    for (const auto& [c, faces] : sorted) colours.push_back({{"rgb", {c.r, c.g, c.b}}, {"faces", faces}});
    return colours;
}

json validity_json(const std::optional<ShapeValidity>& v) {
    if (!v) return nullptr;  // not checked (--isolated: the check would run outside the child)
    json j = {{"valid", v->valid},
              {"invalid",
               {{"solids", v->invalid_solids},
                {"shells", v->invalid_shells},
                {"faces", v->invalid_faces},
                {"edges", v->invalid_edges}}},
              {"check_ms", v->check_ms}};
    if (!v->failure.empty()) j["failure"] = v->failure;
    return j;
}

json scene_summary(const Scene& scene, bool per_face, double total_ms) {
    std::map<std::string, int> degrees;
    size_t rational = 0, reversed = 0, poles = 0, max_poles = 0, loops = 0, inner = 0, triangles = 0, fallback = 0,
           colored = 0;
    for (const Face& f : scene.faces) {
        const NurbsSurface& s = f.surface;
        degrees[std::to_string(s.degree_u) + "x" + std::to_string(s.degree_v)]++;
        rational += s.rational;
        reversed += f.reversed;
        const size_t n = static_cast<size_t>(s.num_u) * s.num_v;
        poles += n;
        max_poles = std::max(max_poles, n);
        loops += f.loops.size();
        for (const TrimLoop& l : f.loops) inner += !l.outer;
        triangles += f.mesh.triangles.size() / 3;
        fallback += f.mesh.fallback_grid;
        colored += f.has_color;
    }
    json j = {
        {"file", scene.source_name},
        {"format", scene.format},
        {"units", scene.units},
        {"coordinates_unit", "mm"},
        {"bbox",
         {{"min", vec_json(scene.bbox.lo)}, {"max", vec_json(scene.bbox.hi)}, {"diagonal", scene.bbox.diagonal()}}},
        {"faces", scene.faces.size()},
        {"bodies", scene.bodies.size()},
        {"patches",
         {{"bspline", scene.faces.size()},
          {"rational", rational},
          {"polynomial", scene.faces.size() - rational},
          {"reversed", reversed},
          {"degrees", degrees}}},
        {"poles", {{"total", poles}, {"max_per_face", max_poles}}},
        {"trim_loops", {{"total", loops}, {"inner", inner}, {"outer", loops - inner}}},
        {"mesh", {{"triangles", triangles}, {"fallback_faces", fallback}}},
        {"colored_faces", colored},
        {"colours", colours_json(scene)},
        {"timings_ms",
         {{"read", scene.timings.read_ms},
          {"nurbs_convert", scene.timings.nurbs_convert_ms},
          {"mesh", scene.timings.mesh_ms},
          {"total", total_ms}}},
        {"warnings", scene.warnings},
        {"parts", assembly_tree_json(scene)},
    };
    if (per_face) {
        json faces = json::array();
        for (const Face& f : scene.faces) faces.push_back(face_json(f, scene));
        j["face_list"] = std::move(faces);
    }
    return j;
}

void print_text(const json& j) {
    auto v3 = [](const json& a) {
        char buf[128];
        std::snprintf(buf, sizeof buf, "(%.6g, %.6g, %.6g)", a[0].get<double>(), a[1].get<double>(),
                      a[2].get<double>());
        return std::string(buf);
    };
    std::printf("file:        %s\n", j["file"].get<std::string>().c_str());
    std::printf("format:      %s, declared units %s (coordinates in mm)\n", j["format"].get<std::string>().c_str(),
                j["units"].get<std::string>().empty() ? "unknown" : j["units"].get<std::string>().c_str());
    std::printf("bbox:        %s .. %s, diagonal %.6g mm\n", v3(j["bbox"]["min"]).c_str(), v3(j["bbox"]["max"]).c_str(),
                j["bbox"]["diagonal"].get<double>());
    const json& p = j["patches"];
    std::printf(
        "faces:       %zu in %zu bodies (B-spline %zu: rational %zu, polynomial %zu; reversed %zu; "
        "with a colour of their own %zu)\n",
        j["faces"].get<size_t>(), j["bodies"].get<size_t>(), p["bspline"].get<size_t>(), p["rational"].get<size_t>(),
        p["polynomial"].get<size_t>(), p["reversed"].get<size_t>(), j["colored_faces"].get<size_t>());
    std::string degrees;
    for (const auto& [k, v] : p["degrees"].items()) degrees += (degrees.empty() ? "" : ", ") + k + ": " + v.dump();
    std::printf("degrees:     %s\n", degrees.c_str());
    std::printf("poles:       %zu (at most %zu on one face)\n", j["poles"]["total"].get<size_t>(),
                j["poles"]["max_per_face"].get<size_t>());
    std::printf("trim loops:  %zu (%zu outer, %zu inner)\n", j["trim_loops"]["total"].get<size_t>(),
                j["trim_loops"]["outer"].get<size_t>(), j["trim_loops"]["inner"].get<size_t>());
    std::printf("mesh:        %zu triangles (uv-grid fallback on %zu faces)\n", j["mesh"]["triangles"].get<size_t>(),
                j["mesh"]["fallback_faces"].get<size_t>());
    const json& t = j["timings_ms"];
    std::printf("timings:     read %.1f ms, nurbs_convert %.1f ms, mesh %.1f ms, total %.1f ms\n",
                t["read"].get<double>(), t["nurbs_convert"].get<double>(), t["mesh"].get<double>(),
                t["total"].get<double>());
    std::string colours;
    size_t listed = 0;
    for (const json& c : j["colours"]) {
        if (++listed > kColoursListed) {
            colours += ", ...";
            break;
        }
        char buf[96];
        std::snprintf(buf, sizeof buf, "%s%.3g,%.3g,%.3g (%d faces)", colours.empty() ? "" : ", ",
                      c["rgb"][0].get<double>(), c["rgb"][1].get<double>(), c["rgb"][2].get<double>(),
                      c["faces"].get<int>());
        colours += buf;
    }
    std::printf("colours:     %zu distinct%s%s\n", j["colours"].size(), colours.empty() ? "" : ": ", colours.c_str());
    if (const json& v = j["validity"]; v.is_null()) {
        std::printf("validity:    not checked (--isolated)\n");
    } else if (v["valid"].get<bool>()) {
        std::printf("validity:    valid (BRepCheck_Analyzer, %.1f ms)\n", v["check_ms"].get<double>());
    } else {
        const json& n = v["invalid"];
        std::printf(
            "validity:    INVALID (BRepCheck_Analyzer): %d solid(s), %d shell(s), %d face(s), %d edge(s) invalid%s%s\n",
            n["solids"].get<int>(), n["shells"].get<int>(), n["faces"].get<int>(), n["edges"].get<int>(),
            v.contains("failure") ? "; the checker failed: " : "",
            v.contains("failure") ? v["failure"].get<std::string>().c_str() : "");
    }
    print_parts(j["parts"]);
    for (const auto& w : j["warnings"]) std::printf("warning:     %s\n", w.get<std::string>().c_str());
    if (j.contains("face_list")) {
        std::printf("\n%6s %7s %9s %4s %4s %6s %6s  %s\n", "face", "degree", "poles", "rat", "rev", "loops", "tris",
                    "name");
        for (const json& f : j["face_list"]) {
            std::printf("%6u %3dx%-3d %4dx%-4d %4s %4s %6zu %6zu  %s\n", f["index"].get<unsigned>(),
                        f["degree"][0].get<int>(), f["degree"][1].get<int>(), f["poles"][0].get<int>(),
                        f["poles"][1].get<int>(), f["rational"].get<bool>() ? "yes" : "no",
                        f["reversed"].get<bool>() ? "yes" : "no", f["trim_loops"].get<size_t>(),
                        f["mesh_triangles"].get<size_t>(), f["name"].get<std::string>().c_str());
        }
    }
}

}  // namespace

void add_info_command(CLI::App& app) {
    struct Args {
        std::string file;
        bool json = false, faces = false, isolated = false;
        bool no_attributes = false;
        ImportOptions options;
        double time_limit_s = 300;
    };
    auto a = std::make_shared<Args>();
    auto* cmd =
        app.add_subcommand("info",
                           "Import a STEP, IGES or BREP file and describe it: format, declared units, bounding\n"
                           "box, faces, B-spline degrees, poles, trim loops, mesh, colours, validity\n"
                           "(BRepCheck_Analyzer), the assembly tree with names, and the import's stage times.\n"
                           "Example: nurbsrt info part.step --faces");
    cmd->add_option("FILE", a->file, "STEP or IGES file (format recognised from its content)")
        ->required()
        ->check(CLI::ExistingFile);
    cmd->add_flag("--json", a->json, "print JSON instead of text");
    cmd->add_flag("--faces", a->faces, "list every face (degree, poles, loops, triangles, name)");
    cmd->add_flag("--isolated", a->isolated, "import in a child process with a time limit (as the service does)");
    cmd->add_option("--time-limit", a->time_limit_s, "seconds allowed for an --isolated import")
        ->check(CLI::PositiveNumber);
    cmd->add_option("--mesh-deflection", a->options.mesh_relative_deflection,
                    "preliminary-map mesh deflection, fraction of the bounding-box diagonal")
        ->check(in_range(1e-6, 0.5))
        ->capture_default_str();
    // A plain flag, applied in the callback: CLI11 2.1 prints a negated flag's
    // default into the help ("--no-attributes{false}").
    cmd->add_flag("--no-attributes", a->no_attributes, "skip colours and names (plain readers instead of XDE; faster)");
    cmd->callback([a] {
        a->options.read_attributes = !a->no_attributes;
        const auto t0 = std::chrono::steady_clock::now();
        Scene scene;
        std::optional<ShapeValidity> validity;
        if (a->isolated) {
            IsolationLimits limits;
            limits.time_limit_s = a->time_limit_s;
            scene = import_isolated(a->file, a->options, limits);
        } else {
            // One read for the import and the validity check.
            SharedRead read(a->file);
            scene = import_file(a->file, a->options);
            validity = check_validity(a->file);
        }
        const double total_ms =
            std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
        json j = scene_summary(scene, a->faces, total_ms);
        j["validity"] = validity_json(validity);
        if (a->json)
            std::cout << j.dump(2) << "\n";
        else
            print_text(j);
    });
}

}  // namespace nurbsrt::cli
