// convert_file: checks the output, then dispatches on its extension to the
// writer of that format (convert_writers.h); the NURBS JSON dump is the
// imported Scene written by core/io/scene_json.h.
#include <chrono>
#include <filesystem>

#include "importer/convert/convert_writers.h"
#include "importer/importer.h"
#include "importer/internal.h"
#include "core/error.h"
#include "core/io/scene_json.h"

namespace nurbsrt {
namespace {

double ms_since(std::chrono::steady_clock::time_point t0) {
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

void write_nurbs_json(const std::string& in_path, const std::string& out_path, ConvertReport& r) {
    const Scene scene = import_file(in_path);
    r.in_format = detect_format(in_path);
    r.faces = static_cast<int>(scene.faces.size());
    r.in_units = scene.units;
    r.read_ms = scene.timings.read_ms;
    r.mesh_ms = scene.timings.nurbs_convert_ms + scene.timings.mesh_ms;
    const auto t0 = std::chrono::steady_clock::now();
    write_scene_json_file(scene, out_path);
    r.write_ms = ms_since(t0);
}

}  // namespace

ConvertReport convert_file(const std::string& in_path, const std::string& out_path, const ConvertOptions& options) {
    ConvertReport r;
    r.output = conversion_format_from_extension(out_path);
    r.out_format = cad_format_of(r.output);
    if (r.output == ConversionFormat::unknown)
        throw Error(ErrorCode::unsupported_format,
                    "output '" + out_path +
                        "': unknown extension (use .stp/.step, .igs/.iges, .stl, .glb, .obj, .json, .brep or .wrl)");
    if (const std::string why = conversion_option_refusal(ConversionOption::units, r.output);
        options.units != LengthUnit::unknown && !why.empty())
        throw Error(ErrorCode::invalid_argument, std::string("option 'units' ") + why + "; " +
                                                     conversion_format_name(r.output) + " has a unit of its own");
    if (const std::string why = conversion_option_refusal(ConversionOption::deflection, r.output);
        options.deflection != 0 && !why.empty())
        throw Error(ErrorCode::invalid_argument, std::string("option 'deflection' ") + why);
    if (const std::string why = conversion_option_refusal(ConversionOption::angular_deflection, r.output);
        options.angular_deflection != kDefaultAngularDeflection && !why.empty())
        throw Error(ErrorCode::invalid_argument, std::string("option 'angular_deflection' ") + why);
    if (!(options.angular_deflection >= kMinAngularDeflection && options.angular_deflection <= kMaxAngularDeflection))
        throw Error(ErrorCode::invalid_argument, "option 'angular_deflection' is out of range");
    if (!(options.deflection >= 0 && options.deflection <= kMaxConversionDeflection))
        throw Error(ErrorCode::invalid_argument,
                    "option 'deflection' must be in (0, " + std::to_string(kMaxConversionDeflection) + "]");
    if (const LengthUnit fixed = conversion_format_fixed_unit(r.output); fixed != LengthUnit::unknown)
        r.out_units = length_unit_name(fixed);
    const std::filesystem::path out_dir = std::filesystem::path(out_path).parent_path();
    std::error_code ec;
    if (!out_dir.empty() && !std::filesystem::is_directory(out_dir, ec))
        throw Error(ErrorCode::io, "cannot write '" + out_path + "': no such directory");

    // A shared read's shape may carry the triangulations of an earlier use:
    // the import's are gone, so that BRepMesh meshes anew and BREP writes
    // none; another mesh output's stay for mesh_for_export, which takes them
    // over at the same parameters (with what it counted) or meshes anew.
    occt::forget_shared_meshes(/*keep_export_mesh=*/conversion_format_is_mesh(r.output));
    switch (r.output) {
        case ConversionFormat::step:
        case ConversionFormat::iges:
        case ConversionFormat::brep:
            occt::write_cad(in_path, out_path, options, r);
            break;
        case ConversionFormat::vrml:
            occt::write_vrml(in_path, out_path, options, r);
            break;
        case ConversionFormat::stl:
            occt::write_stl(in_path, out_path, options, r);
            break;
        case ConversionFormat::glb:
            occt::write_glb(in_path, out_path, options, r);
            break;
        case ConversionFormat::obj:
            occt::write_obj(in_path, out_path, options, r);
            break;
        case ConversionFormat::nurbs_json:
            write_nurbs_json(in_path, out_path, r);
            break;
        case ConversionFormat::unknown:
            break;
    }
    // A unit the source declares that the file cannot say is a change a
    // reader will not see (it assumes mm).
    const std::string declared = r.in_units.substr(0, r.in_units.find(','));
    if (conversion_format_is_unitless(r.output) && !declared.empty() && declared != r.out_units)
        r.warnings.push_back(std::string("the source is in ") + declared + "; " + conversion_format_name(r.output) +
                             " files have no unit: the coordinates are written in " + r.out_units);
    return r;
}

}  // namespace nurbsrt
