// The rescue of pixels without a primary hit. Reads only the map and the hits of
// the previous state, so every pixel's result is independent of the thread count.
//  A (neighbour / silhouette): the faces of the 8 neighbours, started from their
//    converged (u, v) (their hits), then from their map (u, v); the pixel's own map
//    face is retried from the neighbours' converged (u, v). Pixels the map calls
//    background are tried the same way when they touch a hit: the exact silhouette
//    is not the mesh's.
//  B (general): if A found nothing and the pixel should be covered (its map face
//    failed, or at least two 4-neighbours are hit), every face of the 5x5
//    neighbourhood from several starts: the converged (u, v) of its pixels, its
//    map (u, v), the face's mesh point and vertex nearest to the pixel, and the
//    middle of the face's parameter box (on an open silhouette, or in a gap
//    between separate parts, only the nearest of the first two kinds).
//  C (adjacent): if B found nothing either and the pixel is enclosed (its map
//    face failed, or hits on opposite sides within two pixels), the faces that
//    touch B's faces (shared vertices of their meshes, PreparedFace::adjacent),
//    nearest on screen first, from their mesh point and vertex nearest to the
//    pixel and their box middle: a face too thin for the map to show lies between
//    the faces it touches.
//  D (any face near on screen): if C found nothing either and the pixel has hits
//    on opposite sides within two pixels, the faces whose mesh comes within reach
//    of it on screen, whatever they touch: a face seen through a gap between
//    faces that do not meet it, which the map hides behind them.
//  Crack pixels (hit on opposite sides, or on 3 of 4 sides) also accept a hit
//    just outside a trim loop, within the face's tolerance band (Solver::solve).
// All rescue solves use the robust Newton (newton.h); the nearest hit wins.
// Then silhouette growth repeats the rescue next to the pixels it filled.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <memory>
#include <mutex>
#include <utility>
#include <vector>

#include "renderer/frame/mesh_screen_points.h"
#include "renderer/passes/passes.h"

namespace nurbsrt {

namespace {

// Starts per face that no pixel near the rescued one shows (far_starts): the
// nearest point of its mesh on screen, its nearest mesh vertex, its box middle.
constexpr int kFarStartsPerFace = 3;
// C's faces: the adjacent faces of B's; a thin face between the neighbourhood's
// faces touches at least one of them. 12 faces' far starts stay within the start
// budget after A's and B's usual few. Only those whose mesh comes within 8
// pixels of the pixel on screen: the face that covers it has its mesh within
// the deflection of its true extent, a pixel or two at most; a face farther
// away cannot close a hole here.
constexpr NearFaceBound kAdjacentFaces{12, 8.0};
// D's faces: any face whose mesh comes within the same reach of an enclosed
// pixel that A, B and C left empty (MeshScreenPoints::faces_near), the nearest
// few on screen: a face seen through a gap between faces that do not touch it
// (unsewn faces of an IGES file), hidden in the map by the faces around.
constexpr NearFaceBound kScreenFaces{4, kAdjacentFaces.reach_pixels};
// At most this many distinct starts (face, u, v) are solved per rescued pixel. A
// needs at most 8 + 8 + 2 (each neighbour's hit and map start, the own map start
// and one own converged start), B the rest of the first 64, C at most
// kFarStartsPerFace x 12 adjacent faces = 36 more, D 12. It bounds a pixel's cost
// where many small faces meet, and sizes the stack array of tried starts.
constexpr int kMaxStarts = 64 + kFarStartsPerFace * (kAdjacentFaces.max_faces + kScreenFaces.max_faces);
// A's neighbourhood: the 8 pixels around (a hit there is at most a pixel away).
constexpr int kNeighbourRadius = 1;
// B's neighbourhood: 5x5, one ring beyond A's, for the faces a pixel-wide sliver
// of the map (a thin face, a coarse silhouette) hides from the 8 neighbours.
constexpr int kGeneralRadius = 2;
// B's faces: at most one per pixel of its 5x5 neighbourhood besides the pixel
// itself; more distinct faces there are a pathological corner where the start
// budget (kMaxStarts) would run out anyway.
constexpr int kMaxGeneralFaces = 24;
// "No start of this face seen yet": above every squared pixel distance in B's 5x5.
constexpr int kNoStart = 1 << 20;
// Hits on the two sides of a gap of up to 3 pixels within this many pixel
// footprints in depth may be one surface's, or two meeting ones', across a crack:
// a surface sloped up to 2 (63 degrees from facing the eye) over the 4 pixels.
// Separate parts seen one behind the other differ by far more.
constexpr double kCrackDepthFootprints = 8.0;
// Silhouette growth passes: each adds one pixel ring outside the map's
// silhouette; the exact silhouette lies within a few pixels of the mesh's (its
// deflection), so 64 is never reached in practice and only bounds the work.
constexpr int kMaxGrowthPasses = 64;

// The rescue of one pixel (i, j) from the hits `src`: the starts tried so far
// (each distinct start is solved once) and the nearest hits inside the trim and
// within its tolerance band.
class PixelRescue {
public:
    PixelRescue(const FrameContext& c, const Solver& solver, const PixelArray<PixelHit>& src, int i, int j, bool crack)
        : c_(c), solver_(solver), src_(src), i_(i), j_(j), crack_(crack) {}

