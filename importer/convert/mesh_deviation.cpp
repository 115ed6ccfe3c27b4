// The measured deviation of an export mesh from the exact faces it was made
// from (convert_writers.h): every vertex and every triangle's centroid
// projected onto its own trimmed face.
#include <algorithm>
#include <cmath>

#include <BRepBuilderAPI_MakeVertex.hxx>
#include <BRepExtrema_DistShapeShape.hxx>
#include <BRepTopAdaptor_FClass2d.hxx>
#include <BRep_Tool.hxx>
#include <Extrema_GenLocateExtPS.hxx>
#include <Extrema_POnSurf.hxx>
#include <GeomAdaptor_Surface.hxx>
#include <Geom_Surface.hxx>
#include <Poly_Triangulation.hxx>
#include <Precision.hxx>
#include <Standard_Failure.hxx>
#include <TopExp.hxx>
#include <TopLoc_Location.hxx>
#include <TopTools_IndexedMapOfShape.hxx>
#include <TopoDS.hxx>

#include "importer/convert/convert_writers.h"

namespace nurbsrt::occt {
namespace {

// The distance from `p` to the trimmed `face` where the surface's closest
// point lies outside the trim: to the face's boundary, by OCCT's extrema.
double distance_to_trimmed_face(const gp_Pnt& p, const TopoDS_Face& face) {
    BRepExtrema_DistShapeShape d(BRepBuilderAPI_MakeVertex(p).Vertex(), face);
    return d.IsDone() && d.NbSolution() > 0 ? d.Value() : -1.0;
}

}  // namespace

std::vector<double> face_mesh_deviations(const TopoDS_Face& face, long long& outside_trim) {
    std::vector<double> out;
    TopLoc_Location loc;
    const Handle(Poly_Triangulation) t = BRep_Tool::Triangulation(face, loc);
    if (t.IsNull() || !t->HasUVNodes()) return out;
    const gp_Trsf placement = loc.Transformation();
    // The surface placed as the face is (BRep_Tool::Surface applies the face's location).
    const Handle(Geom_Surface) surface = BRep_Tool::Surface(face);
    if (surface.IsNull()) return out;
    const GeomAdaptor_Surface adaptor(surface);
    const BRepTopAdaptor_FClass2d trim(face, Precision::PConfusion());
    // Vertices: BRepMesh puts the inner ones on the surface at their own (u, v);
    // those of the boundary on the edges' 3D curves, which are the face too but
    // lie off the surface by up to the edge tolerance: those are measured to
    // the trimmed face, boundary included.
    for (int i = 1; i <= t->NbNodes(); ++i) {
        const gp_Pnt2d uv = t->UVNode(i);
        const gp_Pnt p = t->Node(i).Transformed(placement);
        double d = p.Distance(surface->Value(uv.X(), uv.Y()));
        if (d > Precision::Confusion()) {
            const double to_face = distance_to_trimmed_face(p, face);
            if (to_face >= 0) d = std::min(d, to_face);
        }
        out.push_back(d);
    }
    // Centroids: Newton from the triangle's (u, v) centroid to the closest
    // point of the surface; where that is trimmed away, the face's boundary.
    Extrema_GenLocateExtPS project(adaptor);
    for (int k = 1; k <= t->NbTriangles(); ++k) {
        int n[3];
        t->Triangle(k).Get(n[0], n[1], n[2]);
        gp_XYZ p(0, 0, 0);
        gp_XY uv(0, 0);
        for (int c : n) {
            p += t->Node(c).Transformed(placement).XYZ();
            uv += t->UVNode(c).XY();
        }
        const gp_Pnt centroid(p / 3);
        uv /= 3;
        double d = -1;
        try {
            project.Perform(centroid, uv.X(), uv.Y(), /*isDistanceCriteria=*/Standard_True);
            if (project.IsDone()) {
                double u = 0, v = 0;
                project.Point().Parameter(u, v);
                if (trim.Perform(gp_Pnt2d(u, v)) != TopAbs_OUT) d = std::sqrt(project.SquareDistance());
            }
        } catch (const Standard_Failure&) {
            d = -1;  // left to the boundary search below
        }
        if (d < 0) {
            ++outside_trim;
            d = distance_to_trimmed_face(centroid, face);
        }
        if (d >= 0) out.push_back(d);
    }
    return out;
}

nlohmann::ordered_json mesh_deviation_json(const TopoDS_Shape& meshed, double diagonal) {
    TopTools_IndexedMapOfShape faces;
    TopExp::MapShapes(meshed, TopAbs_FACE, faces);
    // A face's instances share its triangulation (on the TFace) and are placed
    // rigidly: its deviation is the same in each, so each distinct face (the
    // face unplaced) is measured once.
    TopTools_IndexedMapOfShape distinct;
    for (int i = 1; i <= faces.Extent(); ++i) distinct.Add(faces(i).Located(TopLoc_Location()));
    std::vector<double> all;
    long long outside = 0;
    for (int i = 1; i <= distinct.Extent(); ++i) {
        std::vector<double> d = face_mesh_deviations(TopoDS::Face(distinct(i)), outside);
        all.insert(all.end(), d.begin(), d.end());
    }
    if (all.empty()) return nullptr;
    double sum = 0;
    for (double d : all) sum += d;
    const size_t p99 = std::min(all.size() - 1, static_cast<size_t>(std::ceil(0.99 * all.size())) - 1);
    std::nth_element(all.begin(), all.begin() + static_cast<std::ptrdiff_t>(p99), all.end());
    const double at_p99 = all[p99];
    const double max = *std::max_element(all.begin(), all.end());
    const double mean = sum / static_cast<double>(all.size());
    auto rel = [&](double x) { return diagonal > 0 ? x / diagonal : 0.0; };
    return {{"distinct_faces", distinct.Extent()},
            {"face_instances", faces.Extent()},
            {"points", all.size()},
            {"centroids_projected_to_the_boundary", outside},
            {"max", max},
            {"p99", at_p99},
            {"mean", mean},
            {"relative_to_diagonal", {{"max", rel(max)}, {"p99", rel(at_p99)}, {"mean", rel(mean)}}}};
}

}  // namespace nurbsrt::occt
