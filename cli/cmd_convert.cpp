// nurbsrt convert IN OUT: STEP/IGES/BREP to STEP, IGES, BREP, STL, glb, VRML, OBJ or
// NURBS JSON, the output format from OUT's extension; nurbsrt convert FILES...
// --out-dir DIR --format F: every input in one process.
#include <CLI/CLI.hpp>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include <unistd.h>

#include "cli/commands.h"
#include "cli/validators.h"
#include "cli/warnings.h"
#include "core/error.h"
#include "importer/importer.h"
#include "options/render_request.h"

#include <nlohmann/json.hpp>

namespace nurbsrt::cli {
namespace {

// The fidelity report in a few lines (the whole of it: --report FILE).
void print_fidelity(const std::string& text) {
    if (text.empty()) return;
    const nlohmann::json f = nlohmann::json::parse(text);
    const nlohmann::json& src = f["source"];
    const nlohmann::json& d = f["relative_differences"];
    auto num = [](const nlohmann::json& j, const char* k) { return j.contains(k) ? j[k].get<double>() : 0.0; };
    if (f["output"].contains("geometry")) {
        const nlohmann::json &a = src["geometry"], &b = f["output"]["geometry"];
        std::fprintf(stderr,
                     "nurbsrt: fidelity: solids %d -> %d, shells %d -> %d, faces %d -> %d, edges %d -> %d; relative "
                     "difference of volume %.2g, area %.2g, box %.2g; valid %s -> %s\n",
                     a["solids"].get<int>(), b["solids"].get<int>(), a["shells"].get<int>(), b["shells"].get<int>(),
                     a["faces"].get<int>(), b["faces"].get<int>(), a["edges"].get<int>(), b["edges"].get<int>(),
                     num(d, "volume"), num(d, "area"), num(d, "box"), a["valid"].get<bool>() ? "yes" : "no",
                     b["valid"].get<bool>() ? "yes" : "no");
        const nlohmann::json& at = f["attributes"];
        std::fprintf(stderr, "nurbsrt: fidelity: coloured faces %d -> %d, names %d -> %d (%d lost)\n",
                     at["colours"]["source_coloured_faces"].get<int>(),
                     at["colours"]["output_coloured_faces"].get<int>(), at["names"]["source"].get<int>(),
                     at["names"]["output"].get<int>(), at["names"]["lost"].get<int>());
    } else if (f["output"].contains("mesh_in_mm")) {
        std::fprintf(stderr,
                     "nurbsrt: fidelity: mesh against the exact faces: relative difference of area %.2g, box %.2g",
                     num(d, "area"), num(d, "box"));
        if (d.contains("volume")) std::fprintf(stderr, ", enclosed volume %.2g", num(d, "volume"));
        if (d.contains("volume_centroid")) std::fprintf(stderr, ", volume centroid %.2g", num(d, "volume_centroid"));
        const nlohmann::json& mesh = f["output"]["mesh_in_mm"];
        std::fprintf(stderr, "; edges: %lld open, %lld non-manifold\n", mesh["open_edges"].get<long long>(),
                     mesh["non_manifold_edges"].get<long long>());
        const nlohmann::json& asked = f["output"]["asked"];
        if (const nlohmann::json& dev = f["output"]["deviation_in_mm"]; dev.is_object())
            std::fprintf(stderr,
                         "nurbsrt: fidelity: deviation of %lld vertices and centroids from the trimmed faces: max "
                         "%.3g mm (%.2g of the diagonal), p99 %.3g mm, mean %.3g mm; asked: deflection %.3g of the "
                         "diagonal (%.3g mm), angular deflection %.3g rad\n",
                         dev["points"].get<long long>(), dev["max"].get<double>(),
                         dev["relative_to_diagonal"]["max"].get<double>(), dev["p99"].get<double>(),
                         dev["mean"].get<double>(), num(asked, "deflection"), num(asked, "deflection_mm"),
                         num(asked, "angular_deflection"));
    }
}

struct ConvertArgs {
    std::vector<std::string> files;  // IN OUT, or with out_dir every input
    std::string out_dir, format;
    bool quiet = false, strict = false;
    std::string units, report_path;
    std::string schema = step_schema_name(StepSchema::ap214);
    std::string mode = iges_mode_name(IgesMode::brep);
    double deflection = 0.0;
    double angular = kDefaultAngularDeflection;
};

// The request model of POST /v1/conversions and of the jobs (options/render_request.h),
// its values checked by the same checks as the flags; an option `format` does
// not take is a usage error, never ignored (as the API refuses it).
ConversionRequest request_of(const CLI::App& cmd, const ConvertArgs& a, ConversionFormat format) {
    for (const auto& [flag, option] :
         {std::pair{"--units", ConversionOption::units}, std::pair{"--step-schema", ConversionOption::step_schema},
          std::pair{"--iges-mode", ConversionOption::iges_mode},
          std::pair{"--deflection", ConversionOption::deflection},
          std::pair{"--angular-deflection", ConversionOption::angular_deflection}})
        if (const std::string why = conversion_option_refusal(option, format); cmd.count(flag) > 0 && !why.empty())
            throw CLI::ValidationError(flag, why);
    ConversionRequest request;
    request.format = format;
    request.strict = a.strict;
    ConvertOptions& options = request.options;
    options.units = length_unit_from_name(a.units).value_or(LengthUnit::unknown);
    options.step_schema = step_schema_from_name(a.schema).value_or(StepSchema::ap214);
    options.iges_mode = iges_mode_from_name(a.mode).value_or(IgesMode::brep);
    options.deflection = a.deflection;
    options.angular_deflection = a.angular;
    return request;
}

void print_summary(const std::string& in, const std::string& out, const ConvertReport& r) {
    std::fprintf(stderr, "nurbsrt: converted %s (%s, %s, %d faces) to %s (%s", in.c_str(), format_name(r.in_format),
                 r.in_units.empty() ? "no unit declared" : r.in_units.c_str(), r.faces, out.c_str(),
                 conversion_format_name(r.output));
    if (!r.out_units.empty()) std::fprintf(stderr, ", %s", r.out_units.c_str());
    if (r.triangles > 0) std::fprintf(stderr, ", %lld triangles", r.triangles);
    if (r.degenerate_triangles > 0)
        std::fprintf(stderr, " (%lld of no area or repeated left out)", r.degenerate_triangles);
    std::fprintf(stderr, "): read %.1f ms", r.read_ms);
    if (r.mesh_ms > 0) std::fprintf(stderr, ", mesh %.1f ms", r.mesh_ms);
    std::fprintf(stderr, ", write %.1f ms", r.write_ms);
    if (r.verify_ms > 0) std::fprintf(stderr, ", verify %.1f ms", r.verify_ms);
    std::fputc('\n', stderr);
}

// One conversion: written under OUT's own name in a temporary directory beside
// it (the writer picks the format by the extension, and OBJ names its .mtl
// after the stem), moved out when kept: OUT exists only complete, and not at
// all when --strict refuses it.
void convert_one(const std::string& in, const std::string& out, const ConversionRequest& request,
                 const std::string& report_path, bool quiet) {
    // Removes the partial files on every way out but the renames below.
    struct PartialDir {
        std::filesystem::path path;
        ~PartialDir() {
            std::error_code ec;
            if (!path.empty()) std::filesystem::remove_all(path, ec);
        }
    };
    const std::filesystem::path target(out);
    PartialDir partial{target.parent_path() /
                       ("." + target.stem().string() + ".partial-" + std::to_string(::getpid()))};
    std::filesystem::create_directory(partial.path);
    const std::filesystem::path written = partial.path / target.filename();
    const ConvertReport r = convert_file(in, written.string(), request.options);
    if (!report_path.empty()) {
        std::ofstream report(report_path, std::ios::binary | std::ios::trunc);
        nlohmann::ordered_json j =
            r.fidelity.empty() ? nlohmann::ordered_json::object() : nlohmann::ordered_json::parse(r.fidelity);
        j["warnings"] = r.warnings;
        report << j.dump(2) << '\n';
        if (!report) throw Error(ErrorCode::io, "cannot write the report '" + report_path + "'");
    }
    if (!quiet) print_fidelity(r.fidelity);
    report_warnings(r.warnings, quiet, request.strict);
    // OUT, and what a format writes beside it (OBJ's .mtl).
    for (const std::filesystem::directory_entry& e : std::filesystem::directory_iterator(partial.path))
        std::filesystem::rename(e.path(), target.parent_path() / e.path().filename());
    if (!quiet) print_summary(in, out, r);
}

// --out-dir: every input to DIR/STEM.EXT, one after the other; two inputs of
// one stem would overwrite each other, so that is a usage error before any
// work. A file that fails is reported with its error and the rest go on; the
// command then fails naming how many did.
void convert_each(const CLI::App& cmd, const ConvertArgs& a) {
    if (a.format.empty()) throw CLI::ValidationError("--format", "--out-dir needs the output format (--format)");
    const ConversionFormat format = conversion_format_from_name(a.format);
    const ConversionRequest request = request_of(cmd, a, format);
    std::vector<std::string> outs;
    for (const std::string& in : a.files) {
        if (const std::string why = CLI::ExistingFile(in); !why.empty()) throw CLI::ValidationError("FILES", why);
        const std::string stem = std::filesystem::path(in).stem().string();
        const std::string out =
            (std::filesystem::path(a.out_dir) / (stem + conversion_format_extension(format))).string();
        for (size_t k = 0; k < outs.size(); ++k)
            if (outs[k] == out)
                throw CLI::ValidationError("FILES", a.files[k] + " and " + in + " would both write " + out);
        outs.push_back(out);
    }
    size_t failed = 0;
    for (size_t k = 0; k < a.files.size(); ++k) {
        const std::string report = a.report_path.empty()
                                       ? ""
                                       : (std::filesystem::path(a.out_dir) /
                                          (std::filesystem::path(a.files[k]).stem().string() + ".fidelity.json"))
                                             .string();
        try {
            convert_one(a.files[k], outs[k], request, report, a.quiet);
        } catch (const WarningsRefused& e) {
            ++failed;
            std::fprintf(stderr, "nurbsrt: %s: error [strict]: %s\n", a.files[k].c_str(), e.what());
        } catch (const Error& e) {
            ++failed;
            std::fprintf(stderr, "nurbsrt: %s: error [%s]: %s\n", a.files[k].c_str(), error_code_name(e.code()),
                         e.what());
        }
    }
    if (!a.quiet)
        std::fprintf(stderr, "nurbsrt: converted %zu of %zu files into %s\n", a.files.size() - failed, a.files.size(),
                     a.out_dir.c_str());
    if (failed)
        throw Error(ErrorCode::invalid_argument, std::to_string(failed) + " of " + std::to_string(a.files.size()) +
                                                     " files failed (each reported above); the others were written");
}

void run_convert(const CLI::App& cmd, const ConvertArgs& a) {
    if (!a.out_dir.empty()) return convert_each(cmd, a);
    if (!a.format.empty()) throw CLI::ValidationError("--format", "is for --out-dir; OUT's extension names the format");
    if (a.files.size() != 2)
        throw CLI::ValidationError("FILES", "give IN and OUT, or several inputs with --out-dir DIR --format F");
    const std::string &in = a.files[0], &out = a.files[1];
    if (const std::string why = CLI::ExistingFile(in); !why.empty()) throw CLI::ValidationError("IN", why);
    if (const std::string why = output_file_validator(
            {".stp", ".step", ".igs", ".iges", ".stl", ".glb", ".obj", ".json", ".brep", ".brp", ".wrl", ".vrml"})(out);
        !why.empty())
        throw CLI::ValidationError("OUT", why);
    convert_one(in, out, request_of(cmd, a, conversion_format_from_extension(out)), a.report_path, a.quiet);
}

}  // namespace

void add_convert_command(CLI::App& app) {
    auto* cmd =
        app.add_subcommand("convert",
                           "Convert a STEP, IGES or BREP file. The input format is recognised from the\n"
                           "content, the output format from OUT's extension:\n"
                           "  .stp/.step  STEP AP214 (or --step-schema ap242; exact geometry) with face\n"
                           "              colours, names, layers and\n"
                           "              the assembly structure (IGES groups of named members become\n"
                           "              assemblies, one part per member)\n"
                           "  .igs/.iges  IGES 5.3, BRep mode (or --iges-mode faces: trimmed surfaces without\n"
                           "              topology; exact geometry) with face colours, names and\n"
                           "              layers; IGES has no assemblies: instances become a flat list\n"
                           "              (STEP/IGES: written in the source's length unit unless --units\n"
                           "              names another; the written file is read back; what it lost is\n"
                           "              printed as warnings)\n"
                           "  .stl        binary STL, millimetres (mesh: deflection 0.002 x bounding-box diagonal, or\n"
                           "              --deflection;\n"
                           "              triangles of no area or repeated are left out, and counted)\n"
                           "  .glb        binary glTF 2.0 with colours, names and assembly instances; glTF axes\n"
                           "              and units: Y-up, metres ((x, y, z) mm -> (x, z, -y) / 1000 m)\n"
                           "  .obj        Wavefront OBJ, millimetres, one object per part instance, and\n"
                           "              its materials (the face colours) in a .mtl file of the same stem\n"
                           "              beside it (mesh as for .stl)\n"
                           "  .brep       OCCT's own text format: exact geometry and topology, millimetres; no\n"
                           "              colours, names or assembly (the written file is read back too)\n"
                           "  .wrl        VRML 2.0, millimetres, with colours and the assembly's placements (mesh\n"
                           "              as for .stl)\n"
                           "  .json       the NURBS patches (degrees, knots, homogeneous control points, trim\n"
                           "              loops, face attributes); schema: api_schema/nurbs_scene.schema.json\n"
                           "Examples: nurbsrt convert part.step part.igs\n"
                           "          nurbsrt convert part.igs part.glb\n"
                           "          nurbsrt convert parts/*.step --out-dir meshes --format stl");
    auto a = std::make_shared<ConvertArgs>();
    cmd->add_option("FILES", a->files,
                    "IN OUT: the input (STEP, IGES or BREP) and the output file (.stp, .step, .igs, .iges, .stl,\n"
                    ".glb, .obj, .json, .brep or .wrl); with --out-dir, every input")
        ->required();
    cmd->add_option("--out-dir", a->out_dir,
                    "convert every input FILE into this directory, as DIR/STEM.EXT in --format, one after the\n"
                    "other in this process (the libraries set up once); a file that fails is reported and the\n"
                    "rest go on")
        ->check(CLI::ExistingDirectory);
    cmd->add_option("--format", a->format, "the output format of --out-dir: " + conversion_format_names())
        ->check(CLI::Validator(
            [](std::string& s) {
                return conversion_format_from_name(s) == ConversionFormat::unknown
                           ? "not an output format; one of " + conversion_format_names()
                           : std::string();
            },
            "FORMAT"));
    cmd->add_option("--units", a->units,
                    "STEP/IGES outputs: the length unit to write (the geometry is scaled to it); default: the\n"
                    "source's")
        ->check(CLI::IsMember(length_unit_names()));
    cmd->add_option("--step-schema", a->schema, "STEP outputs: the application protocol, ap214 or ap242")
        ->check(CLI::IsMember(step_schema_names()))
        ->capture_default_str();
    cmd->add_option("--iges-mode", a->mode, "IGES outputs: brep (solids and shells) or faces (trimmed surfaces)")
        ->check(CLI::IsMember(iges_mode_names()))
        ->capture_default_str();
    cmd->add_option("--deflection", a->deflection,
                    "STL, glb, VRML and OBJ outputs: the mesh's linear deflection, a fraction of the model's\n"
                    "bounding-box diagonal (default 0.002)")
        ->check(CLI::Range(std::numeric_limits<double>::min(), kMaxConversionDeflection));
    // Checked by the request model's own check (the API's and the jobs' option), before the import.
    cmd->add_option("--angular-deflection", a->angular,
                    "STL, glb, VRML and OBJ outputs: the mesh's angular deflection, radians (the largest turn of\n"
                    "the normal along a triangle's edge)")
        ->capture_default_str()
        ->check(shared_check(
            // CLI11 names the flag before the message.
            [](const std::string& s) { checked_angular_deflection(std::stod(s), "'" + s + "'"); }, "RADIANS"));
    cmd->add_option("--report", a->report_path,
                    "write the fidelity report (JSON: source and output measured and compared) to this file,\n"
                    "also when --strict refuses the conversion (with --out-dir: DIR/STEM.fidelity.json of each)")
        ->check(output_file_validator({".json"}));
    cmd->add_flag("-q,--quiet", a->quiet, "no summary or warnings on stderr");
    cmd->add_flag("--strict", a->strict,
                  "fail with exit status 3, writing nothing, when the conversion has warnings (something lost)");
    cmd->callback([cmd, a] { run_convert(*cmd, *a); });
}

}  // namespace nurbsrt::cli
