// Reading STEP/IGES/BREP into an OcctModel: one compound of all transferred roots,
// the face-index map, bodies, and (through XDE) colours and names.
#include <algorithm>
#include <cctype>
#include <filesystem>
#include <mutex>
#include <optional>

#include <BRepTools.hxx>
#include <BRep_Builder.hxx>
#include <BRep_Tool.hxx>
#include <IFSelect_ReturnStatus.hxx>
#include <IGESCAFControl_Reader.hxx>
#include <IGESControl_Reader.hxx>
#include <IGESData_GlobalSection.hxx>
#include <IGESData_IGESModel.hxx>
#include <Quantity_Color.hxx>
#include <STEPCAFControl_Reader.hxx>
#include <STEPControl_Reader.hxx>
#include <Standard_Failure.hxx>
#include <TColStd_SequenceOfAsciiString.hxx>
#include <TDF_ChildIterator.hxx>
#include <TDF_Label.hxx>
#include <TDataStd_Name.hxx>
#include <TDocStd_Document.hxx>
#include <TopExp.hxx>
#include <TopExp_Explorer.hxx>
#include <TopTools_IndexedDataMapOfShapeListOfShape.hxx>
#include <TopoDS.hxx>
#include <TopoDS_Compound.hxx>
#include <XCAFApp_Application.hxx>
#include <XSControl_Reader.hxx>
#include <XCAFDoc_DocumentTool.hxx>
#include <XCAFDoc_ShapeTool.hxx>
#include <XCAFPrs.hxx>
#include <gp_Trsf.hxx>
#include <XCAFPrs_DocumentExplorer.hxx>
#include <XCAFPrs_IndexedDataMapOfShapeStyle.hxx>
#include <XCAFPrs_Style.hxx>

#include "importer/internal.h"
#include "importer/shared_read.h"
#include "core/error.h"
#include "core/ascii.h"

