// The referee of disputes between our hits and OCCT's intersector, shared by
// the accuracy and full-frame tests: the distance of a point from a trimmed
// face by BRepExtrema_DistShapeShape (vertex to face), and a ray's point as gp_Pnt.
#pragma once

#include <BRepBuilderAPI_MakeVertex.hxx>
#include <BRepExtrema_DistShapeShape.hxx>
#include <BRep_Tool.hxx>
#include <GeomAPI_ProjectPointOnSurf.hxx>
#include <GeomLProp_SLProps.hxx>
#include <Geom_Surface.hxx>
#include <Standard_Failure.hxx>
#include <TopoDS_Face.hxx>
#include <TopoDS_Vertex.hxx>
#include <gp_Pnt.hxx>

#include <cmath>
#include <limits>

#include "renderer/camera.h"

namespace nurbsrt::test {

// Distance from p to the trimmed face; +inf when OCCT fails.
inline double dist_to_face(const TopoDS_Face& f, const gp_Pnt& p) {
    try {
        const TopoDS_Vertex v = BRepBuilderAPI_MakeVertex(p).Vertex();
        BRepExtrema_DistShapeShape d(v, f);
        if (!d.IsDone() || d.NbSolution() == 0) return std::numeric_limits<double>::infinity();
        return d.Value();
    } catch (const Standard_Failure&) {
        return std::numeric_limits<double>::infinity();
    }
}

// |n . d| at the point of the face's surface nearest p: the cosine of the angle
// between the surface normal there and the ray direction d (unit). NaN when OCCT
// cannot project p or the normal is undefined (a pole).
inline double incidence_cosine(const TopoDS_Face& f, const gp_Pnt& p, const Vec3& d) {
    try {
        const Handle(Geom_Surface) s = BRep_Tool::Surface(f);
        GeomAPI_ProjectPointOnSurf proj(p, s);
        if (!proj.IsDone() || proj.NbPoints() == 0) return std::numeric_limits<double>::quiet_NaN();
        double u = 0, v = 0;
        proj.LowerDistanceParameters(u, v);
        GeomLProp_SLProps props(s, u, v, 1, 1e-12);
        if (!props.IsNormalDefined()) return std::numeric_limits<double>::quiet_NaN();
        const gp_Dir& n = props.Normal();
        return std::fabs(n.X() * d.x + n.Y() * d.y + n.Z() * d.z);
    } catch (const Standard_Failure&) {
        return std::numeric_limits<double>::quiet_NaN();
    }
}

inline gp_Pnt at(const Ray& r, double t) {
    return gp_Pnt(r.origin.x + t * r.dir.x, r.origin.y + t * r.dir.y, r.origin.z + t * r.dir.z);
}

}  // namespace nurbsrt::test