    // Solves face id from (su, sv) unless tried before; true when it hit (inside
    // the trim or within its tolerance band).
    bool attempt(uint32_t id, float su, float sv) {
        if (id == 0 || id > c_.nfaces) return false;
        for (int q = 0; q < ntried_; ++q)
            if (tried_[q].id == id && tried_[q].u == su && tried_[q].v == sv) return false;
        if (ntried_ == limit_) return false;
        tried_[ntried_++] = {id, su, sv};
        PixelHit h;
        const Outcome o = solver_.solve(id, i_, j_, su, sv, solver_.robust, crack_, h);
        if (o == kConverged && h.t < best.t) best = h;
        if (o == kNearTrim && keep_band_hits && h.t < best_near.t) best_near = h;
        return o == kConverged || o == kNearTrim;
    }
    // A: converged neighbours first (their uv is on the exact surface, next to this
    // pixel), one start per face; then the map faces' starts; then the own map face.
    void neighbour_starts(uint32_t own) {
        const PreliminaryMap& map = c_.map;
        uint32_t faces[2 * 8];  // two faces (hit, map) per neighbour at the most
        int nf = 0;
        for (int pass = 0; pass < 2; ++pass)
            for_each_neighbour(c_, i_, j_, kNeighbourRadius, [&](int ni, int nj) {
                if (ni == i_ && nj == j_) return;
                const size_t n = map.index(ni, nj);
                const uint32_t id = pass == 0 ? src_[n].face : map.face[n];
                if (id == 0 || std::find(faces, faces + nf, id) != faces + nf) return;
                faces[nf++] = id;
                if (pass == 0)
                    attempt(id, src_[n].u, src_[n].v);
                else
                    attempt(id, map.u[n], map.v[n]);
            });
        if (!own) return;
        // The own map start was solved by the primary pass (not robust): retry it robustly.
        const size_t k = map.index(i_, j_);
        attempt(own, map.u[k], map.v[k]);
        for_each_neighbour(c_, i_, j_, kNeighbourRadius, [&](int ni, int nj) {
            const PixelHit& nh = src_[map.index(ni, nj)];
            if (nh.face != own) return true;
            attempt(own, nh.u, nh.v);
            return false;  // one converged start of the own face is enough
        });
    }
    // B: every face of the 5x5 neighbourhood. `thorough` (an enclosed pixel):
    // from each start it offers, then its far starts (mesh point and vertex
    // nearest to the pixel, box middle). Otherwise (an open silhouette, where B
    // runs most and every start of one face fails alike): only the face's
    // converged and map starts nearest to the pixel, and only for faces A has
    // not solved; the other starts, on the same sheet, end where these do, and
    // the far starts there cost a third of the rescue's solves for no hit.
    void general_starts(const MeshScreenPoints& screen_points, bool thorough) {
        const PreliminaryMap& map = c_.map;
        uint32_t faces[kMaxGeneralFaces];
        const int nf = general_faces(faces);
        const ScreenPoint sp = c_.camera.pixel_screen(i_, j_);
        for (int q = 0; q < nf; ++q) {
            const uint32_t id = faces[q];
            if (!thorough && solved(id)) continue;
            if (thorough) {
                for_each_neighbour(c_, i_, j_, kGeneralRadius, [&](int ni, int nj) {
                    const size_t n = map.index(ni, nj);
                    if (src_[n].face == id) attempt(id, src_[n].u, src_[n].v);
                    if (map.face[n] == id) attempt(id, map.u[n], map.v[n]);
                });
            } else {
                size_t hit_n = 0, map_n = 0;
                int hit_d = kNoStart, map_d = kNoStart;
                for_each_neighbour(c_, i_, j_, kGeneralRadius, [&](int ni, int nj) {
                    const size_t n = map.index(ni, nj);
                    const int d = (ni - i_) * (ni - i_) + (nj - j_) * (nj - j_);
                    if (src_[n].face == id && d < hit_d) hit_d = d, hit_n = n;
                    if (map.face[n] == id && d < map_d) map_d = d, map_n = n;
                });
                if (hit_d != kNoStart) attempt(id, src_[hit_n].u, src_[hit_n].v);
                if (map_d != kNoStart) attempt(id, map.u[map_n], map.v[map_n]);
            }
            if (thorough) far_starts(screen_points, id, sp);
        }
    }
    // C: the faces adjacent to those of the 5x5 neighbourhood that are not in it
    // (PreparedFace::adjacent). A face narrower than the map's pixel spacing (a
    // fillet or a blend strip seen edge-on, a sliver between two larger faces) may
    // cover no pixel centre of the map at all, and its mesh may lie a little inside
    // its true extent; the exact ray still hits it, between the faces it touches.
    void adjacent_starts(const MeshScreenPoints& screen_points) {
        uint32_t near[kMaxGeneralFaces];
        const int nn = general_faces(near);
        const ScreenPoint sp = c_.camera.pixel_screen(i_, j_);
        MeshScreenPoints::FarFace faces[kAdjacentFaces.max_faces];
        const int nf = screen_points.adjacent_far_faces(near, nn, sp, faces, kAdjacentFaces);
        limit_ = kMaxStarts - kFarStartsPerFace * kScreenFaces.max_faces;
        for (int q = 0; q < nf; ++q) far_starts(faces[q]);
    }
    // D: any faces whose mesh comes within reach of the pixel on screen, but
    // those solved already.
    void screen_starts(const MeshScreenPoints& screen_points) {
        uint32_t solved_ids[kMaxStarts];
        int ns = 0;
        for (int q = 0; q < ntried_; ++q)
            if (std::find(solved_ids, solved_ids + ns, tried_[q].id) == solved_ids + ns)
                solved_ids[ns++] = tried_[q].id;
        const ScreenPoint sp = c_.camera.pixel_screen(i_, j_);
        MeshScreenPoints::FarFace faces[kScreenFaces.max_faces];
        const int nf = screen_points.faces_near(sp, solved_ids, ns, faces, kScreenFaces);
        limit_ = kMaxStarts;
        for (int q = 0; q < nf; ++q) far_starts(faces[q]);
    }

