// STEP/IGES output of convert_file through OCCT's XDE document, so that face
// colours, names, layers and (STEP only) the assembly structure of the input
// survive (OCCT User Guide: "Extended Data Exchange (XDE)", STEP/IGES with
// XDE); BREP, OCCT's own exact format, holds the shape alone.
//
// What was carried is measured, not assumed: the written file is read back
// with XDE and compared with the input's document (coloured faces and their
// colours, names, assemblies/components/instances, faces); every shortfall
// becomes a warning of the ConvertReport.
#include <algorithm>
#include <cmath>
#include <iterator>
#include <set>
#include <vector>

#include <BRepBuilderAPI_Copy.hxx>
#include <BRepTools.hxx>
#include <IFSelect_ReturnStatus.hxx>
#include <IGESCAFControl_Writer.hxx>
#include <IGESControl_Controller.hxx>
#include <Interface_Static.hxx>
#include <STEPCAFControl_Writer.hxx>
#include <STEPControl_Controller.hxx>
#include <Standard_Failure.hxx>
#include <TDF_ChildIterator.hxx>
#include <TDF_LabelMap.hxx>
#include <TDF_LabelSequence.hxx>
#include <TopAbs_ShapeEnum.hxx>
#include <TopExp.hxx>
#include <TopTools_IndexedMapOfShape.hxx>
#include <XCAFDoc_DocumentTool.hxx>
#include <XCAFDoc_Editor.hxx>
#include <XCAFDoc_ShapeTool.hxx>
#include <XCAFPrs_DocumentExplorer.hxx>

#include "importer/convert/convert_writers.h"
#include "importer/internal.h"
#include "core/error.h"

