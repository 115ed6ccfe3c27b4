// The measured deviation of an export mesh from the exact faces it was made
// from (convert_writers.h): every vertex and every triangle's centroid
// projected onto its own trimmed face.
#include <algorithm>
#include <cmath>
#include <deque>
#include <limits>
#include <optional>
#include <vector>

#include <tbb/parallel_for.h>

#include <BRepBuilderAPI_MakeVertex.hxx>
#include <BRepAdaptor_Curve.hxx>
#include <BRepBndLib.hxx>
#include <Bnd_Box.hxx>
#include <Extrema_ExtPC.hxx>
#include <Extrema_LocateExtPC.hxx>
#include <Poly_PolygonOnTriangulation.hxx>
#include <TopExp_Explorer.hxx>
#include <BRepExtrema_ExtPF.hxx>
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
#include <TopoDS_Edge.hxx>
#include <TopoDS_Vertex.hxx>

#include "importer/convert/convert_writers.h"

namespace nurbsrt::occt {
namespace {

// A face's boundary: its edges' 3D curves, each with its box and its vertices.
// The nearest point of a trimmed face is either a foot point of its surface
// inside the trim or a point of this boundary; the boxes leave out the edges
// that cannot come nearer than a distance already found.
class FaceBoundary {
public:
    explicit FaceBoundary(const TopoDS_Face& face) {
        for (TopExp_Explorer e(face, TopAbs_EDGE); e.More(); e.Next()) {
            const TopoDS_Edge& edge = TopoDS::Edge(e.Current());
            if (BRep_Tool::Degenerated(edge)) continue;
            Edge& x = edges_.emplace_back(edge);
            BRepBndLib::Add(edge, x.box, Standard_True);  // the tolerance too: the face lies within it
            TopoDS_Vertex first, last;
            TopExp::Vertices(edge, first, last);
            for (const TopoDS_Vertex& v : {first, last})
                if (!v.IsNull()) x.ends.push_back(BRep_Tool::Pnt(v));
        }
    }

    struct Edge {
        explicit Edge(const TopoDS_Edge& e) : edge(e), curve(e) {}
        TopoDS_Edge edge;
        BRepAdaptor_Curve curve;
        Bnd_Box box;
        std::vector<gp_Pnt> ends;  // its vertices
    };
    const std::deque<Edge>& edges() const { return edges_; }

    // The least of `d` and the distance from `p` to the boundary's points.
    double nearer(const gp_Pnt& p, double d) const {
        for (const Edge& e : edges_) {
            if (box_distance(e.box, p) >= d) continue;
            for (const gp_Pnt& end : e.ends) d = std::min(d, p.Distance(end));
            try {
                const Extrema_ExtPC ext(p, e.curve);
                if (!ext.IsDone()) continue;
                for (int i = 1; i <= ext.NbExt(); ++i) d = std::min(d, std::sqrt(ext.SquareDistance(i)));
            } catch (const Standard_Failure&) {
                // the ends above still bound it
            }
        }
        return d;
    }

private:
    static double box_distance(const Bnd_Box& b, const gp_Pnt& p) {
        if (b.IsVoid()) return 0;
        double lo[3], hi[3];
        b.Get(lo[0], lo[1], lo[2], hi[0], hi[1], hi[2]);
        const double at[3] = {p.X(), p.Y(), p.Z()};
        double sq = 0;
        for (int i = 0; i < 3; ++i) {
            const double out = std::max({lo[i] - at[i], 0.0, at[i] - hi[i]});
            sq += out * out;
        }
        return std::sqrt(sq);
    }
    std::deque<Edge> edges_;  // deque: an adaptor is not to be moved once evaluated
};

// The foot points of a point on the whole surface, kept where they are inside
// the trim (BRepExtrema_ExtPF: the surface sampled on a grid once per face, at
// its initialisation; building that grid per point made the check of a
// 400-face part take seconds).
class FaceInterior {
public:
    explicit FaceInterior(const TopoDS_Face& face) : face_(face) { ext_.Initialize(face, Extrema_ExtFlag_MIN); }

