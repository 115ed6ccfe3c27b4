// From a face's own (u,v) (its pcurves, its triangulation, BRepTools::UVBounds)
// to the (u,v) of the B-spline surface it was converted to, and back.
//
// Converting an analytic surface alone (GeomConvert) is exact and takes
// microseconds, but a circle's rational quadratic form is not parametrized by
// its angle (Piegl & Tiller 7.5), so the face's pcurves no longer hold in the new
// (u,v). BRepBuilderAPI_NurbsConvert re-fits every pcurve to the new surface
// (ProjLib approximation), which took 92 % of a mechanical part's import. For
// the surfaces where a direction's parameter depends on that direction alone
// (planes, cylinders, cones, spheres, tori: a tensor product of a line or a
// circle with a line or a circle), the map is one monotone function per
// direction, found here by Newton on the iso-curves of both surfaces
// (Piegl & Tiller 6.1, point inversion on a curve) and checked before use.
//
// Importer-internal (OCCT headers); copied with ConvertedFace (handles only).
#pragma once

#include <optional>
#include <vector>

#include <Geom_BSplineSurface.hxx>
#include <Geom_Curve.hxx>
#include <Geom_Surface.hxx>
#include <GeomAdaptor_Curve.hxx>

#include "core/vec.h"

namespace nurbsrt::occt {

class UVMap {
public:
    // The identity: the face's (u,v) are the surface's.
    UVMap() = default;

    // The map from `face_surface`'s (u,v) over the face box [u0,u1]x[v0,v1] to
    // `converted`'s, which GeomConvert made from it (same location, not yet
    // transformed). Empty when the parameters do not separate into one
    // function per direction, or when the check over the box fails: the caller
    // then converts with the face's edges instead.
    static std::optional<UVMap> between(const Handle(Geom_Surface) & face_surface,
                                        const Handle(Geom_BSplineSurface) & converted, double u0, double u1, double v0,
                                        double v1);

    bool identity() const { return !u_.active; }
    Vec2 to_surface(Vec2 face_uv) const;
    Vec2 to_face(Vec2 surface_uv) const;

private:
    // One direction: the iso-curve of each surface through a reference point
    // of the box, on which the other's point is inverted.
    struct Axis {
        bool active = false;
        Handle(Geom_Curve) face_iso, surface_iso;
        double face0 = 0, face1 = 1, surface0 = 0, surface1 = 1;  // the box in each parametrization
        // to_surface's seeds: s and ds/dt at evenly spaced t over [face0, face1]
        // (cubic Hermite between them); empty: the linear map.
        std::vector<double> table_s, table_ds;
        // surface_iso's evaluator with its span cache (BSplCLib_Cache): the
        // inversions evaluate it at nearby parameters over and over, which
        // Geom_BSplineCurve::D1 does from the knots and poles every time. Its
        // cache is mutable: a map is used by one thread at a time (the import
        // works on each face in one task).
        Handle(GeomAdaptor_Curve) surface_eval;
        double to_surface(double t) const;
        double to_face(double s) const;
        void tabulate();
        double seed(double t) const;
    };
    Axis u_, v_;
};

}  // namespace nurbsrt::occt