namespace nurbsrt::occt {
namespace {

// Two colours are the same when every channel differs by less than this. IGES
// stores colours as percentages and STEP as reals, both written with enough
// digits for far better; 1/255 is the step of 8-bit colour, so anything closer
// is the same colour on every display.
constexpr double kColourTolerance = 1.0 / 255.0;
// A warning quotes at most this many of the names it counts (the count says
// how many; a longer list is noise).
constexpr size_t kNamesListed = 8;

// What a model's XDE document carries, counted the same way for the input and
// the written file.
struct XdeContent {
    int faces = 0;                               // face occurrences (an instanced part's faces per instance)
    int coloured_faces = 0;                      // of those, with a surface colour
    std::vector<std::pair<Color, int>> colours;  // distinct colour -> coloured faces
    std::set<std::string> names;                 // of parts, assemblies, components and named sub-shapes
    int assemblies = 0;                          // distinct assembly definitions
    int components = 0;                          // component labels: placements of a part or sub-assembly
    int instances = 0;                           // part occurrences in the expanded tree
};

bool same_colour(const Color& a, const Color& b) {
    return std::abs(a.r - b.r) < kColourTolerance && std::abs(a.g - b.g) < kColourTolerance &&
           std::abs(a.b - b.b) < kColourTolerance;
}

void add_colour(XdeContent& c, const Color& colour) {
    ++c.coloured_faces;
    for (auto& [known, n] : c.colours)
        if (same_colour(known, colour)) {
            ++n;
            return;
        }
    c.colours.emplace_back(colour, 1);
}

// Walks the definitions under `root` once each (shared definitions are counted
// once), with an explicit stack: the assembly's depth is the input file's, and a
// file can nest assemblies far deeper than a thread's stack has frames for.
void walk_definitions(const TDF_Label& root, TDF_LabelMap& seen, XdeContent& c) {
    std::vector<TDF_Label> pending{root};
    while (!pending.empty()) {
        const TDF_Label def = pending.back();
        pending.pop_back();
        if (!seen.Add(def)) continue;
        if (std::string n = label_name(def); !n.empty()) c.names.insert(std::move(n));
        if (XCAFDoc_ShapeTool::IsAssembly(def)) {
            ++c.assemblies;
            TDF_LabelSequence comps;
            XCAFDoc_ShapeTool::GetComponents(def, comps, Standard_False);
            for (const TDF_Label& comp : comps) {
                ++c.components;
                if (std::string n = label_name(comp); !n.empty()) c.names.insert(std::move(n));
                TDF_Label ref;
                if (XCAFDoc_ShapeTool::GetReferredShape(comp, ref)) pending.push_back(ref);
            }
            continue;
        }
        for (TDF_ChildIterator ci(def); ci.More(); ci.Next())  // named faces/solids of a part
            if (std::string n = label_name(ci.Value()); !n.empty()) c.names.insert(std::move(n));
    }
}

XdeContent content_of(const OcctModel& m) {
    XdeContent c;
    c.faces = m.faces.Extent();
    for (const FaceAttributes& a : m.attributes)
        if (a.has_color) add_colour(c, a.color);
    if (m.document.IsNull()) return c;
    const Handle(XCAFDoc_ShapeTool) shapes = XCAFDoc_DocumentTool::ShapeTool(m.document->Main());
    TDF_LabelSequence roots;
    shapes->GetFreeShapes(roots);
    TDF_LabelMap seen;
    for (const TDF_Label& root : roots) walk_definitions(root, seen, c);
    for (XCAFPrs_DocumentExplorer ex(m.document, XCAFPrs_DocumentExplorerFlags_OnlyLeafNodes); ex.More(); ex.Next())
        ++c.instances;
    return c;
}

// Faces whose input colour has no face of that colour left in the output
// (a colour kept on fewer faces counts the difference).
int faces_losing_colour(const XdeContent& in, const XdeContent& out) {
    int lost = 0;
    for (const auto& [colour, n] : in.colours) {
        int kept = 0;
        for (const auto& [c, m] : out.colours)
            if (same_colour(colour, c)) kept += m;
        lost += std::max(0, n - kept);
    }
    return lost;
}

// XCAFDoc_ShapeTool names a label it makes for an unnamed shape after the
// shape's type (its auto-naming; the IGES reader makes such labels for
// coloured faces): a name the source never had, which no target must keep.
bool is_generated_name(const std::string& name) {
    static const char* const kTypeNames[] = {"COMPOUND", "COMPSOLID", "SOLID",  "SHELL", "FACE",
                                             "WIRE",     "EDGE",      "VERTEX", "SHAPE"};
    return std::any_of(std::begin(kTypeNames), std::end(kTypeNames), [&](const char* t) { return name == t; });
}

std::string listed_names(const std::vector<std::string>& names) {
    std::string s;
    for (size_t i = 0; i < names.size() && i < kNamesListed; ++i) s += (i ? ", '" : "'") + names[i] + "'";
    if (names.size() > kNamesListed) s += ", ...";
    return s;
}

// What the output lost of the source's attributes, counted once for the
// warnings and the report.
struct Losses {
    int faces_losing_colour = 0;
    std::vector<std::string> names;  // sorted; names the source never had (is_generated_name) left out
};

Losses losses_of(const XdeContent& in, const XdeContent& out) {
    Losses l;
    l.faces_losing_colour = faces_losing_colour(in, out);
    std::set_difference(in.names.begin(), in.names.end(), out.names.begin(), out.names.end(),
                        std::back_inserter(l.names));
    std::erase_if(l.names, is_generated_name);
    return l;
}

std::vector<std::string> shortfalls(const XdeContent& in, const XdeContent& out, const Losses& lost,
                                    CadFormat out_format) {
    std::vector<std::string> w;
    const std::string fmt = format_name(out_format);
    // IGES 5.3 has no product structure like STEP's; its subfigure instances
    // (entities 308/408) are not used by OCCT's IGESCAFControl_Writer, which
    // writes each free shape of the document as one compound with the
    // placements applied (measured: one root named as the top assembly).
    if (out_format == CadFormat::brep && in.components > 0)
        w.push_back("BREP has no product structure: " + std::to_string(in.instances) + " part instance(s) (" +
                    std::to_string(in.components) + " component(s) in " + std::to_string(in.assemblies) +
                    " assembly(ies)) written as one compound of placed shapes");
    else if (out_format == CadFormat::iges && in.components > 0)
        w.push_back("IGES has no assembly structure: " + std::to_string(in.instances) + " part instance(s) (" +
                    std::to_string(in.components) + " component(s) in " + std::to_string(in.assemblies) +
                    " assembly(ies)) written as a flat list of shapes");
    else if (in.assemblies != out.assemblies || in.components != out.components || in.instances != out.instances)
        w.push_back("assembly structure changed: the input has " + std::to_string(in.assemblies) + " assembly(ies), " +
                    std::to_string(in.components) + " component(s), " + std::to_string(in.instances) +
                    " part instance(s); the written " + fmt + " file " + std::to_string(out.assemblies) + ", " +
                    std::to_string(out.components) + ", " + std::to_string(out.instances));
    if (out.faces != in.faces)
        w.push_back("the written " + fmt + " file holds " + std::to_string(out.faces) + " face(s), the input " +
                    std::to_string(in.faces));
    if (lost.faces_losing_colour > 0)
        w.push_back(std::to_string(lost.faces_losing_colour) + " of " + std::to_string(in.coloured_faces) +
                    " coloured face(s) lost their colour (the written " + fmt + " file has " +
                    std::to_string(out.coloured_faces) + " coloured face(s))");
    if (!lost.names.empty())
        w.push_back(std::to_string(lost.names.size()) + " of " + std::to_string(in.names.size()) +
                    " name(s) not in the written " + fmt + " file: " + listed_names(lost.names));
    return w;
}

// The unit a conversion writes: the one asked for, else the first the source
// declares (a STEP file can declare several contexts; its shapes take the
// first), else mm, what OCCT's readers deliver.
LengthUnit target_unit(const std::string& declared, LengthUnit asked) {
    if (asked != LengthUnit::unknown) return asked;
    const LengthUnit first =
        length_unit_from_name(declared.substr(0, declared.find(','))).value_or(LengthUnit::unknown);
    return first != LengthUnit::unknown ? first : LengthUnit::mm;
}

// IGES groups whose members carry names (what OCCT's IGES writer makes of an
// assembly, and what many CAD systems write) become STEP assemblies, one named
// part per member: STEP names products, not sub-shapes of one product, so
// otherwise every member's name is lost and its faces take the group's.
// XCAFDoc_Editor::Expand moves the members' names and colours onto the new
// parts. Groups without member names stay one shape (a file of loose faces
// should not turn into a product per face).
void expand_named_groups(const Handle(TDocStd_Document) & doc) {
    const Handle(XCAFDoc_ShapeTool) shapes = XCAFDoc_DocumentTool::ShapeTool(doc->Main());
    TDF_LabelSequence roots;
    shapes->GetFreeShapes(roots);
    for (const TDF_Label& root : roots) {
        if (XCAFDoc_ShapeTool::IsAssembly(root) || XCAFDoc_ShapeTool::GetShape(root).ShapeType() != TopAbs_COMPOUND)
            continue;
        bool named_member = false;
        for (TDF_ChildIterator ci(root); ci.More() && !named_member; ci.Next())
            named_member = !label_name(ci.Value()).empty();
        if (named_member) XCAFDoc_Editor::Expand(doc->Main(), root, /*theRecursively=*/Standard_True);
    }
}

// The XDE part of the fidelity report: colours, names and the assembly of the
// source and the output, with the first names lost.
nlohmann::ordered_json attributes_json(const XdeContent& in, const XdeContent& out, const Losses& losses) {
    std::vector<std::string> lost(losses.names.begin(),
                                  losses.names.begin() + std::min(losses.names.size(), kNamesListed));
    auto tree = [](const XdeContent& c) {
        return nlohmann::ordered_json{
            {"assemblies", c.assemblies}, {"components", c.components}, {"instances", c.instances}};
    };
    return {{"colours",
             {{"source_coloured_faces", in.coloured_faces},
              {"output_coloured_faces", out.coloured_faces},
              {"faces_losing_colour", losses.faces_losing_colour}}},
            {"names",
             {{"source", in.names.size()},
              {"output", out.names.size()},
              {"lost", losses.names.size()},
              {"lost_first", lost}}},
            {"assembly", {{"source", tree(in)}, {"output", tree(out)}}}};
}

// The OCCT names of the STEP schemas (write.step.schema, STEPControl_Controller).
const char* occt_step_schema(StepSchema s) { return s == StepSchema::ap242 ? "AP242DIS" : "AP214IS"; }

void write_iges(const Handle(TDocStd_Document) & doc, const std::string& out_path, LengthUnit unit, IgesMode mode) {
    IGESControl_Controller::Init();
    // The XDE writer takes unit and mode from these statics (its constructor
    // reads them). BRep mode (186/514/510 entities) keeps faces and solids;
    // "faces" mode writes trimmed surfaces (144) without topology.
    Interface_Static::SetIVal("write.iges.brep.mode", mode == IgesMode::brep ? 1 : 0);
    Interface_Static::SetIVal("write.iges.unit", iges_unit_flag(unit));
    IGESCAFControl_Writer writer;
    writer.SetColorMode(Standard_True);
    writer.SetNameMode(Standard_True);
    writer.SetLayerMode(Standard_True);
    if (!writer.Transfer(doc)) throw Error(ErrorCode::occt_failure, "IGES writer: transfer failed");
    writer.ComputeModel();
    if (!writer.Write(out_path.c_str())) throw Error(ErrorCode::io, "IGES writer: cannot write '" + out_path + "'");
}

void write_step(const Handle(TDocStd_Document) & doc, const std::string& out_path, LengthUnit unit, StepSchema schema) {
    STEPControl_Controller::Init();
    // write.step.unit enumerates the units in IGES's order (STEPControl_Controller).
    // Unit and schema are set before the writer exists: its model takes the
    // unit it scales to and the header's schema when made (the unit set after,
    // the header said INCH over mm numbers).
    Interface_Static::SetIVal("write.step.unit", iges_unit_flag(unit));
    Interface_Static::SetCVal("write.step.schema", occt_step_schema(schema));
    STEPCAFControl_Writer writer;
    writer.SetColorMode(Standard_True);
    writer.SetNameMode(Standard_True);
    writer.SetLayerMode(Standard_True);
    if (!writer.Transfer(doc, STEPControl_AsIs)) throw Error(ErrorCode::occt_failure, "STEP writer: transfer failed");
    if (writer.Write(out_path.c_str()) != IFSelect_RetDone)
        throw Error(ErrorCode::io, "STEP writer: cannot write '" + out_path + "'");
}

// BREP writes the shapes' state flags (free, modified, checked) and
// triangulations as it finds them, and the earlier uses of a shared read
// (importer/shared_read.h: the import, other outputs) change both (measured:
// a face re-meshed loses "checked"): a copy of the topology (the geometry
// shared, no meshes) with "checked" cleared, a cache that only says BRepCheck
// saw the shape, writes the same file whatever came before.
TopoDS_Shape fresh_copy(const TopoDS_Shape& shape) {
    TopoDS_Shape copy = BRepBuilderAPI_Copy(shape, /*copyGeom=*/Standard_False, /*copyMesh=*/Standard_False).Shape();
    TopTools_IndexedMapOfShape all;
    TopExp::MapShapes(copy, all);
    for (int i = 1; i <= all.Extent(); ++i) all(i).TShape()->Checked(Standard_False);
    copy.Checked(Standard_False);
    return copy;
}

// The model written in `out_format`: STEP and IGES from its XDE document in
// `unit` (the writers scale the document's mm to it), BREP as OCCT's own text
// (the shape alone: no colours, names or unit). Callers hold exchange_mutex and
// catch Standard_Failure.
void write_model(const OcctModel& model, const std::string& out_path, CadFormat out_format, LengthUnit unit,
                 const ConvertOptions& options) {
    if (out_format == CadFormat::iges)
        write_iges(model.document, out_path, unit, options.iges_mode);
    else if (out_format == CadFormat::step)
        write_step(model.document, out_path, unit, options.step_schema);
    else if (!BRepTools::Write(fresh_copy(model.shape), out_path.c_str()))
        throw Error(ErrorCode::io, "BREP writer: cannot write '" + out_path + "'");
}

}  // namespace

OcctModel read_for_export(const std::string& in_path, const std::string& target, ConvertReport& r,
                          bool changes_document) {
    OcctModel model = changes_document ? read_model_from_file(in_path, /*read_attributes=*/true, /*keep_document=*/true)
                                       : read_model(in_path, /*read_attributes=*/true, /*keep_document=*/true);
    r.in_format = model.format;
    r.faces = model.faces.Extent();
    r.in_units = model.units;
    r.read_ms = model.read_ms;
    if (model.document.IsNull())
        throw Error(ErrorCode::occt_failure, "XDE reader gave no document for the " + target + " export");
    return model;
}

void write_cad(const std::string& in_path, const std::string& out_path, const ConvertOptions& options,
               ConvertReport& r) {
    // IGES to STEP changes the document (expand_named_groups): on a read of
    // its own, never the shared one the file's other outputs are written from.
    const bool expands = r.out_format == CadFormat::step && detect_format(in_path) == CadFormat::iges;
    OcctModel model = read_for_export(in_path, format_name(r.out_format), r, expands);
    DocumentCloser closer{model.document};
    // Formats without a declared unit (BREP) are written in their own.
    const bool declares_units = conversion_format_declares_units(r.output);
    const LengthUnit unit =
        declares_units ? target_unit(model.units, options.units) : conversion_format_fixed_unit(r.output);
    if (expands) expand_named_groups(model.document);

    const auto t0 = std::chrono::steady_clock::now();
    {
        std::lock_guard<std::mutex> lock(exchange_mutex());
        try {
            write_model(model, out_path, r.out_format, unit, options);
        } catch (const Standard_Failure& f) {
            throw Error(ErrorCode::occt_failure,
                        std::string(format_name(r.out_format)) + " writer: " + failure_text(f));
        }
    }
    r.write_ms = ms_since(t0);
    // Read back what was written (read_model takes exchange_mutex itself).
    const auto t_verify = std::chrono::steady_clock::now();
    try {
        OcctModel written = read_model(out_path, /*read_attributes=*/true, /*keep_document=*/true);
        DocumentCloser written_closer{written.document};
        const XdeContent in = content_of(model), out = content_of(written);
        const Losses lost = losses_of(in, out);
        for (std::string& w : shortfalls(in, out, lost, r.out_format)) r.warnings.push_back(std::move(w));
        r.out_units = declares_units ? written.units : length_unit_name(unit);
        if (r.out_units != length_unit_name(unit))
            r.warnings.push_back(std::string("the written file declares the unit '") + written.units + "', not '" +
                                 length_unit_name(unit) + "'");
        // Geometry read back in mm, as the source: directly comparable whatever the written unit.
        const GeometryMeasures &gin = measure_source(model), gout = measure_geometry(written.shape);
        nlohmann::ordered_json f = {{"source", source_json(model, gin)}};
        f["output"] = {
            {"format", conversion_format_name(r.output)}, {"units", r.out_units}, {"geometry", geometry_json(gout)}};
        f["relative_differences"] = compare_geometry(gin, gout, r.warnings);
        f["attributes"] = attributes_json(in, out, lost);
        r.fidelity = f.dump();
    } catch (const Error& e) {
        // The file is written; that OCCT cannot read it back is worth knowing
        // but does not undo the conversion.
        r.warnings.push_back(std::string("the written file could not be read back to check it: ") + e.what());
        r.out_units = length_unit_name(unit);
    }
    r.verify_ms = ms_since(t_verify);
}

}  // namespace nurbsrt::occt