    // Starts of a face that has no pixel near this one: its mesh's point and
    // vertex nearest to the pixel on screen (in front of the eye), and the middle
    // of its box.
    void far_starts(const MeshScreenPoints& screen_points, uint32_t id, ScreenPoint sp) {
        MeshScreenPoints::FarFace f;
        f.id = id;
        f.nstarts = screen_points.nearest_starts(id, sp, f.starts);
        far_starts(f);
    }

    PixelHit best, best_near;
    // Whether attempt keeps hits within the trim band (kNearTrim) in best_near.
    bool keep_band_hits = true;

private:
    // B's faces: those hit or in the map in the 5x5 neighbourhood, in
    // for_each_neighbour's order, at most kMaxGeneralFaces; returns how many.
    int general_faces(uint32_t (&out)[kMaxGeneralFaces]) const {
        int n = 0;
        for_each_neighbour(c_, i_, j_, kGeneralRadius, [&](int ni, int nj) {
            const size_t k = c_.map.index(ni, nj);
            for (const uint32_t id : {src_[k].face, c_.map.face[k]})
                if (id && id <= c_.nfaces && n < kMaxGeneralFaces && std::find(out, out + n, id) == out + n)
                    out[n++] = id;
        });
        return n;
    }
    // Whether face id has been solved from any start for this pixel.
    bool solved(uint32_t id) const {
        return std::any_of(tried_, tried_ + ntried_, [id](const Start& t) { return t.id == id; });
    }
    void far_starts(const MeshScreenPoints::FarFace& f) {
        for (int q = 0; q < f.nstarts; ++q)
            attempt(f.id, static_cast<float>(f.starts[q].x), static_cast<float>(f.starts[q].y));
        const UvBox& bx = c_.prepared.faces()[f.id - 1].box;
        attempt(f.id, static_cast<float>(0.5 * (bx.u0 + bx.u1)), static_cast<float>(0.5 * (bx.v0 + bx.v1)));
    }