namespace nurbsrt::occt {
namespace {

const char* status_name(IFSelect_ReturnStatus s) {
    switch (s) {
        case IFSelect_RetVoid:
            return "void (nothing read)";
        case IFSelect_RetDone:
            return "done";
        case IFSelect_RetError:
            return "error";
        case IFSelect_RetFail:
            return "fail";
        case IFSelect_RetStop:
            return "stop";
    }
    return "?";
}

// Unit names as STEP (".MILLI.", "METRE", "INCH") or IGES ("MM", "IN") spell them,
// normalised to short lowercase names.
std::string unit_short_name(std::string raw) {
    std::string s;
    for (char c : ascii_lower(std::move(raw)))
        if (std::isalpha(static_cast<unsigned char>(c))) s += c;
    if (s == "mm" || s == "millimetre" || s == "millimeter" || s == "millimetremetre") return "mm";
    if (s == "cm" || s == "centimetre" || s == "centimeter") return "cm";
    if (s == "m" || s == "metre" || s == "meter") return "m";
    if (s == "km" || s == "kilometre" || s == "kilometer") return "km";
    if (s == "in" || s == "inch" || s == "inches") return "inch";
    if (s == "ft" || s == "foot" || s == "feet") return "foot";
    if (s == "mi" || s == "mile") return "mile";
    if (s == "mil") return "mil";
    if (s == "um" || s == "micron" || s == "micrometre" || s == "micrometer") return "micron";
    if (s == "uin" || s == "microinch") return "microinch";
    return s;
}

std::string step_units(STEPControl_Reader& reader) {
    TColStd_SequenceOfAsciiString lengths, angles, solid_angles;
    reader.FileUnits(lengths, angles, solid_angles);
    std::vector<std::string> names;
    for (int i = 1; i <= lengths.Length(); ++i) {
        const std::string n = unit_short_name(lengths.Value(i).ToCString());
        if (!n.empty() && std::find(names.begin(), names.end(), n) == names.end()) names.push_back(n);
    }
    std::string out;
    for (const auto& n : names) out += (out.empty() ? "" : ",") + n;
    return out;
}

std::string iges_units(const IGESControl_Reader& reader) {
    const Handle(IGESData_IGESModel) model = reader.IGESModel();
    if (model.IsNull()) return {};
    const IGESData_GlobalSection& gs = model->GlobalSection();
    const Handle(TCollection_HAsciiString) name = gs.UnitName();
    if (!name.IsNull() && name->Length() > 0) return unit_short_name(name->ToCString());
    return length_unit_name(length_unit_from_iges_flag(gs.UnitFlag()));  // IGES 5.3 global parameter 14
}

Color to_color(const Quantity_Color& c) {
    // Quantity_Color stores linear RGB in OCCT 7.6, as the Scene wants.
    return Color{static_cast<float>(c.Red()), static_cast<float>(c.Green()), static_cast<float>(c.Blue())};
}

// Whether a solid's or shell's every shell is closed (BRep_Tool::IsClosed: each
// edge shared by two faces of the shell, seams counted twice); none: not closed.
bool all_shells_closed(const TopoDS_Shape& group) {
    bool any = false;
    for (TopExp_Explorer ex(group, TopAbs_SHELL); ex.More(); ex.Next()) {
        if (!BRep_Tool::IsClosed(ex.Current())) return false;
        any = true;
    }
    return any;
}

// Bodies by topology: every solid, then every shell outside solids, then all
// remaining free faces as one body. Same for both reader modes, so the body
// numbering does not depend on read_attributes.
void assign_bodies(OcctModel& m) {
    const int n = m.faces.Extent();
    m.attributes.assign(static_cast<size_t>(n), FaceAttributes{});
    std::vector<bool> done(static_cast<size_t>(n), false);
    auto claim = [&](const TopoDS_Shape& group, bool closed) {
        bool any = false;
        const uint32_t body = static_cast<uint32_t>(m.bodies.size());
        for (TopExp_Explorer ex(group, TopAbs_FACE); ex.More(); ex.Next()) {
            const int i = m.faces.FindIndex(ex.Current());
            if (i == 0 || done[static_cast<size_t>(i - 1)]) continue;
            done[static_cast<size_t>(i - 1)] = true;
            m.attributes[static_cast<size_t>(i - 1)].body = body;
            any = true;
        }
        if (!any) return;
        Body made;
        made.closed = closed;
        m.bodies.push_back(made);
    };
    for (TopExp_Explorer ex(m.shape, TopAbs_SOLID); ex.More(); ex.Next())
        claim(ex.Current(), all_shells_closed(ex.Current()));
    for (TopExp_Explorer ex(m.shape, TopAbs_SHELL, TopAbs_SOLID); ex.More(); ex.Next())
        claim(ex.Current(), all_shells_closed(ex.Current()));
    if (std::find(done.begin(), done.end(), false) != done.end()) claim(m.shape, false);
}

// The assembly tree as the document explorer walks it, depth first: each node's
// parent is the last node one level up, its id the path of child positions.
class PartTree {
public:
    explicit PartTree(std::vector<Part>& parts) : parts_(parts) {}

