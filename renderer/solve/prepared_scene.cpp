// prepare(): the camera-independent part of a frame (see prepared_scene.h).
#include "renderer/prepared_scene.h"
#include "renderer/solve/prepared_data.h"

#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <thread>

#include "core/check.h"
#include "core/error.h"

namespace nurbsrt {

namespace {

// Seam test tolerance, relative to the scene's diagonal: far below a pixel, far
// above the rounding of a closed surface's two edge curves (they coincide to
// ~1e-15 when converted from a periodic surface; files' own closed B-splines to
// their tolerance).
constexpr double kSeamRelativeTolerance = 1e-7;
// Each of two faces' sampled loops lies within its tolerance of the shared edge,
// so a sliver point is within about twice it of either polyline.
constexpr double kTrimBandPerTolerance = 2.0;
// Faces built without a tolerance get a rounding-level band, relative to the
// diagonal of their parameter box.
constexpr double kMinTrimBandRelative = 1e-9;

// Adjacency grid cell, relative to the scene's diagonal. BRepMesh puts a node on
// every topological vertex, so faces that share an edge or a vertex have map-mesh
// nodes at the same point (bitwise, when the file shares the vertex; within the
// edge tolerance, up to ~1e-4 of the model, when it does not, as IGES trimmed
// surfaces). A cell 10x that tolerance catches both; a false neighbour (two
// faces' nodes merely close) only costs a few extra solves where one is tried.
constexpr double kAdjacencyCellRelative = 1e-3;

// A face is planar when its control points lie within this fraction of the net's
// extent of one plane: CAD planes converted to B-splines are planar to rounding
// (~1e-15); a face curved enough to shadow itself deviates by far more.
constexpr double kPlanarRelative = 1e-9;

std::atomic<uint64_t> next_prepared_id{1};

PreparedFace prepare_face(const Face& f, double seam_tol) {
    PreparedFace pf;
    pf.trim = TrimTester(f.loops);
    pf.spans = make_surface_spans(f.surface);
    pf.box = face_uv_box(f.surface, f.u_min, f.u_max, f.v_min, f.v_max, seam_tol);
    const double diag = std::hypot(f.u_max - f.u_min, f.v_max - f.v_min);
    pf.near_uv = std::max(kTrimBandPerTolerance * f.trim_tolerance_uv, kMinTrimBandRelative * diag);
    pf.trim_uv = pf.near_uv / kTrimBandPerTolerance;
    pf.planar = planar_control_net(f.surface, kPlanarRelative);
    for (const Vec3& p : f.mesh.xyz)
        if (std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z)) pf.mesh_box.extend(p);
    return pf;
}

MapMesh merge_map_meshes(const Scene& scene) {
    MapMesh m;
    size_t nv = 0, ni = 0;
    for (const Face& f : scene.faces) {
        nv += std::min(f.mesh.xyz.size(), f.mesh.uv.size());
        ni += f.mesh.triangles.size();
    }
    m.xyz.reserve(nv);
    m.uv.reserve(2 * nv);
    m.face.reserve(nv);
    m.indices.reserve(ni);
    for (const Face& f : scene.faces) {
        const uint32_t base = static_cast<uint32_t>(m.xyz.size());
        const size_t n = std::min(f.mesh.xyz.size(), f.mesh.uv.size());
        for (size_t k = 0; k < n; ++k) {
            m.xyz.push_back(f.mesh.xyz[k]);
            m.uv.push_back(static_cast<float>(f.mesh.uv[k].x));
            m.uv.push_back(static_cast<float>(f.mesh.uv[k].y));
            m.face.push_back(f.index);
        }
        for (size_t k = 0; k + 2 < f.mesh.triangles.size(); k += 3) {
            const uint32_t a = f.mesh.triangles[k], b = f.mesh.triangles[k + 1], c = f.mesh.triangles[k + 2];
            if (a >= n || b >= n || c >= n) continue;  // malformed triangle: skip
            m.indices.insert(m.indices.end(), {base + a, base + b, base + c});
        }
    }
    return m;
}

// PreparedFace::adjacent: faces with map-mesh nodes in one cell of a grid of
// kAdjacencyCellRelative x diag. One cell per node (no neighbouring cells):
// coincident nodes always share it, and an edge has a node at each end, so a
// pair split by a cell border at one end is still found at the other. The
// (cell, face) pairs are sorted rather than hashed into per-cell lists: no
// allocation per cell, which dominated prepare() on scenes of many faces.
void link_adjacent_faces(const Scene& scene, std::vector<PreparedFace>& faces) {
    struct Node {
        int64_t x, y, z;
        uint32_t face;
        bool operator<(const Node& o) const {
            return x != o.x ? x < o.x : y != o.y ? y < o.y : z != o.z ? z < o.z : face < o.face;
        }
        bool same_cell(const Node& o) const { return x == o.x && y == o.y && z == o.z; }
    };
    const double inv = 1.0 / (kAdjacencyCellRelative * std::max(scene.bbox.diagonal(), 1e-300));
    std::vector<Node> nodes;
    size_t total = 0;
    for (const Face& f : scene.faces) total += f.mesh.xyz.size();
    nodes.reserve(total);
    for (const Face& f : scene.faces)
        for (const Vec3& p : f.mesh.xyz) {
            if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) continue;
            nodes.push_back({static_cast<int64_t>(std::floor(p.x * inv)), static_cast<int64_t>(std::floor(p.y * inv)),
                             static_cast<int64_t>(std::floor(p.z * inv)), f.index});
        }
    tbb::parallel_sort(nodes.begin(), nodes.end());
    std::vector<uint32_t> ids;
    for (size_t a = 0; a < nodes.size();) {
        size_t b = a;
        ids.clear();
        for (; b < nodes.size() && nodes[b].same_cell(nodes[a]); ++b)
            if (ids.empty() || ids.back() != nodes[b].face) ids.push_back(nodes[b].face);
        for (const uint32_t f : ids)
            for (const uint32_t g : ids)
                if (f != g) faces[f - 1].adjacent.push_back(g);
        a = b;
    }
    for (PreparedFace& pf : faces) {
        std::sort(pf.adjacent.begin(), pf.adjacent.end());
        pf.adjacent.erase(std::unique(pf.adjacent.begin(), pf.adjacent.end()), pf.adjacent.end());
    }
}

