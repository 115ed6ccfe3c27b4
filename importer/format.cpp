// Format detection by content (STEP/IGES), names, and output extensions.
// No OCCT here: the CLI and the server call these before any import starts.
#include <algorithm>
#include <cctype>
#include <cstring>
#include <fstream>
#include <string_view>

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
        case CadFormat::unknown:
            break;
    }
    return "unknown";
}

CadFormat format_from_extension(const std::string& path) {
    const std::string ext = lower_extension(path);
    if (ext == "stp" || ext == "step" || ext == "p21") return CadFormat::step;
    if (ext == "igs" || ext == "iges") return CadFormat::iges;
    return CadFormat::unknown;
}

ConversionFormat conversion_format_from_extension(const std::string& path) {
    const std::string ext = lower_extension(path);
    switch (format_from_extension(path)) {
        case CadFormat::step:
            return ConversionFormat::step;
        case CadFormat::iges:
            return ConversionFormat::iges;
        case CadFormat::unknown:
            break;
    }
    if (ext == "stl") return ConversionFormat::stl;
    if (ext == "glb") return ConversionFormat::glb;
    if (ext == "json") return ConversionFormat::nurbs_json;
    return ConversionFormat::unknown;
}

ConversionFormat conversion_format_from_name(const std::string& name) {
    if (name == "step" || name == "stp") return ConversionFormat::step;
    if (name == "iges" || name == "igs") return ConversionFormat::iges;
    if (name == "stl") return ConversionFormat::stl;
    if (name == "glb") return ConversionFormat::glb;
    if (name == "json") return ConversionFormat::nurbs_json;
    return ConversionFormat::unknown;
}

const char* conversion_format_short_name(ConversionFormat f) {
    switch (f) {
        case ConversionFormat::step:
            return "step";
        case ConversionFormat::iges:
            return "iges";
        case ConversionFormat::stl:
            return "stl";
        case ConversionFormat::glb:
            return "glb";
        case ConversionFormat::nurbs_json:
            return "json";
        case ConversionFormat::unknown:
            break;
    }
    return "";
}

const char* conversion_format_name(ConversionFormat f) {
    switch (f) {
        case ConversionFormat::step:
            return "STEP";
        case ConversionFormat::iges:
            return "IGES";
        case ConversionFormat::stl:
            return "STL";
        case ConversionFormat::glb:
            return "GLB";
        case ConversionFormat::nurbs_json:
            return "NURBS-JSON";
        case ConversionFormat::unknown:
            break;
    }
    return "unknown";
}

const char* conversion_format_extension(ConversionFormat f) {
    switch (f) {
        case ConversionFormat::step:
            return ".step";
        case ConversionFormat::iges:
            return ".igs";
        case ConversionFormat::stl:
            return ".stl";
        case ConversionFormat::glb:
            return ".glb";
        case ConversionFormat::nurbs_json:
            return ".json";
        case ConversionFormat::unknown:
            break;
    }
    return "";
}

const char* conversion_format_content_type(ConversionFormat f) {
    switch (f) {
        case ConversionFormat::step:
            return "model/step";
        case ConversionFormat::iges:
            return "model/iges";
        case ConversionFormat::stl:
            return "model/stl";
        case ConversionFormat::glb:
            return "model/gltf-binary";
        case ConversionFormat::nurbs_json:
            return "application/json";
        case ConversionFormat::unknown:
            break;
    }
    return "application/octet-stream";
}

CadFormat cad_format_of(ConversionFormat f) {
    if (f == ConversionFormat::step) return CadFormat::step;
    if (f == ConversionFormat::iges) return CadFormat::iges;
    return CadFormat::unknown;
}

}  // namespace nurbsrt
