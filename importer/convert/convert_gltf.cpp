// Binary glTF 2.0 (.glb) output of convert_file, through OCCT's XDE document so
// that colours, names and assembly instances (one mesh per part, one node per
// placement) survive.
//
// Axes and units: glTF is Y-up and in metres (glTF 2.0 spec, 3.4), CAD models
// are Z-up millimetres. The writer converts, so viewers show the model upright
// and at its true size: a model point (x, y, z) mm becomes
// (x, z, -y) / 1000 m in the glb. Reading it back with RWGltf_CafReader and
// SetSystemLengthUnit(0.001) + SetSystemCoordinateSystem(Zup) restores the
// model's coordinates (tests/convert_test.cpp checks both directions).
#include <Message_ProgressRange.hxx>
#include <RWGltf_CafWriter.hxx>
#include <RWMesh_CoordinateSystem.hxx>
#include <Standard_Failure.hxx>
#include <TColStd_IndexedDataMapOfStringString.hxx>
#include <TDF_LabelSequence.hxx>
#include <XCAFDoc_DocumentTool.hxx>
#include <XCAFDoc_ShapeTool.hxx>
#include <XCAFDoc_VisMaterial.hxx>
#include <XCAFDoc_VisMaterialPBR.hxx>
#include <XCAFDoc_VisMaterialTool.hxx>
#include <XCAFPrs_Style.hxx>
#include <Quantity_ColorRGBA.hxx>

#include "importer/convert/convert_writers.h"
#include "importer/internal.h"
#include "core/error.h"

namespace nurbsrt::occt {
namespace {

// Roughness of painted or anodised CAD parts in glTF's metallic-roughness model:
// a broad, soft highlight (0: mirror, 1: chalk).
constexpr float kPaintRoughness = 0.5f;

// Painted CAD, not polished metal: a colour without a material gives OCCT's
// writer a metallic factor of 1, glTF's default (glTF 2.0 §3.9.2), and viewers
// show every part as chrome. One PBR material, metallic 0, on every free shape
// of the document (styles are inherited down the assembly) and as the writer's
// default; the parts' own colours still set its base colour. Taken off the
// document again when done: it may be a shared read's (importer/shared_read.h),
// and a later STEP or VRML output of it must not find the material.
class PaintMaterial {
public:
    PaintMaterial(const Handle(TDocStd_Document) & doc, const TDF_LabelSequence& roots)
        : materials_(XCAFDoc_DocumentTool::VisMaterialTool(doc->Main())), roots_(roots) {
        Handle(XCAFDoc_VisMaterial) paint = new XCAFDoc_VisMaterial();
        XCAFDoc_VisMaterialPBR pbr;
        pbr.IsDefined = Standard_True;
        pbr.Metallic = 0.0f;
        pbr.Roughness = kPaintRoughness;
        pbr.BaseColor =
            Quantity_ColorRGBA(Quantity_Color(0.8, 0.8, 0.8, Quantity_TOC_RGB), 1.0f);  // core/scene's default grey
        paint->SetPbrMaterial(pbr);
        label_ = materials_->AddMaterial(paint, "paint");
        for (const TDF_Label& root : roots_) materials_->SetShapeMaterial(root, label_);
        style_.SetMaterial(paint);
    }
    ~PaintMaterial() {
        for (const TDF_Label& root : roots_) materials_->UnSetShapeMaterial(root);
        materials_->RemoveMaterial(label_);
    }
    PaintMaterial(const PaintMaterial&) = delete;
    PaintMaterial& operator=(const PaintMaterial&) = delete;
    const XCAFPrs_Style& style() const { return style_; }

private:
    Handle(XCAFDoc_VisMaterialTool) materials_;
    TDF_LabelSequence roots_;
    TDF_Label label_;
    XCAFPrs_Style style_;
};

}  // namespace

void write_glb(const std::string& in_path, const std::string& out_path, const ConvertOptions& options,
               ConvertReport& r) {
    OcctModel model = read_for_export(in_path, "glTF", r);
    DocumentCloser closer{model.document};

    const TopoDS_Shape meshed = mesh_document_for_export(model.document, r, options, model.measures.get());
    TDF_LabelSequence roots;
    XCAFDoc_DocumentTool::ShapeTool(model.document->Main())->GetFreeShapes(roots);

    const auto t0 = std::chrono::steady_clock::now();
    try {
        RWGltf_CafWriter writer(out_path.c_str(), /*binary=*/Standard_True);
        RWMesh_CoordinateSystemConverter& cs = writer.ChangeCoordinateSystemConverter();
        cs.SetInputLengthUnit(0.001);  // OCCT's readers deliver mm
        cs.SetInputCoordinateSystem(RWMesh_CoordinateSystem_Zup);
        cs.SetOutputLengthUnit(1.0);                                 // glTF: metres
        cs.SetOutputCoordinateSystem(RWMesh_CoordinateSystem_glTF);  // Y-up
        const PaintMaterial paint(model.document, roots);
        writer.SetDefaultStyle(paint.style());
        TColStd_IndexedDataMapOfStringString info;
        info.Add("generator", "nurbsrt");
        if (!writer.Perform(model.document, info, Message_ProgressRange()))
            throw Error(ErrorCode::io, "glTF writer: cannot write '" + out_path + "'");
    } catch (const Standard_Failure& f) {
        throw Error(ErrorCode::occt_failure, "glTF writer: " + failure_text(f));
    }
    r.write_ms = ms_since(t0);
    const auto t_verify = std::chrono::steady_clock::now();
    r.fidelity = mesh_fidelity(model, meshed, r);
    r.verify_ms = ms_since(t_verify);
}

}  // namespace nurbsrt::occt
