// The importer's public interface: STEP/IGES/BREP bytes in, a Scene out.
// This header is OCCT-free on purpose (it is included by cli/ and server/);
// everything that touches OCCT lives in importer/*.cpp.
#pragma once

#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "core/scene/scene.h"

namespace nurbsrt {

enum class CadFormat { unknown, step, iges, brep };

// Recognise the format from the file's content (STEP: "ISO-10303-21;" header;
// IGES: 80-column records with the S/G/D/P/T section letter in column 73;
// BREP: OCCT's text format, "CASCADE Topology V..."), not from its extension.
CadFormat detect_format(const std::string& path);
CadFormat detect_format_bytes(const char* data, size_t size);
const char* format_name(CadFormat f);  // "STEP", "IGES", "BREP", "unknown"
// Format implied by a file name's extension (.stp/.step, .igs/.iges, .brep/.brp), for outputs.
CadFormat format_from_extension(const std::string& path);

// BRepMesh's angular deflection, radians: the largest turn of the surface
// normal along one triangle edge. 0.35 rad (20 degrees) puts 18 segments on
// every circle whatever its size, where the linear deflection alone (0.002 of
// the diagonal) would leave a hole of 1% of the diagonal a triangle.
inline constexpr double kDefaultAngularDeflection = 0.35;
// The range a request may ask: below 0.01 rad a circle gets over 600 segments,
// finer than any view shows, and the mesh of a curved part grows without bound
// as the angle shrinks; above pi/2 (a circle of 4 segments) the angle bounds
// nothing the linear deflection does not.
inline constexpr double kMinAngularDeflection = 0.01;
inline constexpr double kMaxAngularDeflection = 1.5707963267948966;

struct ImportOptions {
    // Mesh for the preliminary map: linear deflection as a fraction of the
    // model's bounding-box diagonal, and angular deflection in radians.
    double mesh_relative_deflection = 0.002;
    double mesh_angular_deflection = kDefaultAngularDeflection;
    // Wall-clock budget for BRepMesh on the whole model, seconds; faces still
    // unmeshed when it runs out get the trimmed-grid fallback (with a warning).
    double mesh_time_limit_s = 60.0;
    // Trim loops: maximum deviation of the (u,v) polyline from its pcurve, as a
    // fraction of the face's parameter-box diagonal. It sets the trim band (twice
    // the trim test's uncertainty), in which a hit near an edge counts for cracks
    // and light rays count as grazing an edge. A coarser tolerance makes the band
    // exceed a model's own edge tolerance many times over (light rays beside an
    // edge taken as blocked) and lets a chord of a loop cut off pixels the exact
    // face covers; 3e-6 gives the exact answer where coarser ones did not, for
    // a few ms of conversion and no measurable frame time (docs/BENCHMARKS.md).
    double trim_relative_tolerance = 3e-6;
    // Read colours and names through the XDE readers (slower, richer).
    bool read_attributes = true;
};

// Reads `path` (format by content) and builds the Scene. Throws nurbsrt::Error:
// io, unsupported_format, unreadable_file, no_faces, occt_failure. Thread-safe:
// STEP/IGES reading is serialized internally (concurrent reads corrupt
// OCCT's heap: its readers share global state); conversion and meshing run outside that lock.
Scene import_file(const std::string& path, const ImportOptions& options = {});

// What convert_file can write, chosen by the output file's extension. The CAD
// formats (STEP, IGES, BREP) keep the exact geometry; STL, glb, VRML and OBJ
// are triangle meshes (BRepMesh at ConvertOptions::deflection);
// nurbs_json is the imported Scene's patches as JSON (core/io/scene_json.h,
// api_schema/nurbs_scene.schema.json). Names, extensions and content types are
// one table (importer/format.cpp).
enum class ConversionFormat { unknown, step, iges, stl, glb, nurbs_json, brep, vrml, obj };

// .stp/.step/.p21, .igs/.iges, .stl, .glb, .json, .brep/.brp, .wrl/.vrml, .obj
// (case-insensitive); unknown otherwise.
ConversionFormat conversion_format_from_extension(const std::string& path);
// By the short names of the API and CLI: step|stp, iges|igs, stl, glb, json,
// brep|brp, vrml|wrl; unknown otherwise.
ConversionFormat conversion_format_from_name(const std::string& name);
// The canonical short names, comma-separated, for messages.
std::string conversion_format_names();
// The canonical short name: "step", "iges", "stl", "glb", "json", "brep", "vrml" ("" for unknown).
const char* conversion_format_short_name(ConversionFormat f);
// "STEP", "IGES", "STL", "GLB", "NURBS-JSON", "BREP", "VRML"
const char* conversion_format_name(ConversionFormat f);
// ".step", ".igs", ".stl", ".glb", ".json", ".brep", ".wrl"
const char* conversion_format_extension(ConversionFormat f);
// "model/step", "model/iges", "model/stl", "model/gltf-binary", "application/json",
// "application/octet-stream" (BREP), "model/vrml"
const char* conversion_format_content_type(ConversionFormat f);
// The CadFormat of a STEP/IGES/BREP output; CadFormat::unknown for the others.
CadFormat cad_format_of(ConversionFormat f);
// Whether the format declares a length unit (STEP, IGES): the `units` option applies.
bool conversion_format_declares_units(ConversionFormat f);
// The length units a CAD file can declare: IGES 5.3's list (global parameter
// 14), which OCCT's STEP writer offers as well. `unknown`: none declared, or
// for an option, "the source's".
enum class LengthUnit { unknown, inch, mm, foot, mile, m, km, mil, micron, cm, microinch };
// "inch", "mm", "foot", "mile", "m", "km", "mil", "micron", "cm", "microinch"; "" for unknown.
const char* length_unit_name(LengthUnit u);
// By those names; nullopt for any other text (no aliases: parsed once at the edge).
std::optional<LengthUnit> length_unit_from_name(std::string_view name);
// Those names, in that order (the values an option may take).
std::vector<std::string> length_unit_names();
// IGES 5.3 global parameter 14 (1 inch, 2 mm, 4 foot, ... 11 microinch) both ways;
// unknown for 3 (a unit named only by parameter 15) and anything out of range.
int iges_unit_flag(LengthUnit u);
LengthUnit length_unit_from_iges_flag(int flag);

// The unit a format writes whatever the source declares (STL, VRML, BREP and
// NURBS JSON mm, glb m); unknown for STEP and IGES (the source's, or `units`).
LengthUnit conversion_format_fixed_unit(ConversionFormat f);
// Whether the format is a triangle mesh (STL, glb, VRML): written from a
// BRepMesh tessellation, its fidelity the mesh's deviation from the exact faces.
bool conversion_format_is_mesh(ConversionFormat f);
// Whether the format's files carry no unit at all (STL, VRML, BREP): written
// in mm, as readers of them assume; a source in another unit is a warning.
bool conversion_format_is_unitless(ConversionFormat f);
// The extension of the file the format's writer puts beside the output, same
// stem (OBJ: ".mtl", its materials, named by the .obj's mtllib line); nullptr
// for a format written as one file.
const char* conversion_format_companion(ConversionFormat f);
// The companion's content type ("model/mtl"); nullptr for none.
const char* conversion_format_companion_content_type(ConversionFormat f);
// `main` (the output file's bytes) with its reference to the companion file
// `written` (a file name) changed to `renamed`: the output and its companion
// then work side by side under their new names.
std::string with_companion_renamed(std::string main, ConversionFormat f, const std::string& written,
                                   const std::string& renamed);

// The conversion options that apply to some output formats only (which, the
// formats' table in importer/format.cpp says): the CLI, the service, the job
// specs and convert_file refuse one given for another format by this alone.
enum class ConversionOption { units, step_schema, iges_mode, deflection, angular_deflection };
// The API's name of the option: "units", "step_schema", "iges_mode", "deflection", "angular_deflection".
const char* conversion_option_name(ConversionOption o);
// "" when `o` applies to `f`, else why not ("applies to STEP and IGES outputs only").
std::string conversion_option_refusal(ConversionOption o, ConversionFormat f);

// The STEP application protocol written: AP214 (automotive design, what most
// CAD systems read) or AP242 (its successor; OCCT 7.6 writes the DIS schema).
enum class StepSchema { ap214, ap242 };
// IGES 5.3 as solids and shells with their topology (entities 186/514/510), or
// as trimmed surfaces alone (144), which older readers take.
enum class IgesMode { brep, faces };
// "ap214", "ap242"; "brep", "faces"; and back (nullopt for other text); all of them.
const char* step_schema_name(StepSchema s);
std::optional<StepSchema> step_schema_from_name(std::string_view name);
std::vector<std::string> step_schema_names();
const char* iges_mode_name(IgesMode m);
std::optional<IgesMode> iges_mode_from_name(std::string_view name);
std::vector<std::string> iges_mode_names();

// What OCCT's BRepCheck_Analyzer says of a file's shape (read as import_file
// reads it; served by a living SharedRead): valid, or how many of its solids,
// shells, faces and edges it finds invalid. `failure`: the checker itself
// threw (then not valid). Throws what the read throws.
struct ShapeValidity {
    bool valid = true;
    int invalid_solids = 0, invalid_shells = 0, invalid_faces = 0, invalid_edges = 0;
    std::string failure;
    double check_ms = 0;
};
ShapeValidity check_validity(const std::string& path);

// What a conversion may change beyond the output format.
struct ConvertOptions {
    // STEP/IGES outputs: the length unit written (geometry scaled to it);
    // unknown keeps the source's declared unit (mm when it declares none).
    // The other outputs have their own: STL, VRML, BREP mm, glb metres.
    LengthUnit units = LengthUnit::unknown;
    StepSchema step_schema = StepSchema::ap214;  // STEP outputs
    IgesMode iges_mode = IgesMode::brep;         // IGES outputs
    // Mesh outputs: BRepMesh's linear deflection as a fraction of the model's
    // bounding-box diagonal, in (0, kMaxConversionDeflection]; 0: ImportOptions'
    // mesh_relative_deflection (0.002).
    double deflection = 0;
    // Mesh outputs: BRepMesh's angular deflection, radians, in
    // [kMinAngularDeflection, kMaxAngularDeflection].
    double angular_deflection = kDefaultAngularDeflection;
};
// The coarsest deflection a conversion takes: a tenth of the model's size
// between mesh and surface is no longer the model's shape.
inline constexpr double kMaxConversionDeflection = 0.1;

// Writes the geometry of `in_path` to `out_path`, the output format taken from
// the extension (see ConversionFormat). Throws nurbsrt::Error (unsupported_format
// for an unknown extension, io, unreadable_file, no_faces, occt_failure).
struct ConvertReport {
    CadFormat in_format = CadFormat::unknown;
    CadFormat out_format = CadFormat::unknown;            // STEP/IGES/BREP outputs; unknown for mesh and JSON outputs
    ConversionFormat output = ConversionFormat::unknown;  // every output, including STEP/IGES
    int faces = 0;
    long long triangles = 0;  // STL and glb: triangles written; 0 otherwise
    int unmeshed_faces = 0;   // STL and glb: faces BRepMesh left empty (missing)
    // STL and glb: triangles BRepMesh made that were left out: of no area at
    // the precision the file stores (float), or repeating another of their face.
    long long degenerate_triangles = 0;
    // The length unit the source declares ("" none) and the one the output is
    // written in (STEP/IGES: what the written file declares; STL, VRML, BREP mm; glb m).
    std::string in_units, out_units;
    // Mesh outputs: the mesh asked of BRepMesh (mesh_for_export): linear
    // deflection relative to the diagonal and in mm, angular deflection in radians.
    double mesh_relative_deflection = 0, mesh_deflection_mm = 0, mesh_angular_deflection = 0;
    double read_ms = 0, mesh_ms = 0, write_ms = 0;  // mesh_ms: BRepMesh (STL, glb) or the import's
                                                    // conversion + meshing (JSON); 0 for STEP/IGES
    double verify_ms = 0;                           // STEP/IGES/BREP: reading the written file back and
                                                    // comparing it (see warnings); 0 otherwise
    // A mesh output of a shared read (a job's file) that took over the mesh an
    // earlier output made at the same parameters, and its measured deviation.
    bool mesh_shared = false;
    // The fidelity report, JSON text (api_schema/openapi.json, FidelityReport):
    // source and output measured alike and compared; "" for NURBS JSON.
    std::string fidelity;
    // STEP/IGES/BREP outputs: what the written file, read back, does not carry
    // of the input (colours, names, assembly structure, faces); mesh outputs:
    // what their format cannot carry; one sentence each without line breaks;
    // empty when all of it was kept.
    std::vector<std::string> warnings;
};
ConvertReport convert_file(const std::string& in_path, const std::string& out_path, const ConvertOptions& options = {});

}  // namespace nurbsrt
