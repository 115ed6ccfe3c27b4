// IntCurvesFace_ShapeIntersector as the exact ray-casting reference (see
// reference_intersector.h).
#include "importer/reference/reference_intersector.h"

#include <BRepAdaptor_Surface.hxx>
#include <BRepGProp.hxx>
#include <BRep_Builder.hxx>
#include <GProp_GProps.hxx>
#include <Geom_BSplineSurface.hxx>
#include <IntCurvesFace_ShapeIntersector.hxx>
#include <ShapeUpgrade_ShapeDivideArea.hxx>
#include <Standard_Failure.hxx>
#include <TopExp.hxx>
#include <TopLoc_Location.hxx>
#include <TopExp_Explorer.hxx>
#include <TopTools_DataMapOfShapeInteger.hxx>
#include <TopTools_IndexedMapOfShape.hxx>
#include <TopoDS.hxx>
#include <TopoDS_Compound.hxx>
#include <gp_Dir.hxx>
#include <gp_Lin.hxx>
#include <gp_Pnt.hxx>
#include <gp_Trsf.hxx>

#include <chrono>
#include <cmath>

#include "importer/occt_shape.h"
#include "core/check.h"
#include "core/error.h"

namespace nurbsrt {
namespace {

using Clock = std::chrono::steady_clock;
double ms_since(Clock::time_point t0) { return std::chrono::duration<double, std::milli>(Clock::now() - t0).count(); }

// A placement as an OCCT location: only rigid motions (A orthonormal, det +1)
// qualify, since TopoDS forbids scaled or mirrored locations and gp_Trsf would
// silently orthogonalize anything else.
gp_Trsf to_trsf(const Affine& a) {
    const auto& m = a.m;
    const Vec3 c[3] = {{m[0], m[4], m[8]}, {m[1], m[5], m[9]}, {m[2], m[6], m[10]}};
    bool rigid = a.determinant() > 0;
    for (int i = 0; i < 3 && rigid; ++i)
        for (int j = 0; j < 3 && rigid; ++j) rigid = std::abs(dot(c[i], c[j]) - (i == j ? 1.0 : 0.0)) < 1e-9;
    if (!rigid) throw Error(ErrorCode::invalid_argument, "reference intersector: a placement must be a rigid motion");
    gp_Trsf t;
    t.SetValues(m[0], m[1], m[2], m[3], m[4], m[5], m[6], m[7], m[8], m[9], m[10], m[11]);
    return t;
}

// IntCurvesFace_Intersector finds a ray's roots on a face from a polyhedron of
// samples over the face's (u, v) box, refined by Newton: on a B-spline face of
// hundreds of spans (a coil of 20 turns) the samples lie far apart on the
// surface, and every ray sees dozens of near misses to refine: 65-140 ms a ray,
// against 1-2 ms on the same face cut into pieces of at most this many spans
// (cutting a B-spline at parameters is exact: knot insertion, Piegl & Tiller A5.3).
constexpr int kMaxSpansPerPiece = 32;

// The number of pieces a face is cut into for the search (1: searched whole).
int pieces_of(const TopoDS_Face& face) {
    const BRepAdaptor_Surface s(face, false);
    if (s.GetType() != GeomAbs_BSplineSurface) return 1;
    const Handle(Geom_BSplineSurface) b = s.BSpline();
    const int spans = (b->NbUKnots() - 1) * (b->NbVKnots() - 1);
    return (spans + kMaxSpansPerPiece - 1) / kMaxSpansPerPiece;
}

// `face` cut into about `pieces` faces of equal area (ShapeUpgrade_ShapeDivideArea);
// empty when OCCT cannot cut it (the face is then searched whole).
std::vector<TopoDS_Face> cut(const TopoDS_Face& face, int pieces) {
    std::vector<TopoDS_Face> out;
    try {
        GProp_GProps props;
        BRepGProp::SurfaceProperties(face, props);
        ShapeUpgrade_ShapeDivideArea divide(face);
        divide.MaxArea() = props.Mass() / pieces;
        if (!divide.Perform()) return out;
        for (TopExp_Explorer e(divide.Result(), TopAbs_FACE); e.More(); e.Next())
            out.push_back(TopoDS::Face(e.Current()));
    } catch (const Standard_Failure&) {
        out.clear();
    }
    return out;
}

}  // namespace

struct ReferenceIntersector::Impl {
    TopoDS_Shape shape;
    TopTools_IndexedMapOfShape faces;              // TopExp::MapShapes order: the face-index contract
    TopoDS_Compound searched;                      // the faces, dense B-spline faces cut into pieces
    TopTools_DataMapOfShapeInteger face_of_piece;  // a piece of `searched` -> its face's index
    IntCurvesFace_ShapeIntersector inter;
    double tolerance = ReferenceIntersector::kDefaultTolerance;
    double read_ms = 0, load_ms = 0;