    // The least of `d` and the distance to the feet inside the trim.
    double nearer(const gp_Pnt& p, double d) {
        try {
            ext_.Perform(BRepBuilderAPI_MakeVertex(p).Vertex(), face_);
            if (ext_.IsDone())
                for (int i = 1; i <= ext_.NbExt(); ++i) d = std::min(d, std::sqrt(ext_.SquareDistance(i)));
        } catch (const Standard_Failure&) {}
        return d;
    }

private:
    TopoDS_Face face_;
    BRepExtrema_ExtPF ext_;
};

// Which boundary edge each node of a face's triangulation lies on, and where:
// BRepMesh puts the boundary nodes on the edges' 3D curves and records their
// parameters (Poly_PolygonOnTriangulation), so a boundary node's nearest point
// of the face is found by a local search on its own edge.
class BoundaryNodes {
public:
    BoundaryNodes(const FaceBoundary& boundary, const Handle(Poly_Triangulation) & t, const TopLoc_Location& loc)
        : boundary_(boundary), at_(static_cast<size_t>(t->NbNodes()) + 1) {
        const std::deque<FaceBoundary::Edge>& edges = boundary.edges();
        for (size_t k = 0; k < edges.size(); ++k) {
            const Handle(Poly_PolygonOnTriangulation) polygon =
                BRep_Tool::PolygonOnTriangulation(edges[k].edge, t, loc);
            if (polygon.IsNull() || !polygon->HasParameters()) continue;
            for (int i = 1; i <= polygon->NbNodes(); ++i)
                at_[static_cast<size_t>(polygon->Node(i))] = {static_cast<int>(k), polygon->Parameter(i)};
        }
    }

    // The distance from `p` to node `node`'s edge, by Newton on the curve from
    // the node's parameter; -1 for a node on no edge.
    double distance(int node, const gp_Pnt& p) const {
        const Where& w = at_[static_cast<size_t>(node)];
        if (w.edge < 0) return -1;
        const FaceBoundary::Edge& e = boundary_.edges()[static_cast<size_t>(w.edge)];
        const BRepAdaptor_Curve& c = e.curve;
        // The edge's vertices bound it too: BRepMesh puts an edge's end nodes at
        // its vertices, which lie off the curve by up to their tolerance.
        double d = p.Distance(c.Value(w.parameter));
        for (const gp_Pnt& end : e.ends) d = std::min(d, p.Distance(end));
        if (d <= Precision::Confusion()) return d;
        try {
            const Extrema_LocateExtPC local(p, c, w.parameter, Precision::PConfusion());
            if (local.IsDone()) d = std::min(d, std::sqrt(local.SquareDistance()));
        } catch (const Standard_Failure&) {}
        return d;
    }

private:
    struct Where {
        int edge = -1;  // in boundary_.edges()
        double parameter = 0;
    };
    const FaceBoundary& boundary_;
    std::vector<Where> at_;
};

// A placed face's triangulation and what measuring it needs.
struct MeshedFace {
    const TopoDS_Face& face;
    Handle(Poly_Triangulation) t;
    TopLoc_Location loc;
    gp_Trsf placement;
    Handle(Geom_Surface) surface;  // placed as the face is (BRep_Tool::Surface applies its location)
    std::optional<FaceBoundary> boundary;
    std::optional<BoundaryNodes> nodes;    // on `boundary`'s edges
    std::optional<FaceInterior> interior;  // built at the first point that needs it
    // Per node (1-based, as the triangulation numbers them): placed, and the
    // surface at its (u, v); measured once, read by every triangle around it.
    std::vector<gp_Pnt> xyz, on_surface;

