// Wavefront OBJ + MTL output of convert_file through OCCT's RWObj_CafWriter
// (TKRWMesh): one object per part instance (named after it), each face's colour
// a material of the .mtl file written beside the .obj (same stem, referenced by
// its `mtllib` line). OBJ has no unit: the coordinates are the model's
// millimetres and its axes (Z up), as in the STL output.
#include <Message_ProgressRange.hxx>
#include <RWMesh_CoordinateSystem.hxx>
#include <RWObj_CafWriter.hxx>
#include <Standard_Failure.hxx>
#include <TColStd_IndexedDataMapOfStringString.hxx>

#include "importer/convert/convert_writers.h"
#include "importer/internal.h"
#include "core/error.h"

namespace nurbsrt::occt {
namespace {

// OCCT's readers deliver mm; OBJ readers take the numbers as they are.
constexpr double kMillimetre = 0.001;

}  // namespace

void write_obj(const std::string& in_path, const std::string& out_path, const ConvertOptions& options,
               ConvertReport& r) {
    OcctModel model = read_for_export(in_path, "OBJ", r);
    DocumentCloser closer{model.document};
    const TopoDS_Shape meshed = mesh_document_for_export(model.document, r, options, model.measures.get());

    const auto t0 = std::chrono::steady_clock::now();
    try {
        RWObj_CafWriter writer(out_path.c_str());
        RWMesh_CoordinateSystemConverter& cs = writer.ChangeCoordinateSystemConverter();
        cs.SetInputLengthUnit(kMillimetre);
        cs.SetOutputLengthUnit(kMillimetre);
        cs.SetInputCoordinateSystem(RWMesh_CoordinateSystem_Zup);
        cs.SetOutputCoordinateSystem(RWMesh_CoordinateSystem_Zup);
        TColStd_IndexedDataMapOfStringString info;
        info.Add("generator", "nurbsrt");
        if (!writer.Perform(model.document, info, Message_ProgressRange()))
            throw Error(ErrorCode::io, "OBJ writer: cannot write '" + out_path + "'");
    } catch (const Standard_Failure& f) {
        throw Error(ErrorCode::occt_failure, "OBJ writer: " + failure_text(f));
    }
    r.write_ms = ms_since(t0);
    const auto t_verify = std::chrono::steady_clock::now();
    r.fidelity = mesh_fidelity(model, meshed, r);
    r.verify_ms = ms_since(t_verify);
}

}  // namespace nurbsrt::occt