// Power-form patches of a whole scene: at most this many coefficients (64 MB).
// They hold up to (p+1)(q+1) coefficients per knot-span pair where the control
// points hold about one, so a large upload of dense bicubic faces could
// multiply its memory by ~16 (typical CAD models stay far below: about 10x
// their control points). Beyond the budget the largest faces keep only the
// basis tables, which give the same hits to rounding, more slowly.
constexpr size_t kMaxScenePatchCoefficients = size_t(1) << 21;

// Which faces get power-form patches: all, unless their coefficients exceed
// kMaxScenePatchCoefficients; then all but the largest (decided before any is
// made, so a large upload never holds them all at once).
std::vector<uint8_t> faces_with_patches(const Scene& scene, const std::vector<PreparedFace>& faces) {
    std::vector<size_t> size(faces.size());
    size_t total = 0;
    for (size_t k = 0; k < faces.size(); ++k) {
        size[k] = patch_coefficients(scene.faces[k].surface, faces[k].spans);
        total += size[k];
    }
    std::vector<uint8_t> with(faces.size(), 1);
    if (total <= kMaxScenePatchCoefficients) return with;
    std::vector<size_t> order(faces.size());
    for (size_t k = 0; k < order.size(); ++k) order[k] = k;
    std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) { return size[a] > size[b]; });
    for (const size_t k : order) {
        if (total <= kMaxScenePatchCoefficients) break;
        total -= size[k];
        with[k] = 0;
    }
    return with;
}