    int32_t add(int depth, const std::string& name, const XCAFPrs_Style& style, const gp_Trsf& placement) {
        // Deeper than one below the current path cannot come from a depth-first walk: a root then.
        if (depth < 0 || static_cast<size_t>(depth) > path_.size()) depth = 0;
        path_.resize(static_cast<size_t>(depth));
        children_.resize(static_cast<size_t>(depth));
        Part p;
        p.parent = depth > 0 ? path_.back() : -1;
        const int position = depth > 0 ? children_.back()++ : roots_++;
        p.id = (depth > 0 ? parts_[static_cast<size_t>(p.parent)].id + "/" : std::string()) + std::to_string(position);
        p.name = name;
        if (style.IsSetColorSurf()) {
            p.has_color = true;
            p.color = to_color(style.GetColorSurf());
        }
        for (int r = 0; r < 3; ++r)
            for (int c = 0; c < 4; ++c) p.placement[static_cast<size_t>(4 * r + c)] = placement.Value(r + 1, c + 1);
        const auto index = static_cast<int32_t>(parts_.size());
        parts_.push_back(std::move(p));
        path_.push_back(index);
        children_.push_back(0);
        return index;
    }

private:
    std::vector<Part>& parts_;
    std::vector<int32_t> path_;  // the parts from a root down to the last one added
    std::vector<int> children_;  // children so far of each part on the path
    int roots_ = 0;
};

// Names and colours from the XDE document, matched to our faces by located
// TShape. Follows what RWMesh_FaceIterator does for glTF export: the node's
// style is the default; styles of sub-shapes (faces, solids) of the part override it.
void apply_xde_attributes(OcctModel& m, const Handle(TDocStd_Document) & doc) {
    size_t unmatched = 0;
    std::vector<bool> body_named(m.bodies.size(), false);
    PartTree tree(m.parts);
    for (XCAFPrs_DocumentExplorer ex(doc, XCAFPrs_DocumentExplorerFlags_None); ex.More(); ex.Next()) {
        const XCAFPrs_DocumentNode& node = ex.Current();
        std::string name = label_name(node.Label);
        if (name.empty()) name = label_name(node.RefLabel);
        const XCAFPrs_Style& style = node.Style;
        const int32_t leaf = tree.add(ex.CurrentDepth(), name, style, node.Location.Transformation());
        if (node.IsAssembly) continue;  // its parts follow, depth first
        TopoDS_Shape part;
        if (!XCAFDoc_ShapeTool::GetShape(node.RefLabel, part) || part.IsNull()) continue;
        part.Location(node.Location, false);

        // Sub-shape styles, most specific last so that faces win over solids.
        XCAFPrs_IndexedDataMapOfShapeStyle styles;
        XCAFPrs::CollectStyleSettings(node.RefLabel, TopLoc_Location(), styles);
        NCollection_DataMap<TopoDS_Shape, Quantity_Color, TopTools_ShapeMapHasher> face_color;
        for (int type = TopAbs_COMPOUND; type <= TopAbs_FACE; ++type) {
            for (XCAFPrs_IndexedDataMapOfShapeStyle::Iterator it(styles); it.More(); it.Next()) {
                if (it.Key().ShapeType() != type || !it.Value().IsSetColorSurf()) continue;
                const TopoDS_Shape located = it.Key().Located(node.Location);
                for (TopExp_Explorer fe(located, TopAbs_FACE); fe.More(); fe.Next())
                    face_color.Bind(fe.Current(), it.Value().GetColorSurf());
            }
        }
        // Sub-shape names (rare: named faces).
        NCollection_DataMap<TopoDS_Shape, std::string, TopTools_ShapeMapHasher> face_name;
        for (TDF_ChildIterator ci(node.RefLabel); ci.More(); ci.Next()) {
            TopoDS_Shape sub;
            if (!XCAFDoc_ShapeTool::GetShape(ci.Value(), sub) || sub.IsNull()) continue;
            const std::string n = label_name(ci.Value());
            if (n.empty()) continue;
            for (TopExp_Explorer fe(sub.Located(node.Location), TopAbs_FACE); fe.More(); fe.Next())
                face_name.Bind(fe.Current(), n);
        }

        for (TopExp_Explorer fe(part, TopAbs_FACE); fe.More(); fe.Next()) {
            const int i = m.faces.FindIndex(fe.Current());
            if (i == 0) {
                ++unmatched;
                continue;
            }
            FaceAttributes& a = m.attributes[static_cast<size_t>(i - 1)];
            if (const Quantity_Color* c = face_color.Seek(fe.Current())) {
                a.has_color = true;
                a.color = to_color(*c);
            } else if (style.IsSetColorSurf()) {
                a.has_color = true;
                a.color = to_color(style.GetColorSurf());
            }
            if (const std::string* fn = face_name.Seek(fe.Current()))
                a.name = *fn;
            else
                a.name = name;
            if (a.body < m.bodies.size() && a.has_color && !m.bodies[a.body].has_color) {
                // Colour set on the solid or its faces only: the body takes its first face's.
                m.bodies[a.body].has_color = true;
                m.bodies[a.body].color = a.color;
            }
            if (a.body < m.bodies.size() && m.bodies[a.body].part < 0) m.bodies[a.body].part = leaf;
            if (a.body < m.bodies.size() && !body_named[a.body]) {
                body_named[a.body] = true;
                Body& b = m.bodies[a.body];
                b.name = name;
                if (style.IsSetColorSurf()) {
                    b.has_color = true;
                    b.color = to_color(style.GetColorSurf());
                }
            }
        }
    }
    if (unmatched > 0)
        m.warnings.push_back(std::to_string(unmatched) +
                             " face(s) of the XDE document not found in the transferred shape; "
                             "their colours/names were not applied");
}

// Compound of all transferred roots, as OneShape() would build it (a single
// root stays itself, which gives the same MapShapes order).
TopoDS_Shape all_roots(XSControl_Reader& reader) { return reader.OneShape(); }

// The file status after ReadFile, as the user's error: `format` names the reader.
void check_read_status(IFSelect_ReturnStatus st, const std::string& format) {
    // RetVoid: parsed fine but holds no entities at all.
    if (st == IFSelect_RetVoid) throw Error(ErrorCode::no_faces, format + " file read, but it holds no entities");
    if (st != IFSelect_RetDone)
        throw Error(ErrorCode::unreadable_file, format + " reader: file status " + status_name(st));
}

// What follows a successful ReadFile, the same for STEP and IGES: transfer the
// roots (into an XDE document when attributes are read), then the faces, their
// bodies and the document's colours and names. `reader` is `caf`'s own reader
// when attributes are read, else a plain one.
template <class CafReader>
void transfer_model(XSControl_Reader& reader, CafReader& caf, bool attributes, bool keep_document,
                    const std::string& format, OcctModel& m) {
    Handle(TDocStd_Document) doc;
    const int roots = reader.NbRootsForTransfer();
    if (attributes) {
        XCAFApp_Application::GetApplication()->NewDocument("MDTV-XCAF", doc);
        caf.Transfer(doc);  // false also for "nothing to transfer": judged below
    } else {
        reader.TransferRoots();
    }
    if (reader.NbShapes() == 0) {
        // A syntactically fine file with nothing to transfer holds no faces;
        // roots that all fail to transfer mean content OCCT cannot read.
        if (roots == 0) throw Error(ErrorCode::no_faces, format + " file read, but it has no shape to transfer");
        throw Error(ErrorCode::unreadable_file,
                    format + " reader: 0 of " + std::to_string(roots) + " roots transferred");
    }
    m.shape = all_roots(reader);
    if (m.shape.IsNull()) throw Error(ErrorCode::unreadable_file, format + " reader: transferred shape is null");
    TopExp::MapShapes(m.shape, TopAbs_FACE, m.faces);
    assign_bodies(m);
    if (attributes && !doc.IsNull()) {
        apply_xde_attributes(m, doc);
        if (keep_document)
            m.document = doc;
        else
            XCAFApp_Application::GetApplication()->Close(doc);
    }
}

void read_step(const std::string& path, bool attributes, bool keep_document, OcctModel& m) {
    STEPCAFControl_Reader caf;
    STEPControl_Reader plain;
    STEPControl_Reader& reader = attributes ? caf.ChangeReader() : plain;
    if (attributes) {
        caf.SetColorMode(true);
        caf.SetNameMode(true);
        // Layers only matter to a document handed on (the STEP/IGES writers
        // carry them); the renderer's import does not use them.
        caf.SetLayerMode(keep_document);
        caf.SetPropsMode(false);
        caf.SetGDTMode(false);
        caf.SetMatMode(false);
        caf.SetViewMode(false);
    }
    check_read_status(attributes ? caf.ReadFile(path.c_str()) : plain.ReadFile(path.c_str()), "STEP");
    m.units = step_units(reader);
    transfer_model(reader, caf, attributes, keep_document, "STEP", m);
}

void read_iges(const std::string& path, bool attributes, bool keep_document, OcctModel& m) {
    IGESCAFControl_Reader caf;
    IGESControl_Reader plain;
    IGESControl_Reader& reader = attributes ? static_cast<IGESControl_Reader&>(caf) : plain;
    if (attributes) {
        caf.SetColorMode(true);
        caf.SetNameMode(true);
        caf.SetLayerMode(keep_document);  // as for STEP
    }
    check_read_status(reader.ReadFile(path.c_str()), "IGES");
    m.units = iges_units(reader);
    transfer_model(reader, caf, attributes, keep_document, "IGES", m);
}

// OCCT's own exact format (BRepTools::Write): one shape, no colours, names or
// units (its numbers are taken as mm, what OCCT's readers deliver). With
// attributes, an XDE document holding the shape as one part, so that exports
// and the assembly tree treat it like any other file.
void read_brep(const std::string& path, bool attributes, bool keep_document, OcctModel& m) {
    BRep_Builder builder;
    if (!BRepTools::Read(m.shape, path.c_str(), builder) || m.shape.IsNull())
        throw Error(ErrorCode::unreadable_file, "BREP reader: the file holds no readable shape");
    TopExp::MapShapes(m.shape, TopAbs_FACE, m.faces);
    assign_bodies(m);
    if (!attributes) return;
    Handle(TDocStd_Document) doc;
    XCAFApp_Application::GetApplication()->NewDocument("MDTV-XCAF", doc);
    XCAFDoc_DocumentTool::ShapeTool(doc->Main())->AddShape(m.shape, /*makeAssembly=*/Standard_False);
    apply_xde_attributes(m, doc);
    if (keep_document)
        m.document = doc;
    else
        XCAFApp_Application::GetApplication()->Close(doc);
}

}  // namespace

std::string label_name(const TDF_Label& label) {
    Handle(TDataStd_Name) attr;
    if (label.IsNull() || !label.FindAttribute(TDataStd_Name::GetID(), attr)) return {};
    // TCollection_AsciiString from an extended string with no replacement char is UTF-8.
    return TCollection_AsciiString(attr->Get()).ToCString();
}

namespace {

// The read a SharedRead keeps (one at a time in a process: the file worker's).
struct SharedModel {
    std::mutex m;
    std::string path;  // empty: no SharedRead lives
    bool done = false;
    OcctModel model;
    std::optional<Error> error;
    int reads = 0, uses = 0;
    double read_ms = 0;
};

SharedModel& shared_model() {
    static SharedModel s;
    return s;
}

}  // namespace

DocumentCloser::~DocumentCloser() {
    if (doc.IsNull()) return;
    SharedModel& s = shared_model();
    {
        std::lock_guard<std::mutex> lock(s.m);
        if (!s.path.empty() && s.model.document == doc) return;  // the SharedRead closes it
    }
    XCAFApp_Application::GetApplication()->Close(doc);
}

std::mutex& exchange_mutex() {
    static std::mutex m;
    return m;
}

OcctModel read_model(const std::string& path, bool read_attributes, bool keep_document) {
    SharedModel& s = shared_model();
    std::unique_lock<std::mutex> lock(s.m);
    if (s.path.empty() || s.path != path) {
        lock.unlock();
        return read_model_from_file(path, read_attributes, keep_document);
    }
    ++s.uses;
    if (!s.done) {
        // Everything any use may ask for: attributes, and the document the writers need.
        s.done = true;
        try {
            ++s.reads;
            s.model = read_model_from_file(path, true, true);
            s.read_ms = s.model.read_ms;
        } catch (const Error& e) {
            s.error = e;
        } catch (const std::exception& e) {
            // Any failure is every later use's error too, never an empty model.
            s.error = Error(ErrorCode::internal, e.what());
        }
    }
    if (s.error) throw *s.error;
    OcctModel m = s.model;
    if (!keep_document) m.document.Nullify();
    if (s.uses > 1) m.read_ms = 0;  // served: this use paid no read
    return m;
}

void forget_shared_meshes(bool keep_export_mesh) {
    SharedModel& s = shared_model();
    std::lock_guard<std::mutex> lock(s.m);
    if (!s.done || s.error) return;
    if (keep_export_mesh && s.model.measures->export_mesh) return;
    BRepTools::Clean(s.model.shape);
    s.model.measures->export_mesh.reset();
}

OcctModel read_model_from_file(const std::string& path, bool read_attributes, bool keep_document) {
    if (keep_document) read_attributes = true;
    route_occt_messages();
    std::error_code ec;
    if (!std::filesystem::is_regular_file(path, ec))
        throw Error(ErrorCode::io, "cannot open '" + path + "': no such file (or not a regular file)");
    OcctModel m;
    m.format = detect_format(path);
    if (m.format == CadFormat::unknown)
        throw Error(ErrorCode::unsupported_format, "'" + path +
                                                       "' is neither STEP (ISO-10303-21 header), IGES (80-column "
                                                       "records) nor OCCT's text BREP (CASCADE Topology header)");
    const auto t0 = std::chrono::steady_clock::now();
    {
        std::lock_guard<std::mutex> lock(exchange_mutex());
        const std::string who = std::string(format_name(m.format)) + " reader: ";
        try {
            if (m.format == CadFormat::step)
                read_step(path, read_attributes, keep_document, m);
            else if (m.format == CadFormat::iges)
                read_iges(path, read_attributes, keep_document, m);
            else
                read_brep(path, read_attributes, keep_document, m);
        } catch (const Standard_Failure& f) {
            throw Error(ErrorCode::occt_failure, who + failure_text(f));
        } catch (const std::bad_alloc&) {
            throw Error(ErrorCode::occt_failure, who + "out of memory");
        }
    }
    m.read_ms = ms_since(t0);
    if (m.faces.Extent() == 0)
        throw Error(ErrorCode::no_faces, std::string(format_name(m.format)) + " file read, but it holds no faces (" +
                                             "only curves, points or empty shapes)");
    return m;
}

}  // namespace nurbsrt::occt

