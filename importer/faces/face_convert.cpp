// One face to a clamped, non-periodic B-spline surface (convert_face): an
// analytic surface alone with the map of the face's (u,v) (uv_map.h), a
// B-spline surface as it is, anything else with its edges by
// BRepBuilderAPI_NurbsConvert; its parameter box, and the Scene form of the surface.
#include <algorithm>
#include <cmath>
#include <optional>

#include <BRepBuilderAPI_Copy.hxx>
#include <BRepBuilderAPI_NurbsConvert.hxx>
#include <BRepTools.hxx>
#include <BRep_Tool.hxx>
#include <Geom_ElementarySurface.hxx>
#include <Geom_RectangularTrimmedSurface.hxx>
#include <Geom_SweptSurface.hxx>
#include <GeomConvert.hxx>
#include <Geom_Surface.hxx>
#include <Precision.hxx>
#include <Standard_Failure.hxx>
#include <TColStd_Array1OfReal.hxx>
#include <TColStd_Array2OfReal.hxx>
#include <TColgp_Array2OfPnt.hxx>
#include <TopLoc_Location.hxx>
#include <TopoDS.hxx>

#include "importer/internal.h"
#include "core/error.h"

namespace nurbsrt::occt {
namespace {

// True when the flat knot vector starts and ends with degree+1 equal knots.
bool clamped(const TColStd_Array1OfReal& flat, int degree) {
    const int lo = flat.Lower(), hi = flat.Upper();
    for (int k = 1; k <= degree; ++k) {
        if (flat(lo + k) != flat(lo) || flat(hi - k) != flat(hi)) return false;
    }
    return true;
}

// Makes a periodic direction non-periodic over a range that contains the
// face's pcurves: pcurves on a periodic surface may sit one period (or part
// of one) away from the knot range, and a clamped surface is only valid on
// its knot range. Segment() keeps the parametrization, so (u,v) of the face
// stay valid.
void unperiodize(Geom_BSplineSurface& s, double fu0, double fu1, double fv0, double fv1) {
    double u0, u1, v0, v1;
    s.Bounds(u0, u1, v0, v1);
    double tu0 = u0, tu1 = u1, tv0 = v0, tv1 = v1;
    bool segment = false;
    const double eps = Precision::PConfusion();
    if (s.IsUPeriodic() && fu1 > fu0 && (fu0 < u0 - eps || fu1 > u1 + eps)) {
        tu0 = fu0;
        tu1 = fu0 + s.UPeriod();
        segment = true;
    }
    if (s.IsVPeriodic() && fv1 > fv0 && (fv0 < v0 - eps || fv1 > v1 + eps)) {
        tv0 = fv0;
        tv1 = fv0 + s.VPeriod();
        segment = true;
    }
    if (segment) s.Segment(tu0, tu1, tv0, tv1);
    if (s.IsUPeriodic()) s.SetUNotPeriodic();
    if (s.IsVPeriodic()) s.SetVNotPeriodic();
}

// The last steps of every conversion: non-periodic over the face's box (in the
// surface's parameters), clamped, and moved by the face's location.
Handle(Geom_BSplineSurface) finish_surface(Handle(Geom_BSplineSurface) bs, double fu0, double fu1, double fv0,
                                           double fv1, const TopLoc_Location& loc) {
    unperiodize(*bs, fu0, fu1, fv0, fv1);
    if (!clamped(bs->UKnotSequence(), bs->UDegree()) || !clamped(bs->VKnotSequence(), bs->VDegree())) {
        double u0, u1, v0, v1;
        bs->Bounds(u0, u1, v0, v1);
        bs->Segment(u0, u1, v0, v1);  // inserts end knots to full multiplicity
    }
    if (!loc.IsIdentity()) bs = Handle(Geom_BSplineSurface)::DownCast(bs->Transformed(loc.Transformation()));
    return bs;
}

// The face itself with copies of its edges (no geometry copied): every
// converted face owns its edges, so faces can later be meshed in parallel
// without two threads writing one edge.
TopoDS_Face copied_face(const TopoDS_Face& face) {
    BRepBuilderAPI_Copy copy(face, /*copyGeom=*/Standard_False, /*copyMesh=*/Standard_False);
    if (!copy.IsDone() || copy.Shape().IsNull() || copy.Shape().ShapeType() != TopAbs_FACE)
        throw Error(ErrorCode::occt_failure, "BRepBuilderAPI_Copy failed");
    return TopoDS::Face(copy.Shape());
}

// Surfaces whose conversion is exact and whose parameters stay separable (one
// function per direction; see uv_map.h), also trimmed: the elementary ones,
// and the swept ones (a curve revolved or extruded: the sweep's parameter and
// the curve's each map alone). Whether GeomConvert was exact for the curve
// there is what UVMap::between checks.
Handle(Geom_Surface) separable_surface(const Handle(Geom_Surface) & g) {
    Handle(Geom_Surface) basis = g;
    if (const auto rts = Handle(Geom_RectangularTrimmedSurface)::DownCast(g); !rts.IsNull())
        basis = rts->BasisSurface();
    if (Handle(Geom_ElementarySurface)::DownCast(basis).IsNull() && Handle(Geom_SweptSurface)::DownCast(basis).IsNull())
        return {};
    return basis;
}

// Relative excess of a box over its surface's period or parameter range that
// is rounding, not a face reaching further (which its pcurves would show by
// far more).
constexpr double kRounding = 1e-9;

// A face box as GeomConvert takes it, false when it cannot: over one period of
// a periodic direction by rounding (u from -4.8e-13 to 2 pi - 4.8e-13), cut
// to exactly one period, starting at the nearby multiple of the period if any
// (Convert_*ToBSplineSurface fails on a whole period from a start just below
// 0: NCollection_Array2::Allocate); over a bounded direction's range by
// rounding (a sphere's latitude past the pole), clamped to it.
bool convertible_range(bool periodic, double period, double lo, double hi, double& t0, double& t1) {
    const double eps = kRounding * std::max(t1 - t0, 1.0);
    if (periodic) {
        if (t1 - t0 < period - eps) return true;
        if (t1 - t0 > period + eps) return false;
        const double k = std::round(t0 / period) * period;
        if (std::fabs(t0 - k) <= eps) t0 = k;
        t1 = t0 + period;
        return true;
    }
    if (t0 < lo) {
        if (lo - t0 > eps) return false;
        t0 = lo;
    }
    if (t1 > hi) {
        if (t1 - hi > eps) return false;
        t1 = hi;
    }
    return t1 > t0;
}

// The surface converted alone (GeomConvert, microseconds) with the map from
// the face's (u,v) to the new ones, instead of BRepBuilderAPI_NurbsConvert,
// which re-fits every pcurve of the face (most of an import's time on
// mechanical parts). Empty when that map cannot be had; the caller then
// converts the whole face.
std::optional<ConvertedFace> convert_surface_alone(const TopoDS_Face& face, const Handle(Geom_Surface) & g,
                                                   const TopLoc_Location& loc) {
    const Handle(Geom_Surface) basis = separable_surface(g);
    if (basis.IsNull()) return std::nullopt;
    double fu0 = 0, fu1 = 0, fv0 = 0, fv1 = 0;
    BRepTools::UVBounds(face, fu0, fu1, fv0, fv1);
    if (!(fu1 > fu0) || !(fv1 > fv0) || Precision::IsInfinite(fu0) || Precision::IsInfinite(fu1) ||
        Precision::IsInfinite(fv0) || Precision::IsInfinite(fv1))
        return std::nullopt;
    double bu0, bu1, bv0, bv1;
    basis->Bounds(bu0, bu1, bv0, bv1);
    if (!convertible_range(basis->IsUPeriodic(), basis->IsUPeriodic() ? basis->UPeriod() : 0, bu0, bu1, fu0, fu1) ||
        !convertible_range(basis->IsVPeriodic(), basis->IsVPeriodic() ? basis->VPeriod() : 0, bv0, bv1, fv0, fv1))
        return std::nullopt;
    Handle(Geom_BSplineSurface) bs;
    std::optional<UVMap> map;
    try {
        bs = GeomConvert::SurfaceToBSplineSurface(new Geom_RectangularTrimmedSurface(basis, fu0, fu1, fv0, fv1));
        if (!bs.IsNull()) map = UVMap::between(basis, bs, fu0, fu1, fv0, fv1);
    } catch (const Standard_Failure&) {
        return std::nullopt;  // e.g. a box over more than one period: the whole face is converted instead
    }
    if (!map) return std::nullopt;
    double su0, su1, sv0, sv1;
    bs->Bounds(su0, su1, sv0, sv1);
    ConvertedFace out;
    out.face = copied_face(face);
    out.surface = finish_surface(bs, su0, su1, sv0, sv1, loc);
    out.map = std::move(*map);
    return out;
}

}  // namespace

double UVBox::diagonal() const { return std::hypot(u1 - u0, v1 - v0); }

ConvertedFace convert_face(const TopoDS_Face& face) {
    route_occt_messages();
    ConvertedFace out;
    try {
        TopLoc_Location face_loc;
        const Handle(Geom_Surface) original = BRep_Tool::Surface(face, face_loc);
        if (original.IsNull()) throw Error(ErrorCode::occt_failure, "face has no surface");
        if (Handle(Geom_BSplineSurface)::DownCast(original).IsNull()) {
            if (std::optional<ConvertedFace> alone = convert_surface_alone(face, original, face_loc)) return *alone;
            // Copies of the edges too (copy = true), as copied_face gives.
            BRepBuilderAPI_NurbsConvert nc(face, Standard_True);
            if (!nc.IsDone()) throw Error(ErrorCode::occt_failure, "BRepBuilderAPI_NurbsConvert failed");
            if (nc.Shape().IsNull() || nc.Shape().ShapeType() != TopAbs_FACE)
                throw Error(ErrorCode::occt_failure, "BRepBuilderAPI_NurbsConvert gave no face");
            out.face = TopoDS::Face(nc.Shape());
        } else {
            // Already a B-spline surface: NurbsConvert would return the same
            // surface but re-approximates every edge curve, which can cost
            // seconds on one face. A plain copy keeps the exact pcurves and the
            // same (u,v).
            out.face = copied_face(face);
        }

        TopLoc_Location loc;
        const Handle(Geom_Surface) g = BRep_Tool::Surface(out.face, loc);
        if (g.IsNull()) throw Error(ErrorCode::occt_failure, "converted face has no surface");
        Handle(Geom_BSplineSurface) bs = Handle(Geom_BSplineSurface)::DownCast(g);
        // NurbsConvert leaves B-splines as they are but may wrap others (e.g. a
        // trimmed B-spline); GeomConvert gives a fresh copy either way, which we
        // need because the surface may be shared and we modify it below.
        if (bs.IsNull())
            bs = GeomConvert::SurfaceToBSplineSurface(g);
        else
            bs = Handle(Geom_BSplineSurface)::DownCast(bs->Copy());
        if (bs.IsNull()) throw Error(ErrorCode::occt_failure, "surface is not convertible to a B-spline");

        double fu0 = 0, fu1 = 0, fv0 = 0, fv1 = 0;
        BRepTools::UVBounds(out.face, fu0, fu1, fv0, fv1);
        out.surface = finish_surface(bs, fu0, fu1, fv0, fv1, loc);
    } catch (const Standard_Failure& f) {
        throw Error(ErrorCode::occt_failure, "NURBS conversion: " + failure_text(f));
    }
    return out;
}

UVBox face_uv_box(const ConvertedFace& cf) {
    double su0, su1, sv0, sv1;
    cf.surface->Bounds(su0, su1, sv0, sv1);
    UVBox b;
    BRepTools::UVBounds(cf.face, b.u0, b.u1, b.v0, b.v1);
    // Each direction's map is increasing: the box's corners map to the box.
    const Vec2 lo = cf.map.to_surface({b.u0, b.v0}), hi = cf.map.to_surface({b.u1, b.v1});
    b = {lo.x, hi.x, lo.y, hi.y};
    // pcurves may stray slightly outside the surface's range in real files
    // (whose edges can lie 0.3 mm off their pcurves); the
    // Scene's box must lie inside the knot range.
    b.u0 = std::clamp(b.u0, su0, su1);
    b.u1 = std::clamp(b.u1, su0, su1);
    b.v0 = std::clamp(b.v0, sv0, sv1);
    b.v1 = std::clamp(b.v1, sv0, sv1);
    if (!(b.u1 > b.u0)) {
        b.u0 = su0;
        b.u1 = su1;
    }
    if (!(b.v1 > b.v0)) {
        b.v0 = sv0;
        b.v1 = sv1;
    }
    return b;
}

NurbsSurface to_scene_surface(const Geom_BSplineSurface& s) {
    NurbsSurface n;
    n.degree_u = s.UDegree();
    n.degree_v = s.VDegree();
    n.num_u = s.NbUPoles();
    n.num_v = s.NbVPoles();
    const TColStd_Array1OfReal& ku = s.UKnotSequence();
    const TColStd_Array1OfReal& kv = s.VKnotSequence();
    n.knots_u.assign(ku.begin(), ku.end());
    n.knots_v.assign(kv.begin(), kv.end());
    const TColgp_Array2OfPnt& poles = s.Poles();
    const TColStd_Array2OfReal* weights = s.Weights();  // null when non-rational
    n.cp.resize(static_cast<size_t>(n.num_u) * static_cast<size_t>(n.num_v));
    for (int i = 0; i < n.num_u; ++i) {
        for (int j = 0; j < n.num_v; ++j) {
            const gp_Pnt& p = poles(poles.LowerRow() + i, poles.LowerCol() + j);
            const double w = weights != nullptr ? (*weights)(weights->LowerRow() + i, weights->LowerCol() + j) : 1.0;
            // Rational iff a weight differs from 1: IsURational() speaks of one
            // direction only, so the weights are what tells.
            if (w != 1.0) n.rational = true;
            n.cp[static_cast<size_t>(i) * n.num_v + j] = Vec4{w * p.X(), w * p.Y(), w * p.Z(), w};
        }
    }
    return n;
}

}  // namespace nurbsrt::occt
