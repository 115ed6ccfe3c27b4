// The referee of disputes between our hits and OCCT's intersector, shared by
// the accuracy and full-frame tests: the distance of a point from a trimmed
// face by BRepExtrema_DistShapeShape (vertex to face), and a ray's point as gp_Pnt.
#pragma once

#include <BRepBuilderAPI_MakeVertex.hxx>
#include <BRepExtrema_DistShapeShape.hxx>
#include <Standard_Failure.hxx>
#include <TopoDS_Face.hxx>
#include <TopoDS_Vertex.hxx>
#include <gp_Pnt.hxx>

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

inline gp_Pnt at(const Ray& r, double t) {
    return gp_Pnt(r.origin.x + t * r.dir.x, r.origin.y + t * r.dir.y, r.origin.z + t * r.dir.z);
}

}  // namespace nurbsrt::test
