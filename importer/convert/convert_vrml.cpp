// VRML 2.0 (.wrl, ISO/IEC 14772-1) output of convert_file through OCCT's XDE
// document (VrmlAPI_Writer::WriteDoc: one Shape node a face, its colour as the
// material's diffuse colour, the assembly's placements as Transform nodes).
// VRML has no unit of its own: the coordinates are the model's millimetres,
// as in the STL output.
#include <Standard_Failure.hxx>
#include <VrmlAPI_Writer.hxx>

#include "importer/convert/convert_writers.h"
#include "importer/internal.h"
#include "core/error.h"

namespace nurbsrt::occt {
namespace {

// WriteDoc's coordinates are the document's times this: 1 keeps mm.
constexpr double kVrmlScale = 1.0;

}  // namespace

void write_vrml(const std::string& in_path, const std::string& out_path, const ConvertOptions& options,
                ConvertReport& r) {
    OcctModel model = read_for_export(in_path, "VRML", r);
    DocumentCloser closer{model.document};
    // The writer meshes faces without a triangulation itself, at its own
    // deflection: ours first, with the degenerate triangles taken out.
    const TopoDS_Shape meshed = mesh_document_for_export(model.document, r, options, model.measures.get());

    const auto t0 = std::chrono::steady_clock::now();
    try {
        if (!VrmlAPI_Writer().WriteDoc(model.document, out_path.c_str(), kVrmlScale))
            throw Error(ErrorCode::io, "VRML writer: cannot write '" + out_path + "'");
    } catch (const Standard_Failure& f) {
        throw Error(ErrorCode::occt_failure, "VRML writer: " + failure_text(f));
    }
    r.write_ms = ms_since(t0);
    const auto t_verify = std::chrono::steady_clock::now();
    r.fidelity = mesh_fidelity(model, meshed, r);
    r.verify_ms = ms_since(t_verify);
}

}  // namespace nurbsrt::occt