namespace nurbsrt {

SharedRead::SharedRead(const std::string& path) {
    occt::SharedModel& s = occt::shared_model();
    std::lock_guard<std::mutex> lock(s.m);
    if (!s.path.empty()) throw Error(ErrorCode::internal, "one shared read at a time");
    s.path = path;
}

SharedRead::~SharedRead() {
    occt::SharedModel& s = occt::shared_model();
    std::lock_guard<std::mutex> lock(s.m);
    if (!s.model.document.IsNull()) XCAFApp_Application::GetApplication()->Close(s.model.document);
    s.model = occt::OcctModel{};
    s.path.clear();
    s.done = false;
    s.error.reset();
    s.reads = s.uses = 0;
    s.read_ms = 0;
}

void SharedRead::forget_meshes() { occt::forget_shared_meshes(); }

int SharedRead::reads() const {
    std::lock_guard<std::mutex> lock(occt::shared_model().m);
    return occt::shared_model().reads;
}

int SharedRead::uses() const {
    std::lock_guard<std::mutex> lock(occt::shared_model().m);
    return occt::shared_model().uses;
}

double SharedRead::read_ms() const {
    std::lock_guard<std::mutex> lock(occt::shared_model().m);
    return occt::shared_model().read_ms;
}

}  // namespace nurbsrt
