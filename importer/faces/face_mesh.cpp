// Coarse (u,v) meshes for the preliminary map: BRepMesh per face under a time
// budget, and a trimmed regular grid wherever BRepMesh fails or runs out of time,
// or fills the part of a face it left without triangles.
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdint>

#include <BRepMesh_IncrementalMesh.hxx>
#include <BRep_Tool.hxx>
#include <IMeshTools_Parameters.hxx>
#include <Message_ProgressIndicator.hxx>
#include <Message_ProgressRange.hxx>
#include <Poly_Triangulation.hxx>
#include <Standard_Failure.hxx>
#include <TopLoc_Location.hxx>
#include <tbb/parallel_for.h>

#include "importer/internal.h"

namespace nurbsrt::occt {
namespace {

using Clock = std::chrono::steady_clock;

// BRepMesh polls UserBreak() of the progress indicator between its steps;
// answering "break" past the deadline makes it give up on the face.
class DeadlineIndicator : public Message_ProgressIndicator {
public:
    explicit DeadlineIndicator(Clock::time_point deadline) : deadline_(deadline) {}
    Standard_Boolean UserBreak() override {
        if (Clock::now() > deadline_) broke_ = true;
        return broke_.load();
    }
    void Show(const Message_ProgressScope&, const Standard_Boolean) override {}
    bool broke() const { return broke_.load(); }

private:
    Clock::time_point deadline_;
    std::atomic<bool> broke_{false};
};

}  // namespace

bool mesh_from_triangulation(const ConvertedFace& cf, FaceMesh& out) {
    TopLoc_Location loc;
    const Handle(Poly_Triangulation) tri = BRep_Tool::Triangulation(cf.face, loc);
    if (tri.IsNull() || tri->NbTriangles() == 0 || !tri->HasUVNodes()) return false;
    const gp_Trsf trsf = loc.Transformation();
    const bool moved = !loc.IsIdentity();
    FaceMesh m;
    const int n = tri->NbNodes();
    m.uv.reserve(static_cast<size_t>(n));
    m.xyz.reserve(static_cast<size_t>(n));
    for (int i = 1; i <= n; ++i) {
        const gp_Pnt2d uv = tri->UVNode(i);
        gp_Pnt p = tri->Node(i);
        if (moved) p.Transform(trsf);
        m.uv.push_back(cf.map.to_surface({uv.X(), uv.Y()}));
        m.xyz.push_back({p.X(), p.Y(), p.Z()});
    }
    m.triangles.reserve(3 * static_cast<size_t>(tri->NbTriangles()));
    for (int t = 1; t <= tri->NbTriangles(); ++t) {
        int a, b, c;
        tri->Triangle(t).Get(a, b, c);
        if (a < 1 || b < 1 || c < 1 || a > n || b > n || c > n) return false;
        m.triangles.insert(m.triangles.end(),
                           {static_cast<uint32_t>(a - 1), static_cast<uint32_t>(b - 1), static_cast<uint32_t>(c - 1)});
    }
    out = std::move(m);
    return true;
}

FaceMesh trimmed_grid_mesh(const ConvertedFace& cf, const UVBox& box, const std::vector<TrimLoop>& loops, int cells) {
    FaceMesh m;
    m.fallback_grid = true;
    const int n = cells + 1;
    std::vector<int> index(static_cast<size_t>(n) * n, -1);
    auto uv_of = [&](int i, int j) {
        return Vec2{box.u0 + (box.u1 - box.u0) * i / cells, box.v0 + (box.v1 - box.v0) * j / cells};
    };
    // Only vertices of kept triangles are emitted, so the mesh (and the scene
    // bbox built from it) does not reach into trimmed-away parts.
    auto vertex = [&](int i, int j) -> uint32_t {
        int& idx = index[static_cast<size_t>(i) * n + j];
        if (idx < 0) {
            const Vec2 uv = uv_of(i, j);
            const gp_Pnt p = cf.surface->Value(uv.x, uv.y);
            idx = static_cast<int>(m.uv.size());
            m.uv.push_back(uv);
            m.xyz.push_back({p.X(), p.Y(), p.Z()});
        }
        return static_cast<uint32_t>(idx);
    };
    for (int i = 0; i < cells; ++i) {
        for (int j = 0; j < cells; ++j) {
            const Vec2 a = uv_of(i, j), c = uv_of(i + 1, j + 1);
            const Vec2 b = uv_of(i + 1, j), d = uv_of(i, j + 1);
            if (inside_loops(loops, {(a.x + b.x + c.x) / 3, (a.y + b.y + c.y) / 3}))
                m.triangles.insert(m.triangles.end(), {vertex(i, j), vertex(i + 1, j), vertex(i + 1, j + 1)});
            if (inside_loops(loops, {(a.x + c.x + d.x) / 3, (a.y + c.y + d.y) / 3}))
                m.triangles.insert(m.triangles.end(), {vertex(i, j), vertex(i + 1, j + 1), vertex(i, j + 1)});
        }
    }
    return m;
}

namespace {

// BRepMesh can leave part of a face without triangles while the nodes of its
// boundary are there (e.g. a strip along an edge of a plane), at any deflection and with
// the Watson and the Delabella algorithm alike. The preliminary map then shows
// no pixel of that part, and the rescue and nearer-sheet passes, which look
// for faces through the map's meshes, miss a thin face in front there. Such a
// mesh (nodes that no triangle uses) gets the triangles of a trimmed (u, v)
// grid that lie inside the trim loops and outside all of its triangles, at
// this many times the fallback grid's cells per side: the strips seen were a
// few deflections wide, under one fallback cell.
constexpr int kFillRefinement = 4;

bool has_unused_nodes(const FaceMesh& m) {
    std::vector<char> used(m.uv.size(), 0);
    for (const uint32_t t : m.triangles) used[t] = 1;
    return std::find(used.begin(), used.end(), 0) != used.end();
}

size_t fill_untriangulated(const ConvertedFace& cf, const UVBox& box, const std::vector<TrimLoop>& loops, int cells,
                           FaceMesh& m) {
    const double cu = (box.u1 - box.u0) / cells, cv = (box.v1 - box.v0) / cells;
    if (!(cu > 0) || !(cv > 0)) return 0;
    auto cell = [&](double x, double x0, double step) {
        return std::clamp(static_cast<int>(std::floor((x - x0) / step)), 0, cells - 1);
    };
    // The mesh's triangles bucketed by the grid cells their (u, v) boxes overlap.
    std::vector<std::vector<uint32_t>> bucket(static_cast<size_t>(cells) * cells);
    const size_t ntri = m.triangles.size() / 3;
    for (size_t t = 0; t < ntri; ++t) {
        const Vec2 &a = m.uv[m.triangles[3 * t]], &b = m.uv[m.triangles[3 * t + 1]], &c = m.uv[m.triangles[3 * t + 2]];
        const int i0 = cell(std::min({a.x, b.x, c.x}), box.u0, cu), i1 = cell(std::max({a.x, b.x, c.x}), box.u0, cu);
        const int j0 = cell(std::min({a.y, b.y, c.y}), box.v0, cv), j1 = cell(std::max({a.y, b.y, c.y}), box.v0, cv);
        for (int i = i0; i <= i1; ++i)
            for (int j = j0; j <= j1; ++j)
                bucket[static_cast<size_t>(i) * cells + j].push_back(static_cast<uint32_t>(t));
    }
    auto covered = [&](Vec2 p) {
        for (const uint32_t t : bucket[static_cast<size_t>(cell(p.x, box.u0, cu)) * cells + cell(p.y, box.v0, cv)]) {
            const Vec2 &a = m.uv[m.triangles[3 * t]], &b = m.uv[m.triangles[3 * t + 1]],
                       &c = m.uv[m.triangles[3 * t + 2]];
            const double d0 = (b.x - a.x) * (p.y - a.y) - (b.y - a.y) * (p.x - a.x);
            const double d1 = (c.x - b.x) * (p.y - b.y) - (c.y - b.y) * (p.x - b.x);
            const double d2 = (a.x - c.x) * (p.y - c.y) - (a.y - c.y) * (p.x - c.x);
            if ((d0 >= 0 && d1 >= 0 && d2 >= 0) || (d0 <= 0 && d1 <= 0 && d2 <= 0)) return true;
        }
        return false;
    };
    const FaceMesh grid = trimmed_grid_mesh(cf, box, loops, cells);
    std::vector<int64_t> index(grid.uv.size(), -1);
    size_t added = 0;
    for (size_t t = 0; t + 2 < grid.triangles.size(); t += 3) {
        const uint32_t* g = &grid.triangles[t];
        const Vec2 centroid{(grid.uv[g[0]].x + grid.uv[g[1]].x + grid.uv[g[2]].x) / 3,
                            (grid.uv[g[0]].y + grid.uv[g[1]].y + grid.uv[g[2]].y) / 3};
        if (covered(centroid)) continue;
        for (int k = 0; k < 3; ++k) {
            if (index[g[k]] < 0) {
                index[g[k]] = static_cast<int64_t>(m.uv.size());
                m.uv.push_back(grid.uv[g[k]]);
                m.xyz.push_back(grid.xyz[g[k]]);
            }
            m.triangles.push_back(static_cast<uint32_t>(index[g[k]]));
        }
        ++added;
    }
    return added;
}

}  // namespace

void mesh_faces(const std::vector<ConvertedFace>& faces, const std::vector<UVBox>& boxes,
                const std::vector<const std::vector<TrimLoop>*>& loops, const std::vector<double>& face_sizes,
                const std::vector<uint32_t>& numbers, const MeshParams& p, std::vector<FaceMesh>& meshes,
                std::vector<std::string>& warnings) {
    const size_t n = faces.size();
    meshes.assign(n, FaceMesh{});
    const Clock::time_point start = Clock::now();
    const auto budget =
        std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(std::max(0.0, p.time_limit_s)));
    const Clock::time_point deadline = start + budget;
    // One face may not eat the whole budget (BRepMesh may never finish one
    // face), so the others still get their real meshes.
    const auto face_budget =
        std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(std::max(0.0, p.face_time_limit_s)));
    enum Outcome : char { ok, failed, timed_out, skipped };
    std::vector<char> outcome(n, ok);
    std::vector<std::string> errors(n);
    std::vector<size_t> filled(n, 0);

    tbb::parallel_for(size_t(0), n, [&](size_t i) {
        if (faces[i].face.IsNull() || faces[i].surface.IsNull()) {
            outcome[i] = failed;
            return;
        }
        const Clock::time_point now = Clock::now();
        if (now >= deadline) {
            outcome[i] = skipped;
            return;
        }
        Handle(DeadlineIndicator) indicator = new DeadlineIndicator(std::min(deadline, now + face_budget));
        // A deflection larger than the face itself (a small hole in a very
        // large model) polygonizes its edges into self-intersecting wires and
        // BRepMesh gives up; so the deflection is capped by the face's size,
        // and a failed face gets one finer retry.
        double deflection = p.deflection;
        if (i < face_sizes.size() && face_sizes[i] > 0) deflection = std::min(deflection, 0.1 * face_sizes[i]);
        try {
            for (int attempt = 0; attempt < 2; ++attempt) {
                IMeshTools_Parameters params;
                params.Deflection = deflection;
                params.Angle = p.angle;
                params.InParallel = Standard_False;  // we parallelize over faces ourselves
                BRepMesh_IncrementalMesh mesher(faces[i].face, params, indicator->Start());
                if (indicator->broke()) {
                    outcome[i] = timed_out;
                    break;
                }
                if (mesh_from_triangulation(faces[i], meshes[i])) {
                    outcome[i] = ok;
                    if (has_unused_nodes(meshes[i]))
                        filled[i] = fill_untriangulated(faces[i], boxes[i], *loops[i], kFillRefinement * p.grid_cells,
                                                        meshes[i]);
                    break;
                }
                outcome[i] = failed;
                deflection *= 0.2;
            }
        } catch (const Standard_Failure& f) {
            outcome[i] = failed;
            errors[i] = failure_text(f);
        }
    });

    for (size_t i = 0; i < n; ++i) {
        const std::string face = "face " + std::to_string(numbers[i]);
        if (filled[i])
            warnings.push_back(face + ": BRepMesh left part of it without triangles; " + std::to_string(filled[i]) +
                               " triangles of a trimmed (u,v) grid fill it");
        if (outcome[i] == ok) continue;
        switch (outcome[i]) {
            case failed:
                warnings.push_back(face + ": BRepMesh gave no triangulation" +
                                   (errors[i].empty() ? "" : " (" + errors[i] + ")") + "; using a trimmed (u,v) grid");
                break;
            case timed_out:
                warnings.push_back(face + ": BRepMesh ran out of time; using a trimmed (u,v) grid");
                break;
            default:
                warnings.push_back(face + ": mesh time limit reached before meshing; using a trimmed (u,v) grid");
                break;
        }
        if (faces[i].surface.IsNull()) continue;
        try {
            meshes[i] = trimmed_grid_mesh(faces[i], boxes[i], *loops[i], p.grid_cells);
        } catch (const Standard_Failure& f) {
            warnings.push_back(face + ": trimmed grid failed too (" + failure_text(f) + ")");
        }
    }
}

}  // namespace nurbsrt::occt