    double nearer_interior(const gp_Pnt& p, double d) {
        if (!interior) interior.emplace(face);
        return interior->nearer(p, d);
    }
};

// Vertices: BRepMesh puts the inner ones on the surface at their own (u, v);
// those of the boundary on the edges' 3D curves, which are the face too but lie
// off the surface by up to the edge tolerance: those are measured to their own
// edge, then to any part of the boundary that could be nearer.
void vertex_deviations(MeshedFace& f, std::vector<double>& out) {
    f.xyz.assign(static_cast<size_t>(f.t->NbNodes()) + 1, gp_Pnt());
    f.on_surface.assign(f.xyz.size(), gp_Pnt());
    for (int i = 1; i <= f.t->NbNodes(); ++i) {
        const gp_Pnt2d uv = f.t->UVNode(i);
        const gp_Pnt p = f.xyz[static_cast<size_t>(i)] = f.t->Node(i).Transformed(f.placement);
        f.on_surface[static_cast<size_t>(i)] = f.surface->Value(uv.X(), uv.Y());
        double d = p.Distance(f.on_surface[static_cast<size_t>(i)]);
        if (d > Precision::Confusion()) {
            const double to_edge = f.nodes->distance(i, p);
            if (to_edge >= 0) d = std::min(d, to_edge);
            if (d > Precision::Confusion()) d = f.boundary->nearer(p, d);
        }
        out.push_back(d);
    }
}

// Centroids: Newton from the triangle's (u, v) centroid to the closest point of
// the surface (minimising the distance; where that stops at the surface's own
// bounds, the root of the normal condition), kept where it is inside the trim;
// then any part of the boundary that could be nearer. Where the foot point is
// trimmed away, the surface's other feet inside the trim and the boundary.
void centroid_deviations(MeshedFace& f, std::vector<double>& out, long long& outside_trim) {
    const GeomAdaptor_Surface adaptor(f.surface);
    const BRepTopAdaptor_FClass2d trim(f.face, Precision::PConfusion());
    Extrema_GenLocateExtPS project(adaptor);
    for (int k = 1; k <= f.t->NbTriangles(); ++k) {
        int n[3];
        f.t->Triangle(k).Get(n[0], n[1], n[2]);
        gp_XYZ p(0, 0, 0);
        gp_XY uv(0, 0);
        for (int c : n) {
            p += f.xyz[static_cast<size_t>(c)].XYZ();
            uv += f.t->UVNode(c).XY();
        }
        const gp_Pnt centroid(p / 3);
        uv /= 3;
        // The nodes' surface points lie on the face (their (u, v) are inside the
        // trim): no closest point is farther. A root beyond that is another
        // sheet's (the normal condition near a pole, say), not this point's.
        double bound = std::numeric_limits<double>::infinity();
        for (int c : n) bound = std::min(bound, centroid.Distance(f.on_surface[static_cast<size_t>(c)]));
        double d = -1;
        try {
            project.Perform(centroid, uv.X(), uv.Y(), /*isDistanceCriteria=*/Standard_True);
            if (!project.IsDone()) project.Perform(centroid, uv.X(), uv.Y(), /*isDistanceCriteria=*/Standard_False);
            if (project.IsDone()) {
                double u = 0, v = 0;
                project.Point().Parameter(u, v);
                const double found = std::sqrt(project.SquareDistance());
                if (found <= bound + Precision::Confusion() && trim.Perform(gp_Pnt2d(u, v)) != TopAbs_OUT) d = found;
            }
        } catch (const Standard_Failure&) {
            d = -1;  // left to the search of the whole face below
        }
        if (d < 0) {
            ++outside_trim;
            d = f.nearer_interior(centroid, bound);
        }
        out.push_back(f.boundary->nearer(centroid, d));
    }
}

}  // namespace

std::vector<double> face_mesh_deviations(const TopoDS_Face& face, long long& outside_trim) {
    std::vector<double> out;
    MeshedFace f{face, {}, {}, {}, {}, {}, {}, {}, {}, {}};
    f.t = BRep_Tool::Triangulation(face, f.loc);
    if (f.t.IsNull() || !f.t->HasUVNodes()) return out;
    f.placement = f.loc.Transformation();
    f.surface = BRep_Tool::Surface(face);
    if (f.surface.IsNull()) return out;
    f.boundary.emplace(face);
    f.nodes.emplace(*f.boundary, f.t, f.loc);
    vertex_deviations(f, out);  // before the centroids: it measures the nodes they read
    centroid_deviations(f, out, outside_trim);
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
    // Faces are measured side by side (each with its own OCCT search
    // structures; the shape is only read) and gathered in face order.
    const size_t n = static_cast<size_t>(distinct.Extent());
    std::vector<std::vector<double>> per_face(n);
    std::vector<long long> outside_of(n, 0);
    tbb::parallel_for(size_t(0), n, [&](size_t i) {
        per_face[i] = face_mesh_deviations(TopoDS::Face(distinct(static_cast<int>(i) + 1)), outside_of[i]);
    });
    std::vector<double> all;
    long long outside = 0;
    for (size_t i = 0; i < n; ++i) {
        all.insert(all.end(), per_face[i].begin(), per_face[i].end());
        outside += outside_of[i];
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
