// STEP/IGES output of convert_file: OCCT's writers on the shape as read.
#include <IFSelect_ReturnStatus.hxx>
#include <IGESControl_Controller.hxx>
#include <IGESControl_Writer.hxx>
#include <Interface_Static.hxx>
#include <STEPControl_Writer.hxx>
#include <Standard_Failure.hxx>

#include "importer/convert_writers.h"
#include "importer/internal.h"
#include "renderer/error.h"

namespace nurbsrt::occt {

void write_cad(const std::string& in_path, const std::string& out_path, ConvertReport& r) {
    const OcctModel model = read_model(in_path, /*read_attributes=*/false);
    r.in_format = model.format;
    r.faces = model.faces.Extent();
    r.read_ms = model.read_ms;

    const auto t0 = std::chrono::steady_clock::now();
    {
        std::lock_guard<std::mutex> lock(exchange_mutex());
        try {
            if (r.out_format == CadFormat::iges) {
                IGESControl_Controller::Init();
                // BRep mode (186/514/510 entities) keeps faces and solids; the
                // default "faces" mode writes trimmed surfaces without topology.
                Interface_Static::SetIVal("write.iges.brep.mode", 1);
                IGESControl_Writer writer("MM", 1);
                if (!writer.AddShape(model.shape))
                    throw Error(ErrorCode::occt_failure, "IGES writer: shape not accepted");
                writer.ComputeModel();
                if (!writer.Write(out_path.c_str()))
                    throw Error(ErrorCode::io, "IGES writer: cannot write '" + out_path + "'");
            } else {
                STEPControl_Writer writer;
                const IFSelect_ReturnStatus st = writer.Transfer(model.shape, STEPControl_AsIs);
                if (st != IFSelect_RetDone)
                    throw Error(ErrorCode::occt_failure, "STEP writer: transfer failed");
                if (writer.Write(out_path.c_str()) != IFSelect_RetDone)
                    throw Error(ErrorCode::io, "STEP writer: cannot write '" + out_path + "'");
            }
        } catch (const Standard_Failure& f) {
            throw Error(ErrorCode::occt_failure,
                        std::string(format_name(r.out_format)) + " writer: " + failure_text(f));
        }
    }
    r.write_ms = ms_since(t0);
}

}  // namespace nurbsrt::occt