    struct Start {
        uint32_t id;
        float u, v;
    };
    const FrameContext& c_;
    const Solver& solver_;
    const PixelArray<PixelHit>& src_;
    const int i_, j_;
    const bool crack_;
    Start tried_[kMaxStarts];
    int ntried_ = 0;
    // A's and B's share; C and D may use the rest.
    int limit_ = kMaxStarts - kFarStartsPerFace * (kAdjacentFaces.max_faces + kScreenFaces.max_faces);
};

// Whether both pixels of a row or column pair around (i, j) are hit nearer than
// t by more than a pixel footprint at t.
bool behind_pair(const FrameContext& c, const PixelArray<PixelHit>& src, int i, int j, double t) {
    const double margin = c.pixel_footprint(t);
    auto nearer = [&](int a, int b) {
        if (!c.in_frame(a, b)) return false;
        const PixelHit& h = src[c.map.index(a, b)];
        return h.face != 0 && h.t < t - margin;
    };
    return (nearer(i - 1, j) && nearer(i + 1, j)) || (nearer(i, j - 1) && nearer(i, j + 1));
}

// Whether hits a and b, on either side of a background gap of at most three
// pixels, can border one crack: their depths differ by at most
// kCrackDepthFootprints pixel footprints (one surface, or two that meet, across
// the gap), or their faces are the same, touch, or both touch a third (a strip
// too thin for the map between them). Otherwise the gap is background between
// two separate things, where a thorough search is wasted.
bool may_share_crack(const FrameContext& c, const PixelHit& a, const PixelHit& b) {
    const double footprint = c.pixel_footprint(std::min(a.t, b.t));
    if (std::abs(a.t - b.t) <= kCrackDepthFootprints * footprint || a.face == b.face) return true;
    const std::vector<uint32_t>& na = c.prepared.faces()[a.face - 1].adjacent;
    const std::vector<uint32_t>& nb = c.prepared.faces()[b.face - 1].adjacent;
    if (std::binary_search(na.begin(), na.end(), b.face)) return true;
    // Both lists ascending: a common element by one merge.
    for (auto x = na.begin(), y = nb.begin(); x != na.end() && y != nb.end();) {
        if (*x == *y) return true;
        if (*x < *y)
            ++x;
        else
            ++y;
    }
    return false;
}

// Whether the background pixel (i, j) lies in a crack or pinhole: hit within
// two pixels on both sides along a row or column, by hits that may border one
// crack (may_share_crack).
bool enclosed_in_crack(const FrameContext& c, const PixelArray<PixelHit>& src, int i, int j) {
    static const PixelHit kNoHit;
    auto hit_at = [&](int a, int b) -> const PixelHit& { return c.in_frame(a, b) ? src[c.map.index(a, b)] : kNoHit; };
    for (const auto& [di, dj] : {std::pair{1, 0}, std::pair{0, 1}}) {
        const PixelHit* before[2] = {&hit_at(i - di, j - dj), &hit_at(i - 2 * di, j - 2 * dj)};
        const PixelHit* after[2] = {&hit_at(i + di, j + dj), &hit_at(i + 2 * di, j + 2 * dj)};
        for (const PixelHit* a : before)
            for (const PixelHit* b : after)
                if (a->face && b->face && may_share_crack(c, *a, *b)) return true;
    }
    return false;
}

// One pixel's rescue from the hits `src` (and the map); returns its kind, or kNoRescue.
uint8_t rescue_pixel(const FrameContext& c, const Solver& solver, const MeshScreenPoints& screen_points, int i, int j,
                     const PixelArray<PixelHit>& src, PixelHit& out) {
    const size_t k = c.map.index(i, j);
    auto hit_at = [&](int a, int b) { return c.in_frame(a, b) && src[c.map.index(a, b)].face != 0; };
    const uint32_t own = c.map.face[k] <= c.nfaces ? c.map.face[k] : 0;
    bool touches = false;
    for_each_neighbour(c, i, j, kNeighbourRadius, [&](int ni, int nj) {
        touches = hit_at(ni, nj);
        return !touches;
    });
    if (!own && !touches) return kNoRescue;  // plain background
    const bool l = hit_at(i - 1, j), r = hit_at(i + 1, j), u = hit_at(i, j - 1), d = hit_at(i, j + 1);
    const int n4 = l + r + u + d;
    const bool crack = (l && r) || (u && d) || n4 >= 3;
    // Hits on opposite sides within two pixels: a crack two pixels wide, or a
    // pixel beside a one-pixel hit sliver (a thin face's few map pixels, already
    // solved) that the exact surface covers too.
    auto hit_within2 = [&](int di, int dj) { return hit_at(i + di, j + dj) || hit_at(i + 2 * di, j + 2 * dj); };
    const bool enclosed = (hit_within2(-1, 0) && hit_within2(1, 0)) || (hit_within2(0, -1) && hit_within2(0, 1));

    PixelRescue pr(c, solver, src, i, j, crack);
    pr.neighbour_starts(own);
    // The map shows its own face here, in front of every other mesh, but its
    // solves failed while another face was hit: try the own face's far starts
    // too, as B does where nothing was hit. A strip seen edge-on whose mesh
    // chord lies off the exact surface can diverge from its map start yet
    // converge from its nearest mesh vertex. Inside the trim only: a band hit
    // here lies over the face across the edge, which the ray does hit.
    if (own && pr.best.face && pr.best.face != own) {
        pr.keep_band_hits = false;
        pr.far_starts(screen_points, own, c.camera.pixel_screen(i, j));
        pr.keep_band_hits = true;
    }
    uint8_t kind = own ? kRescueNeighbour : kRescueSilhouette;
    // A hit found behind both neighbours of a row or column pair (deeper than
    // their nearer one by a pixel footprint) is a face seen through a crack of the
    // front surface: the face that closes the crack is not among A's; look further.
    const bool pit = pr.best.face && behind_pair(c, src, i, j, pr.best.t);
    if ((!pr.best.face && !pr.best_near.face && (own || n4 >= 2 || enclosed)) || pit) {
        // Thorough where a face should cover the pixel, not in a gap between separate things
        // (enclosed_in_crack), where the far starts and D find nothing.
        const bool thorough = own || crack || pit || enclosed_in_crack(c, src, i, j);
        pr.general_starts(screen_points, thorough);
        kind = kRescueGeneral;
        // C only where the pixel is enclosed (its map face failed, or hits on
        // opposite sides): not along every silhouette, where B already fails for good reason.
        if ((!pr.best.face && !pr.best_near.face && (own || enclosed)) || (pit && behind_pair(c, src, i, j, pr.best.t)))
            pr.adjacent_starts(screen_points);
        if (!pr.best.face && !pr.best_near.face && enclosed && thorough) pr.screen_starts(screen_points);
    }
    // A hit inside a trim beats a near-trim one unless the latter is in front
    // (a crack in a front face must not show the face behind it).
    PixelHit best = pr.best;
    if (pr.best_near.face && pr.best_near.t < best.t) {
        best = pr.best_near;
        kind = kRescueTrimTol;
    }
    if (!best.face) return kNoRescue;
    out = best;
    return kind;
}

// Silhouette growth: where the mesh is coarse, the exact silhouette can lie
// several pixels outside the map's. Repeat the rescue on the background pixels
// next to the last pass's new hits until none is added; each pass reads only the
// previous state, so the result stays thread-independent.
// `fresh`: the pixels the rescue filled, ascending.
void grow_silhouettes(const FrameContext& c, const Solver& solver, const MeshScreenPoints& screen_points,
                      std::vector<size_t> fresh, FrameBuffers& b) {
    const int W = c.width;
    std::vector<size_t> cand;
    std::vector<uint8_t> queued(c.pixels(), 0);
    for (int pass = 0; pass < kMaxGrowthPasses && !fresh.empty(); ++pass) {
        throw_if_canceled(c.options);
        cand.clear();
        for (const size_t k : fresh)
            for_each_neighbour(c, static_cast<int>(k % W), static_cast<int>(k / W), kNeighbourRadius,
                               [&](int ni, int nj) {
                                   const size_t n = c.map.index(ni, nj);
                                   if (!b.hits[n].face && !queued[n]) {
                                       queued[n] = 1;
                                       cand.push_back(n);
                                   }
                               });
        std::sort(cand.begin(), cand.end());
        std::vector<PixelHit> got(cand.size());
        std::vector<uint8_t> kinds(cand.size(), kNoRescue);
        c.arena.execute([&] {
            tbb::parallel_for(size_t(0), cand.size(), [&](size_t q) {
                const size_t k = cand[q];
                // b.hits is only written after this loop: every pixel reads the previous pass.
                kinds[q] = rescue_pixel(c, solver, screen_points, static_cast<int>(k % W), static_cast<int>(k / W),
                                        b.hits, got[q]);
            });
        });
        fresh.clear();
        for (size_t q = 0; q < cand.size(); ++q) {
            queued[cand[q]] = 0;
            if (!kinds[q]) continue;
            b.set(cand[q], got[q]);
            b.rescued[cand[q]] = kinds[q];
            fresh.push_back(cand[q]);
        }
    }
    throw_if_canceled(c.options);
}

}  // namespace

namespace {

// Per pixel: 1 where the pixel has no primary hit but a face in the map or a hit
// among its 8 neighbours, i.e. where rescue_pixel has something to try; the rest
// of the background is skipped on one byte. A separable 3x3 dilation of the hit
// mask, from the primary outcomes (a byte per pixel) rather than the 40-byte
// hits. Each loop is branch-free over a row's interior (the borders apart) so
// that the compiler vectorizes it.
std::vector<uint8_t> rescue_candidates(const FrameContext& c, const std::vector<uint8_t>& outcome) {
    const size_t W = static_cast<size_t>(c.width), H = static_cast<size_t>(c.height), n = c.pixels();
    std::vector<uint8_t> hit(n), row(n);
    for (size_t k = 0; k < n; ++k) hit[k] = outcome[k] == kConverged;
    for (size_t j = 0; j < H; ++j) {
        const uint8_t* h = hit.data() + j * W;
        uint8_t* r = row.data() + j * W;
        r[0] = h[0] | (W > 1 ? h[1] : 0);
        for (size_t i = 1; i + 1 < W; ++i) r[i] = h[i - 1] | h[i] | h[i + 1];
        if (W > 1) r[W - 1] = h[W - 2] | h[W - 1];
    }
    // In place over `hit`: a pixel's result needs only its own hit byte.
    const uint32_t nfaces = c.nfaces;
    for (size_t j = 0; j < H; ++j) {
        const uint8_t* r = row.data() + j * W;
        const uint8_t* up = j > 0 ? r - W : r;
        const uint8_t* down = j + 1 < H ? r + W : r;
        const uint32_t* face = c.map.face.data() + j * W;
        uint8_t* h = hit.data() + j * W;
        for (size_t i = 0; i < W; ++i) {
            const uint8_t own = face[i] - 1u < nfaces;  // 1..nfaces: a face of the scene
            h[i] = static_cast<uint8_t>((h[i] ^ 1u) & (up[i] | r[i] | down[i] | own));  // hit bytes are 0 or 1
        }
    }
    return hit;
}

}  // namespace

void rescue_pass(const FrameContext& c, const Solver& solver, const MeshScreenPoints& screen_points, FrameBuffers& b) {
    const std::vector<uint8_t> todo = rescue_candidates(c, b.outcome);
    // Every pixel reads the primary hits: the rescued ones are collected per row
    // and written after the pass, so the result does not depend on the order
    // (or the thread count).
    struct Rescued {
        size_t k;
        PixelHit hit;
        uint8_t kind;
    };
    std::vector<std::vector<Rescued>> rows(c.height);
    parallel_rows(c, true, [&](int j) {
        const uint8_t* row = todo.data() + c.map.index(0, j);
        // The candidates are 1 among 0s: memchr skips to the next (vectorized).
        for (const uint8_t* p = row; (p = static_cast<const uint8_t*>(std::memchr(p, 1, row + c.width - p))); ++p) {
            const int i = static_cast<int>(p - row);
            const size_t k = c.map.index(i, j);
            PixelHit h;
            if (const uint8_t kind = rescue_pixel(c, solver, screen_points, i, j, b.hits, h))
                rows[j].push_back({k, h, kind});
        }
    });
    throw_if_canceled(c.options);
    std::vector<size_t> fresh;  // ascending: the rows in order, each row's pixels in order
    for (const std::vector<Rescued>& row : rows)
        for (const Rescued& r : row) {
            b.set(r.k, r.hit);
            b.rescued[r.k] = r.kind;
            fresh.push_back(r.k);
        }
    grow_silhouettes(c, solver, screen_points, std::move(fresh), b);
}

}  // namespace nurbsrt
