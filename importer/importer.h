// The importer's public interface: STEP/IGES bytes in, a Scene out.
// This header is OCCT-free on purpose (it is included by cli/ and server/);
// everything that touches OCCT lives in importer/*.cpp.
#pragma once

#include <string>

#include "renderer/scene.h"

namespace nurbsrt {

enum class CadFormat { unknown, step, iges };

// Recognise the format from the file's content (STEP: "ISO-10303-21;" header;
// IGES: 80-column records with the S/G/D/P/T section letter in column 73),
// not from its extension.
CadFormat detect_format(const std::string& path);
CadFormat detect_format_bytes(const char* data, size_t size);
const char* format_name(CadFormat f);  // "STEP", "IGES", "unknown"
// Format implied by a file name's extension (.stp/.step, .igs/.iges), for outputs.
CadFormat format_from_extension(const std::string& path);

struct ImportOptions {
    // Mesh for the preliminary map: linear deflection as a fraction of the
    // model's bounding-box diagonal, and angular deflection in radians.
    double mesh_relative_deflection = 0.002;
    double mesh_angular_deflection = 0.35;
    // Wall-clock budget for BRepMesh on the whole model, seconds; faces still
    // unmeshed when it runs out get the trimmed-grid fallback (with a warning).
    double mesh_time_limit_s = 60.0;
    // Trim loops: maximum deviation of the (u,v) polyline from its pcurve, as a
    // fraction of the face's parameter-box diagonal.
    double trim_relative_tolerance = 1e-4;
    // Read colours and names through the XDE readers (slower, richer).
    bool read_attributes = true;
};

// Reads `path` (format by content) and builds the Scene. Throws nurbsrt::Error:
// io, unsupported_format, unreadable_file, no_faces, occt_failure. Thread-safe:
// STEP/IGES reading is serialized internally (STACK.md: concurrent reads corrupt
// OCCT's heap); conversion and meshing run outside that lock.
Scene import_file(const std::string& path, const ImportOptions& options = {});

// Writes the geometry of `in_path` to `out_path`, the output format taken from
// the extension (.stp/.step or .igs/.iges). Throws nurbsrt::Error.
struct ConvertReport {
    CadFormat in_format = CadFormat::unknown, out_format = CadFormat::unknown;
    int faces = 0;
    double read_ms = 0, write_ms = 0;
};
ConvertReport convert_file(const std::string& in_path, const std::string& out_path);

}  // namespace nurbsrt
