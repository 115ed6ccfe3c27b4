// Binary STL output of convert_file. STL has no units: the coordinates are the
// model's millimetres, as every CAD tool reading STL assumes by default.
#include <StlAPI_Writer.hxx>
#include <Standard_Failure.hxx>

#include "importer/convert/convert_writers.h"
#include "importer/internal.h"
#include "core/error.h"

namespace nurbsrt::occt {

void write_stl(const std::string& in_path, const std::string& out_path, const ConvertOptions& options,
               ConvertReport& r) {
    const OcctModel model = read_model(in_path, /*read_attributes=*/false);
    r.in_format = model.format;
    r.faces = model.faces.Extent();
    r.in_units = model.units;
    r.read_ms = model.read_ms;
    mesh_for_export(model.shape, r, options, model.measures.get());

    const auto t0 = std::chrono::steady_clock::now();
    try {
        StlAPI_Writer writer;
        writer.ASCIIMode() = Standard_False;  // binary: a fifth of the size, exact floats
        if (!writer.Write(model.shape, out_path.c_str()))
            throw Error(ErrorCode::io, "STL writer: cannot write '" + out_path + "'");
    } catch (const Standard_Failure& f) {
        throw Error(ErrorCode::occt_failure, "STL writer: " + failure_text(f));
    }
    r.write_ms = ms_since(t0);
    const auto t_verify = std::chrono::steady_clock::now();
    r.fidelity = mesh_fidelity(model, model.shape, r);
    r.verify_ms = ms_since(t_verify);
}

}  // namespace nurbsrt::occt
