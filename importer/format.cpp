// Format detection by content (STEP/IGES/BREP), names, and the output formats' table.
// No OCCT here: the CLI and the server call these before any import starts.
#include <algorithm>
#include <array>
#include <cctype>
#include <cstring>
#include <fstream>
#include <string_view>

#include "core/enum_names.h"
#include "importer/importer.h"
#include "core/error.h"
#include "core/ascii.h"

namespace nurbsrt {
namespace {

bool is_iges_section_letter(char c) {
    // S start, G global, D directory, P parameter, T terminate; C marks the
    // compressed form whose first record is still flagged in column 73.
    return c == 'S' || c == 'G' || c == 'D' || c == 'P' || c == 'T' || c == 'C';
}

// An IGES record is 80 columns: the section letter in column 73 and a
// right-justified sequence number in columns 74-80 (blanks allowed).
bool looks_like_iges_record(std::string_view rec) {
    if (rec.size() < 73) return false;
    if (!is_iges_section_letter(rec[72])) return false;
    bool digit = false;
    for (size_t i = 73; i < std::min<size_t>(rec.size(), 80); ++i) {
        const char c = rec[i];
        if (std::isdigit(static_cast<unsigned char>(c)))
            digit = true;
        else if (c != ' ')
            return false;
    }
    return digit || rec.size() == 73;
}

// First record: up to the first line break when there is one within 80
// columns (plus CR), otherwise the first 80 bytes: some writers
// emit all records back to back without line breaks.
std::string_view first_record(std::string_view s) {
    const size_t nl = s.find('\n');
    if (nl != std::string_view::npos && nl <= 82) {
        std::string_view rec = s.substr(0, nl);
        if (!rec.empty() && rec.back() == '\r') rec.remove_suffix(1);
        return rec;
    }
    return s.substr(0, std::min<size_t>(s.size(), 80));
}

std::string lower_extension(const std::string& path) {
    const size_t slash = path.find_last_of("/\\");
    const size_t dot = path.find_last_of('.');
    if (dot == std::string::npos || (slash != std::string::npos && dot < slash)) return {};
    return ascii_lower(std::string_view(path).substr(dot + 1));
}

// Every output format once: its names, the extensions it is recognised by (the
// first is written), its content type and what it keeps. In ConversionFormat's order.
struct ConversionFormatInfo {
    ConversionFormat format;
    const char* short_name;  // the API's and CLI's name
    const char* alias;       // a second accepted name, or nullptr
    const char* name;        // for messages and answers
    const char* written_extension;
    std::array<const char*, 3> extensions;  // lower case, without the dot; nullptr pads
    const char* content_type;
    CadFormat cad;          // exact B-rep formats: the CadFormat (also readable); unknown for the others
    LengthUnit fixed_unit;  // unknown: writes a declared length unit (the `units` option applies)
    bool unitless;          // the file says nothing of its unit (fixed_unit is what readers assume)
    bool mesh;              // a triangle mesh from BRepMesh
    unsigned options;       // bits of the ConversionOptions that apply (option_bit)
};

constexpr unsigned option_bit(ConversionOption o) { return 1u << static_cast<unsigned>(o); }
constexpr unsigned kStepOptions = option_bit(ConversionOption::units) | option_bit(ConversionOption::step_schema);
constexpr unsigned kIgesOptions = option_bit(ConversionOption::units) | option_bit(ConversionOption::iges_mode);
constexpr unsigned kMeshOptions =
    option_bit(ConversionOption::deflection) | option_bit(ConversionOption::angular_deflection);

constexpr EnumName<ConversionOption> kConversionOptionNames[] = {
    {ConversionOption::units, "units"},
    {ConversionOption::step_schema, "step_schema"},
    {ConversionOption::iges_mode, "iges_mode"},
    {ConversionOption::deflection, "deflection"},
    {ConversionOption::angular_deflection, "angular_deflection"}};
static_assert(names_every_value(kConversionOptionNames, ConversionOption::angular_deflection));
// Content types: IANA's model/step, model/iges, model/stl, model/gltf-binary and
// model/vrml; OCCT's BREP has no registered type.
constexpr ConversionFormatInfo kConversionFormats[] = {
    {ConversionFormat::unknown,
     "",
     nullptr,
     "unknown",
     "",
     {},
     "application/octet-stream",
     CadFormat::unknown,
     LengthUnit::unknown,
     false,
     false,
     0},
    {ConversionFormat::step,
     "step",
     "stp",
     "STEP",
     ".step",
     {"stp", "step", "p21"},
     "model/step",
     CadFormat::step,
     LengthUnit::unknown,
     false,
     false,
     kStepOptions},
    {ConversionFormat::iges,
     "iges",
     "igs",
     "IGES",
     ".igs",
     {"igs", "iges"},
     "model/iges",
     CadFormat::iges,
     LengthUnit::unknown,
     false,
     false,
     kIgesOptions},
    // STL and VRML have no unit: the model's mm, as CAD tools reading them assume.
    {ConversionFormat::stl,
     "stl",
     nullptr,
     "STL",
     ".stl",
     {"stl"},
     "model/stl",
     CadFormat::unknown,
     LengthUnit::mm,
     true,
     true,
     kMeshOptions},
    // glTF 2.0 §3.4: metres.
    {ConversionFormat::glb,
     "glb",
     nullptr,
     "GLB",
     ".glb",
     {"glb"},
     "model/gltf-binary",
     CadFormat::unknown,
     LengthUnit::m,
     false,
     true,
     kMeshOptions},
    // The imported Scene's coordinates (the Scene names the source's unit).
    {ConversionFormat::nurbs_json,
     "json",
     nullptr,
     "NURBS-JSON",
     ".json",
     {"json"},
     "application/json",
     CadFormat::unknown,
     LengthUnit::mm,
     false,
     false,
     0},
    // OCCT's readers deliver mm, and BREP declares no unit.
    {ConversionFormat::brep,
     "brep",
     "brp",
     "BREP",
     ".brep",
     {"brep", "brp"},
     "application/octet-stream",
     CadFormat::brep,
     LengthUnit::mm,
     true,
     false,
     0},
    {ConversionFormat::vrml,
     "vrml",
     "wrl",
     "VRML",
     ".wrl",
     {"wrl", "vrml"},
     "model/vrml",
     CadFormat::unknown,
     LengthUnit::mm,
     true,
     true,
     kMeshOptions},
    // OBJ has no unit either; its materials come in a .mtl file beside it
    // (the service answers both in a ZIP). model/obj: IANA's registration.
    {ConversionFormat::obj,
     "obj",
     nullptr,
     "OBJ",
     ".obj",
     {"obj"},
     "model/obj",
     CadFormat::unknown,
     LengthUnit::mm,
     true,
     true,
     kMeshOptions},
};
static_assert(std::size(kConversionFormats) == static_cast<size_t>(ConversionFormat::obj) + 1);

// The files a format's writer puts beside the output (same stem, this
// extension), their content type (IANA's model/mtl) and the line of the output
// that names them (OBJ's "mtllib <file>", Wavefront's OBJ specification).
struct CompanionFile {
    ConversionFormat format;
    const char* extension;
    const char* content_type;
    const char* reference;
};
constexpr CompanionFile kCompanionFiles[] = {{ConversionFormat::obj, ".mtl", "model/mtl", "mtllib "}};

constexpr bool formats_in_order() {
    for (size_t i = 0; i < std::size(kConversionFormats); ++i)
        if (static_cast<size_t>(kConversionFormats[i].format) != i) return false;
    return true;
}
static_assert(formats_in_order());

const ConversionFormatInfo& info_of(ConversionFormat f) {
    const auto i = static_cast<size_t>(f);
    return kConversionFormats[i < std::size(kConversionFormats) ? i : 0];
}

// OCCT's own text format (BRepTools::Write): "CASCADE Topology V1, (c)
// Matra-Datavision" (V1 to V3) first, after DRAW's "DBRep_DrawableShape" when
// DRAW saved it.
bool looks_like_brep(std::string_view s) {
    const size_t first = s.find_first_not_of(" \t\r\n");
    if (first == std::string_view::npos) return false;
    std::string_view rest = s.substr(first);
    constexpr std::string_view kDraw = "DBRep_DrawableShape";
    if (rest.substr(0, kDraw.size()) == kDraw) {
        const size_t next = rest.find_first_not_of(" \t\r\n", kDraw.size());
        rest = next == std::string_view::npos ? std::string_view() : rest.substr(next);
    }
    return rest.substr(0, 18) == "CASCADE Topology V";
}

}  // namespace

CadFormat detect_format_bytes(const char* data, size_t size) {
    if (data == nullptr || size == 0) return CadFormat::unknown;
    std::string_view s(data, std::min<size_t>(size, 4096));
    // UTF-8 byte-order mark, written by some Windows tools.
    if (s.size() >= 3 && s.substr(0, 3) == "\xEF\xBB\xBF") s.remove_prefix(3);
    // STEP Part 21: the header keyword comes first, possibly after blanks or a comment.
    const size_t first = s.find_first_not_of(" \t\r\n");
    if (first != std::string_view::npos) {
        std::string_view rest = s.substr(first);
        if (rest.substr(0, 12) == "ISO-10303-21") return CadFormat::step;
        if (rest.substr(0, 2) == "/*" && s.find("ISO-10303-21") != std::string_view::npos) return CadFormat::step;
    }
    if (looks_like_iges_record(first_record(s))) return CadFormat::iges;
    if (looks_like_brep(s)) return CadFormat::brep;
    return CadFormat::unknown;
}

CadFormat detect_format(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    if (!in) throw Error(ErrorCode::io, "cannot open '" + path + "'");
    char buf[4096];
    in.read(buf, sizeof(buf));
    return detect_format_bytes(buf, static_cast<size_t>(in.gcount()));
}

const char* format_name(CadFormat f) {
    switch (f) {
        case CadFormat::step:
            return "STEP";
        case CadFormat::iges:
            return "IGES";
        case CadFormat::brep:
            return "BREP";
        case CadFormat::unknown:
            break;
    }
    return "unknown";
}

CadFormat format_from_extension(const std::string& path) {
    return cad_format_of(conversion_format_from_extension(path));
}

ConversionFormat conversion_format_from_extension(const std::string& path) {
    const std::string ext = lower_extension(path);
    for (const ConversionFormatInfo& f : kConversionFormats)
        for (const char* e : f.extensions)
            if (e != nullptr && ext == e) return f.format;
    return ConversionFormat::unknown;
}

ConversionFormat conversion_format_from_name(const std::string& name) {
    for (const ConversionFormatInfo& f : kConversionFormats)
        if (name == f.short_name || (f.alias != nullptr && name == f.alias)) return f.format;
    return ConversionFormat::unknown;
}

const char* conversion_format_short_name(ConversionFormat f) { return info_of(f).short_name; }
const char* conversion_format_name(ConversionFormat f) { return info_of(f).name; }
const char* conversion_format_extension(ConversionFormat f) { return info_of(f).written_extension; }
const char* conversion_format_content_type(ConversionFormat f) { return info_of(f).content_type; }
CadFormat cad_format_of(ConversionFormat f) { return info_of(f).cad; }
bool conversion_format_declares_units(ConversionFormat f) {
    return f != ConversionFormat::unknown && info_of(f).fixed_unit == LengthUnit::unknown;
}
LengthUnit conversion_format_fixed_unit(ConversionFormat f) { return info_of(f).fixed_unit; }
bool conversion_format_is_mesh(ConversionFormat f) { return info_of(f).mesh; }
bool conversion_format_is_unitless(ConversionFormat f) { return info_of(f).unitless; }

const char* conversion_format_companion(ConversionFormat f) {
    for (const CompanionFile& c : kCompanionFiles)
        if (c.format == f) return c.extension;
    return nullptr;
}

const char* conversion_format_companion_content_type(ConversionFormat f) {
    for (const CompanionFile& c : kCompanionFiles)
        if (c.format == f) return c.content_type;
    return nullptr;
}

std::string with_companion_renamed(std::string main, ConversionFormat f, const std::string& written,
                                   const std::string& renamed) {
    for (const CompanionFile& c : kCompanionFiles) {
        if (c.format != f) continue;
        const std::string line = c.reference + written;
        if (const size_t at = main.find(line); at != std::string::npos)
            main.replace(at + line.size() - written.size(), written.size(), renamed);
    }
    return main;
}

const char* conversion_option_name(ConversionOption o) { return enum_name(kConversionOptionNames, o, "?"); }

std::string conversion_option_refusal(ConversionOption o, ConversionFormat f) {
    if ((info_of(f).options & option_bit(o)) != 0) return {};
    std::vector<std::string> taking;
    for (const ConversionFormatInfo& i : kConversionFormats)
        if ((i.options & option_bit(o)) != 0) taking.emplace_back(i.name);
    std::string list;
    for (size_t k = 0; k < taking.size(); ++k)
        list += (k == 0 ? "" : k + 1 == taking.size() ? " and " : ", ") + taking[k];
    return "applies to " + list + " outputs only";
}

std::string conversion_format_names() {
    std::string s;
    for (const ConversionFormatInfo& f : kConversionFormats)
        if (f.format != ConversionFormat::unknown) s += (s.empty() ? "" : ", ") + std::string(f.short_name);
    return s;
}

}  // namespace nurbsrt