    void load() {
        TopExp::MapShapes(shape, TopAbs_FACE, faces);
        const auto t0 = Clock::now();
        BRep_Builder b;
        b.MakeCompound(searched);
        for (int i = 1; i <= faces.Extent(); ++i) {
            const TopoDS_Face& face = TopoDS::Face(faces.FindKey(i));
            const int pieces = pieces_of(face);
            std::vector<TopoDS_Face> cuts = pieces > 1 ? cut(face, pieces) : std::vector<TopoDS_Face>{};
            if (cuts.empty()) cuts.push_back(face);
            for (const TopoDS_Face& piece : cuts) {
                b.Add(searched, piece);
                face_of_piece.Bind(piece, i);
            }
        }
        inter.Load(searched, tolerance);
        load_ms = ms_since(t0);
    }
};

ReferenceIntersector::ReferenceIntersector(const std::string& path, const std::vector<Affine>& placements,
                                           double tolerance)
    : impl_(std::make_unique<Impl>()) {
    impl_->tolerance = tolerance;
    const auto t0 = Clock::now();
    const occt::OcctModel model = occt::read_model(path, false);
    impl_->read_ms = ms_since(t0);
    if (placements.empty()) {
        impl_->shape = model.shape;
    } else {
        // Located copies in one compound: MapShapes visits copy after copy, each in
        // the original's order, so face c * N + i is face i of copy c (append_scene).
        BRep_Builder b;
        TopoDS_Compound c;
        b.MakeCompound(c);
        for (const Affine& a : placements) b.Add(c, model.shape.Moved(TopLoc_Location(to_trsf(a))));
        impl_->shape = c;
    }
    impl_->load();
}

ReferenceIntersector::ReferenceIntersector(const occt::OcctModel& model, double tolerance)
    : impl_(std::make_unique<Impl>()) {
    impl_->tolerance = tolerance;
    impl_->shape = model.shape;
    impl_->load();
}

ReferenceIntersector::~ReferenceIntersector() = default;

ReferenceHit ReferenceIntersector::cast(const Ray& r, double t_max) {
    ReferenceHit h;
    try {
        impl_->inter.Perform(gp_Lin(gp_Pnt(r.origin.x, r.origin.y, r.origin.z), gp_Dir(r.dir.x, r.dir.y, r.dir.z)), 0.0,
                             t_max);
    } catch (const Standard_Failure&) {
        // OCCT can throw (e.g. Standard_NullObject) on a few rays. No reference for this
        // ray; reload so that a possibly inconsistent state is not reused.
        h.error = true;
        impl_->inter.Load(impl_->searched, impl_->tolerance);
        return h;
    }
    if (!impl_->inter.IsDone()) return h;
    for (int k = 1; k <= impl_->inter.NbPnt(); ++k) {
        const double w = impl_->inter.WParameter(k);
        if (w > 0 && w < h.t) {
            h.hit = true;
            h.t = w;
            const int* face = impl_->face_of_piece.Seek(impl_->inter.Face(k));
            NURBSRT_CHECK(face != nullptr);  // every piece searched was bound to its face
            h.face = *face;
        }
    }
    return h;
}

int ReferenceIntersector::faces() const { return impl_->faces.Extent(); }
double ReferenceIntersector::read_ms() const { return impl_->read_ms; }
double ReferenceIntersector::load_ms() const { return impl_->load_ms; }

}  // namespace nurbsrt