// What the preliminary map draws from without bounds checks (a GL draw call
// reads indices and attributes as given): every array per vertex, every index
// a vertex, every face id a face.
void check_map_mesh(const MapMesh& map, size_t faces) {
    NURBSRT_CHECK(map.uv.size() == 2 * map.xyz.size() && map.face.size() == map.xyz.size());
    NURBSRT_CHECK(map.indices.size() % 3 == 0);
    for (uint32_t i : map.indices) NURBSRT_CHECK(i < map.xyz.size());
    for (uint32_t f : map.face) NURBSRT_CHECK(f >= 1 && f <= faces);
}

}  // namespace

PreparedScene::PreparedScene() : data_(std::make_unique<PreparedData>()) {}
PreparedScene::PreparedScene(PreparedScene&&) noexcept = default;
PreparedScene& PreparedScene::operator=(PreparedScene&&) noexcept = default;
PreparedScene::~PreparedScene() = default;

struct PreparedSceneBuilder {
    static PreparedScene build(const Scene& scene, std::shared_ptr<const Scene> owner, int threads) {
        const auto t0 = std::chrono::steady_clock::now();
        for (size_t k = 0; k < scene.faces.size(); ++k)
            if (scene.faces[k].index != k + 1)
                throw Error(ErrorCode::invalid_argument, "scene: faces[i].index must be i + 1");
        PreparedScene ps;
        ps.scene_ = &scene;
        ps.owner_ = std::move(owner);
        ps.id_ = next_prepared_id.fetch_add(1, std::memory_order_relaxed);
        ps.data_->faces.resize(scene.faces.size());
        const double seam_tol = kSeamRelativeTolerance * std::max(scene.bbox.diagonal(), 1e-300);
        const int n = threads > 0 ? threads : static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
        tbb::task_arena arena(n);
        arena.execute([&] {
            tbb::parallel_for(size_t(0), scene.faces.size(),
                              [&](size_t k) { ps.data_->faces[k] = prepare_face(scene.faces[k], seam_tol); });
        });
        const std::vector<uint8_t> with_patches = faces_with_patches(scene, ps.data_->faces);
        arena.execute([&] {
            tbb::parallel_for(size_t(0), scene.faces.size(), [&](size_t k) {
                PreparedFace& pf = ps.data_->faces[k];
                if (with_patches[k]) pf.patches = make_surface_patches(scene.faces[k].surface, pf.spans);
            });
        });
        arena.execute([&] { link_adjacent_faces(scene, ps.data_->faces); });
        ps.data_->map = merge_map_meshes(scene);
        check_map_mesh(ps.data_->map, scene.faces.size());
        ps.prepare_ms_ = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
        return ps;
    }
};

size_t PreparedScene::memory_bytes() const {
    size_t n = sizeof(PreparedScene) + sizeof(PreparedData) + data_->faces.capacity() * sizeof(PreparedFace);
    for (const PreparedFace& f : data_->faces)
        n += f.trim.memory_bytes() + f.adjacent.capacity() * sizeof(uint32_t) + f.spans.u.memory_bytes() +
             f.spans.v.memory_bytes() + f.patches.memory_bytes();
    n += data_->map.xyz.capacity() * sizeof(Vec3) + data_->map.uv.capacity() * sizeof(float) +
         data_->map.face.capacity() * sizeof(uint32_t) + data_->map.indices.capacity() * sizeof(uint32_t);
    return n;
}

PreparedScene prepare(const Scene& scene, int threads) { return PreparedSceneBuilder::build(scene, nullptr, threads); }

PreparedScene prepare(std::shared_ptr<const Scene> scene, int threads) {
    if (!scene) throw Error(ErrorCode::invalid_argument, "prepare: no scene");
    const Scene& s = *scene;
    return PreparedSceneBuilder::build(s, std::move(scene), threads);
}

}  // namespace nurbsrt
