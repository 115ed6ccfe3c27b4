// Trim loops: every wire of a converted face as closed (u,v) polylines sampled
// from the edges' pcurves, and the even-odd test over them.
#include <algorithm>
#include <cmath>
#include <cstdio>

#include <BRepTools.hxx>
#include <BRep_Tool.hxx>
#include <Geom2dAdaptor_Curve.hxx>
#include <Geom2d_BSplineCurve.hxx>
#include <Geom2d_Curve.hxx>
#include <Precision.hxx>
#include <TopExp_Explorer.hxx>
#include <TopoDS.hxx>
#include <TopoDS_Edge.hxx>
#include <TopoDS_Iterator.hxx>
#include <TopoDS_Wire.hxx>
#include <gp_Pnt2d.hxx>

#include "importer/internal.h"

namespace nurbsrt::occt {
namespace {

constexpr int kMaxDepth = 18;  // 2^18 pieces per initial interval at most
constexpr size_t kMaxPointsPerEdge = 200000;

double dist_to_chord(Vec2 p, Vec2 a, Vec2 b) {
    const Vec2 ab = b - a, ap = p - a;
    const double len2 = ab.x * ab.x + ab.y * ab.y;
    if (len2 <= 0) return std::hypot(ap.x, ap.y);
    const double t = std::clamp((ap.x * ab.x + ap.y * ab.y) / len2, 0.0, 1.0);
    return std::hypot(ap.x - t * ab.x, ap.y - t * ab.y);
}

// A pcurve evaluated in the surface's (u,v): sampling after the map keeps the
// chord tolerance in the parameters the trim test uses.
struct MappedCurve {
    const Geom2dAdaptor_Curve& c;
    const UVMap& map;
};

Vec2 at(const MappedCurve& m, double t) {
    const gp_Pnt2d p = m.c.Value(t);
    return m.map.to_surface({p.X(), p.Y()});  // the identity leaves it as it is
}

// Appends points of (t0, t1] so that the chord of every piece deviates from the
// curve by at most `tol`. The deviation is probed at 1/4, 1/2, 3/4 of each piece,
// which catches S-shaped pieces whose midpoint happens to lie on the chord.
// `mid`: the point at the middle of (t0, t1] when known (a halved piece's quarter
// point is its half's middle: passed down, not evaluated again).
void refine(const MappedCurve& c, double t0, Vec2 p0, double t1, Vec2 p1, double tol, int depth, std::vector<Vec2>& out,
            const Vec2* mid = nullptr) {
    if (depth < kMaxDepth && out.size() < kMaxPointsPerEdge) {
        const double tm = 0.5 * (t0 + t1);
        const Vec2 pm = mid ? *mid : at(c, tm);
        const Vec2 q0 = at(c, 0.5 * (t0 + tm)), q1 = at(c, 0.5 * (tm + t1));
        const double err = std::max({dist_to_chord(pm, p0, p1), dist_to_chord(q0, p0, p1), dist_to_chord(q1, p0, p1)});
        if (err > tol) {
            refine(c, t0, p0, tm, pm, tol, depth + 1, out, &q0);
            refine(c, tm, pm, t1, p1, tol, depth + 1, out, &q1);
            return;
        }
    }
    out.push_back(p1);
}

// Initial pieces: one for a line, the polynomial spans of a B-spline (twice,
// so that a single span's curvature is seen), a handful otherwise.
int initial_pieces(const Geom2dAdaptor_Curve& c) {
    switch (c.GetType()) {
        case GeomAbs_Line:
            return 1;
        case GeomAbs_BSplineCurve:
        case GeomAbs_BezierCurve:
            return std::clamp(2 * c.NbIntervals(GeomAbs_C2), 4, 4096);
        default:
            return 8;
    }
}

std::vector<Vec2> sample_pcurve(const Handle(Geom2d_Curve) & pc, double f, double l, double tol, const UVMap& map) {
    const Geom2dAdaptor_Curve curve(pc, f, l);
    const MappedCurve c{curve, map};
    const int n = initial_pieces(curve);
    std::vector<Vec2> pts{at(c, f)};
    double t_prev = f;
    Vec2 p_prev = pts.front();
    for (int k = 1; k <= n; ++k) {
        const double t = k == n ? l : f + (l - f) * k / n;
        const Vec2 p = at(c, t);
        refine(c, t_prev, p_prev, t, p, tol, 0, pts);
        t_prev = t;
        p_prev = p;
    }
    return pts;
}

double dist(Vec2 a, Vec2 b) { return std::hypot(a.x - b.x, a.y - b.y); }

// Orders the wire's edge polylines into closed loops by nearest endpoints.
// Wires are normally stored in order, which this reproduces; it also copes
// with wires whose edges are stored out of order or that hold two loops.
// Consecutive pieces that do not quite meet are joined by a straight segment
// (the gap), whose largest size is reported.
std::vector<std::vector<Vec2>> chain(std::vector<std::vector<Vec2>> pieces, double& max_gap) {
    std::vector<std::vector<Vec2>> loops;
    std::vector<bool> used(pieces.size(), false);
    size_t remaining = pieces.size();
    while (remaining > 0) {
        size_t first = 0;
        while (used[first]) ++first;
        used[first] = true;
        --remaining;
        std::vector<Vec2> loop = std::move(pieces[first]);
        while (remaining > 0) {
            const Vec2 end = loop.back();
            size_t best = pieces.size();
            bool best_reversed = false;
            double best_d = HUGE_VAL;
            for (size_t k = 0; k < pieces.size(); ++k) {
                if (used[k]) continue;
                const double d_fwd = dist(end, pieces[k].front());
                // A reversed match must be clearly better: edge orientation is
                // normally right, and a closed edge matches both ways.
                const double d_rev = dist(end, pieces[k].back());
                if (d_fwd < best_d) {
                    best_d = d_fwd;
                    best = k;
                    best_reversed = false;
                }
                if (d_rev < 0.5 * best_d && d_rev < 0.5 * d_fwd) {
                    best_d = d_rev;
                    best = k;
                    best_reversed = true;
                }
            }
            // Close this loop when its start is nearer than any remaining piece.
            if (dist(end, loop.front()) < best_d && loop.size() > 2) break;
            used[best] = true;
            --remaining;
            std::vector<Vec2>& p = pieces[best];
            if (best_reversed) std::reverse(p.begin(), p.end());
            max_gap = std::max(max_gap, best_d);
            loop.insert(loop.end(), p.begin(), p.end());
        }
        max_gap = std::max(max_gap, dist(loop.back(), loop.front()));
        loops.push_back(std::move(loop));
    }
    return loops;
}

// Removes repeated points and the closing duplicate (TrimLoop implies it).
std::vector<Vec2> clean(const std::vector<Vec2>& in, double eps) {
    std::vector<Vec2> out;
    out.reserve(in.size());
    for (const Vec2& p : in)
        if (out.empty() || dist(out.back(), p) > eps) out.push_back(p);
    while (out.size() > 1 && dist(out.back(), out.front()) <= eps) out.pop_back();
    return out;
}

// Typical speed of the surface, |dS| per unit (u,v), to turn 3D edge
// tolerances into uv ones: the median over a grid of min(|Su|,|Sv|), so that
// degenerate poles (speed 0) do not dominate.
double typical_speed(const Geom_BSplineSurface& s, const UVBox& b) {
    std::vector<double> speeds;
    constexpr int n = 5;
    for (int i = 0; i < n; ++i) {
        for (int j = 0; j < n; ++j) {
            gp_Pnt p;
            gp_Vec du, dv;
            s.D1(b.u0 + (b.u1 - b.u0) * (i + 0.5) / n, b.v0 + (b.v1 - b.v0) * (j + 0.5) / n, p, du, dv);
            const double sp = std::min(du.Magnitude(), dv.Magnitude());
            if (sp > 0 && std::isfinite(sp)) speeds.push_back(sp);
        }
    }
    if (speeds.empty()) return 0;
    std::nth_element(speeds.begin(), speeds.begin() + speeds.size() / 2, speeds.end());
    return speeds[speeds.size() / 2];
}

}  // namespace

TrimResult sample_trim_loops(const ConvertedFace& cf, const UVBox& box, double relative_tolerance) {
    TrimResult r;
    const double diag = box.diagonal();
    const double tol = std::max(relative_tolerance * diag, 1e-12);
    // Forward face: edge orientations inside its wires are then the stored
    // ones, which is what selects the right pcurve of a seam edge.
    const TopoDS_Face face = TopoDS::Face(cf.face.Oriented(TopAbs_FORWARD));
    const TopoDS_Wire outer = BRepTools::OuterWire(face);

    double max_edge_tol = 0, max_gap = 0;
    int missing_pcurves = 0;
    for (TopoDS_Iterator wi(face); wi.More(); wi.Next()) {
        if (wi.Value().ShapeType() != TopAbs_WIRE) continue;
        const TopoDS_Wire& wire = TopoDS::Wire(wi.Value());
        std::vector<std::vector<Vec2>> pieces;
        for (TopoDS_Iterator ei(wire); ei.More(); ei.Next()) {
            if (ei.Value().ShapeType() != TopAbs_EDGE) continue;
            const TopoDS_Edge& e = TopoDS::Edge(ei.Value());
            // INTERNAL/EXTERNAL edges do not bound the face.
            if (e.Orientation() != TopAbs_FORWARD && e.Orientation() != TopAbs_REVERSED) continue;
            max_edge_tol = std::max(max_edge_tol, BRep_Tool::Tolerance(e));
            double f = 0, l = 0;
            const Handle(Geom2d_Curve) pc = BRep_Tool::CurveOnSurface(e, face, f, l);
            if (pc.IsNull() || Precision::IsInfinite(f) || Precision::IsInfinite(l) || !(l > f)) {
                ++missing_pcurves;
                continue;
            }
            std::vector<Vec2> pts = sample_pcurve(pc, f, l, tol, cf.map);
            if (e.Orientation() == TopAbs_REVERSED) std::reverse(pts.begin(), pts.end());
            pieces.push_back(std::move(pts));
        }
        if (pieces.empty()) continue;
        const bool is_outer = !outer.IsNull() && wire.IsSame(outer);
        for (auto& loop : chain(std::move(pieces), max_gap)) {
            std::vector<Vec2> pts = clean(loop, 1e-3 * tol);
            if (pts.size() < 3) continue;  // a degenerate loop (a point or a slit) bounds nothing
            r.loops.push_back(TrimLoop{std::move(pts), is_outer});
        }
    }
    if (missing_pcurves > 0)
        r.warnings.push_back(std::to_string(missing_pcurves) +
                             " edge(s) without a usable pcurve skipped in the trim loops");
    if (max_gap > 0.05 * diag) {
        char buf[160];
        std::snprintf(buf, sizeof(buf), "trim loop gap of %.3g in (u,v) (%.1f%% of the box) closed", max_gap,
                      100.0 * max_gap / diag);
        r.warnings.emplace_back(buf);
    }
    // Uncertainty of the trim test: the sampling deviation plus the edges' 3D
    // tolerance seen in (u,v) (edges may lie that far off their pcurves'
    // image, so the true boundary is only known to within it). Capped at 1% of
    // the box so that a tiny-speed surface cannot make the whole face uncertain.
    const double speed = typical_speed(*cf.surface, box);
    const double edge_uv = speed > 0 ? max_edge_tol / speed : 0.0;
    r.tolerance_uv = std::min(tol + edge_uv, std::max(tol, 0.01 * diag));
    return r;
}

bool inside_loops(const std::vector<TrimLoop>& loops, Vec2 p) {
    if (loops.empty()) return true;
    bool inside = false;
    for (const TrimLoop& loop : loops) {
        const auto& pts = loop.points;
        const size_t n = pts.size();
        for (size_t i = 0, j = n - 1; i < n; j = i++) {
            const Vec2 a = pts[i], b = pts[j];
            if ((a.y > p.y) != (b.y > p.y) && p.x < (b.x - a.x) * (p.y - a.y) / (b.y - a.y) + a.x) inside = !inside;
        }
    }
    return inside;
}

}  // namespace nurbsrt::occt
