// The nearer-sheet pass. Where a surface folds over itself (or two faces lie
// closer than the map mesh's deflection), the map can hand a pixel the farther of
// two sheets, and Newton converges there; it shows as an isolated depth spike: a
// hit deeper than the mean of both neighbours of a horizontal or vertical pair by
// more than the spike threshold, or as a step at the end of a run of such pixels
// (the near neighbour a sheet in front, the other level), or on a silhouette a
// sheet behind the neighbour (a curved face's rim, crossed twice by the ray).
// Such pixels are solved again from those neighbours' faces and (u, v), at a step
// also from faces the neighbours do not show (nearer_sheet_search.cpp); a hit on
// the pixel's own ray that is nearer by more than the nearer threshold replaces
// it: the nearest intersection is the visible one. A face narrower than a pixel
// that runs diagonally in front of others shows in the map only every second or
// third pixel: its face is tried at the pixels around those (thin_tries), and a
// face most of whose pixels are such is tried along its whole mesh on screen
// (thin_face_tries: where it runs along a row, its map pixels may be missing
// for a stretch). A hit just outside the neighbour face's trim, within its tolerance band,
// counts where both neighbours are in front (a crack between two front faces
// otherwise shows the face behind). Reads only the hits so far, so the result
// stays independent of the thread count.
#include <algorithm>
#include <cmath>
#include <tuple>
#include <utility>

#include "renderer/frame/mesh_screen_points.h"
#include "renderer/passes/nearer_sheet.h"
#include "renderer/passes/passes.h"

namespace nurbsrt {

namespace {

// Relative to the scene's bounding-box diagonal. A spike is measured against the
// mean depth of the two neighbours, i.e. a second difference, which on one smooth
// sheet is tiny at the resolutions rendered; 10x the nearer threshold keeps it
// above Newton's noise and far below the gap between two sheets the map confuses.
constexpr double kSpikeRelative = 1e-5;
// Nearer: 100x the default Newton tolerance (kDefaultRelativeTolerance), so the
// same root reached from another start never counts as nearer.
constexpr double kNearerRelative = 1e-6;
// Neighbour offsets (di, dj): the 4-neighbours, the diagonal ones.
constexpr std::pair<int, int> kSideOffsets[] = {{-1, 0}, {1, 0}, {0, -1}, {0, 1}};
constexpr std::pair<int, int> kDiagonalOffsets[] = {{-1, -1}, {1, -1}, {-1, 1}, {1, 1}};
// A neighbour's (u, v) "jumps" when it is 3x farther from the pixel's than the
// opposite neighbour's, or than half the distance between the two neighbours'
// (compared squared: 9): on one smooth sheet all three are about equal.
constexpr double kUvJump2 = 9.0;
// On one smooth sheet the pixel's (u, v) lies near the midpoint of its pair's;
// off it by more than the pair's whole distance (twice half of it; squared: 4),
// it lies on another sheet between two on one: a fold of the face, where the
// steps to both neighbours are alike and kUvJump2 does not tell (a fillet seen
// where it turns away).
constexpr double kUvOffPair2 = 4.0;
// A neighbour nearer than the pixel by this many times the depth step to the
// pair's other neighbour is on another sheet, whatever the (u, v) say: on one
// smooth sheet the steps to both sides are about equal (a slope), differing by
// a factor of a few only where the sheet turns edge-on within a pixel; at the
// end of a run of far-sheet pixels the near neighbour lies a whole gap between
// sheets away while the far one is level with the pixel. The (u, v) test misses
// that end where a pixel step in one parameter exceeds the sheets' distance in
// the other (a cylinder's axial parameter near its silhouette).
constexpr double kSheetStepRatio = 8;
// On one smooth sheet the (u, v) step from one pixel to the next changes
// little: a second difference up to the step itself (squared: 1) still
// continues the sheet (foreshortening towards a silhouette grows steps far more
// slowly, pixel to pixel); a step onto another sheet jumps by many steps.
constexpr double kUvSmooth2 = 1.0;
// across_own_rim's starts, in steps from the pixel's root through the map's
// start: the ray's entry root lies on the far side of the rim from its exit,
// at an unknown multiple of that step.
constexpr double kAcrossRimSteps[] = {2, 4, 8, 16};
// Passes after the first: a run of far-sheet pixels is peeled one pixel per pass
// from each end, so runs of up to about 64 pixels are cleared; longer runs are not spikes
// but a whole region the map got wrong, which this pass does not claim to fix.
constexpr int kMaxPeelPasses = 32;

// The squared distance between two hits' (u, v).
double uv_dist2(const PixelHit& x, const PixelHit& y) {
    const double du = double(x.u) - y.u, dv = double(x.v) - y.v;
    return du * du + dv * dv;
}

struct Update {
    size_t k;
    PixelHit hit;
};

}  // namespace

NearerSheet::NearerSheet(const FrameContext& c, const Solver& solver, const MeshScreenPoints& screen_points,
                         const FrameBuffers& b)
    : c_(c), solver_(solver), hits_(b.hits), depth_(b.depth), rescued_(b.rescued), screen_points_(screen_points) {
    const double diag = std::max(c.bbox.diagonal(), 1e-300);
    spike_ = kSpikeRelative * diag;
    nearer_ = kNearerRelative * diag;
}

bool NearerSheet::find(int i, int j, PixelHit& out) const {
    const PixelHit& p = hits_[c_.map.index(i, j)];
    if (!p.face) return false;
    PixelHit best = p;
    bool pit = false;
    const int pairs[2][4] = {{i - 1, j, i + 1, j}, {i, j - 1, i, j + 1}};
    // Pits where a neighbour continues the pixel's sheet and the other is on
    // another face; and whether a pit's neighbour on the pixel's face does not.
    bool continued = false, own_face_jump = false, step = false, silhouette = false;
    StepFronts fronts;
    for (const auto& pq : pairs) {
        if (!c_.in_frame(pq[0], pq[1]) || !c_.in_frame(pq[2], pq[3])) continue;
        const PixelHit& a = hits_[c_.map.index(pq[0], pq[1])];
        const PixelHit& b = hits_[c_.map.index(pq[2], pq[3])];
        if (!a.face != !b.face) {
            silhouette = true;
            const bool a_side = a.face != 0;
            silhouette_pair(i, j, a_side ? pq[0] : pq[2], a_side ? pq[1] : pq[3], best);
            continue;
        }
        // Beyond a fold's silhouette, the near sheet's root (solved from where
        // the sheet's (u, v) steps lead past the pixel, see fold_edge).
        for (int q = 0; q < 2; ++q) {
            const PixelHit& n = q == 0 ? a : b;
            if (fold_edge(p, n, q == 0 ? b : a))
                consider(p.face, i, j, 2 * p.u - n.u, 2 * p.v - n.v, solver_.robust, false, best);
        }
        if (!a.face || !b.face || !(p.t > 0.5 * (a.t + b.t) + spike_)) continue;
        // Only from a neighbour on another face, or on another sheet of the same
        // face, where its (u, v) jumps: a smoothly curved concave sheet, whose
        // depth also rises above the pair's mean, changes (u, v) evenly and is not
        // solved again. On another sheet either one neighbour is far in (u, v)
        // while the other is near (the edge of a run of far-sheet pixels), or both
        // are far compared with their own distance (an isolated far-sheet pixel).
        const double half_pair2 = 0.25 * uv_dist2(a, b);
        // (u, v) distances mislead where a face's parametrization is very
        // anisotropic; in model units, a pixel deeper than both of its pair by
        // more than its own footprint is not on their smooth sheet either (on a
        // slope it lies between them, so grazing views cost no extra solves).
        const bool deep = p.t - std::max(a.t, b.t) > sheet_gap(p.t);
        const float mid_u = 0.5f * (a.u + b.u), mid_v = 0.5f * (a.v + b.v);
        const double off_u = double(p.u) - mid_u, off_v = double(p.v) - mid_v;
        const bool off_pair =
            a.face == p.face && b.face == p.face && off_u * off_u + off_v * off_v > kUvOffPair2 * half_pair2;
        bool from[2] = {false, false}, cont[2] = {false, false};
        for (int q = 0; q < 2; ++q) {
            const PixelHit& n = q == 0 ? a : b;
            const PixelHit& other = q == 0 ? b : a;
            const bool step = p.t - n.t > kSheetStepRatio * std::fabs(p.t - other.t);
            const bool jump = deep || step || off_pair || n.face != p.face || other.face != p.face ||
                              uv_dist2(n, p) > kUvJump2 * std::min(uv_dist2(other, p), half_pair2);
            from[q] = jump && n.t < p.t - nearer_;
            cont[q] = from[q] && continues(p, n, 2 * pq[2 * q] - i, 2 * pq[2 * q + 1] - j);
        }
        const int jumps = from[0] + from[1];
        step |= jumps == 1;
        // At a pit (both neighbours in front) the pixel is a crack in the front
        // surface: a hit just outside a neighbour's trim, within its tolerance
        // band, counts (as for the rescue's cracks). Never at a mere step in
        // depth, where the band would spread a face past its edge pixel by pixel.
        // Where each neighbour's surface meets the pixel's ray (NaN: no
        // convergence), for telling a concave corner from a crack below.
        double crossing[2] = {NAN, NAN};
        for (int q = 0; q < 2; ++q) {
            const PixelHit& n = q == 0 ? a : b;
            if (!from[q]) continue;
            const Outcome o = consider(n.face, i, j, n.u, n.v, solver_.params, jumps == 2, best, &crossing[q]);
            if (jumps != 1 || n.face == p.face) continue;
            // At a step, how the solve on the face in front ended: crossed
            // outside its trim and in front of the hit, the ray passes beyond
            // that face's edge (beyond_edges); ended where no face is linked
            // (unlinked_end); Newton diverged or stalled (faces_beyond_failed);
            // failed in any way (faces_joining_failed).
            if (o == kTrimmed && crossing[q] < p.t - sheet_gap(p.t)) fronts.crossed[fronts.ncrossed++] = n.face;
            fronts.unlinked |= unlinked_end(p, n, o);
            if (newton_failed(o)) fronts.failed[fronts.nfailed++] = {pq[2 * q] - i, pq[2 * q + 1] - j, o};
        }
        // A pit between two nearer neighbours on one face: the middle of their
        // (u, v) starts next to the root between them, where Newton from either
        // end can still run to another sheet (near a silhouette a sheet's two
        // roots lie close together). So too a step whose pair lies on the
        // pixel's face: the pixel on a far turn of a face folded many times,
        // where every neighbour's start may lead behind. No trim band at a step.
        if ((jumps == 2 || (jumps == 1 && a.face == p.face)) && a.face == b.face)
            consider(a.face, i, j, 0.5f * (a.u + b.u), 0.5f * (a.v + b.v), solver_.params, jumps == 2, best);
        // A pit whose two neighbours' surfaces both meet the ray at or behind
        // the pixel's hit is a concave corner (a groove, a fillet's foot seen
        // from outside), not a crack: a crack's front surface continues over the
        // gap, so at least one of them meets the ray in front, outside its trim.
        // Corners are not searched further: costly, and almost never nearer.
        const bool corner = crossing[0] >= p.t - nearer_ && crossing[1] >= p.t - nearer_;
        if (jumps == 2 && !corner) {
            pit = true;
            continued |= (cont[0] && b.face != p.face) || (cont[1] && a.face != p.face);
            own_face_jump |= (!cont[0] && a.face == p.face) || (!cont[1] && b.face == p.face);
        }
    }
    auto unchanged = [&] { return best.face == p.face && best.t == p.t; };
    if (pit && unchanged()) fill_pit(i, j, continued && !own_face_jump, best);
    // A step (one neighbour in front) that the pair's faces did not fill: the
    // faces the 4-neighbours do not show (a strip thinner than a pixel between
    // the face in front and the pixel's). So too at a silhouette pixel the
    // rescue filled: the face in front may show only diagonally, where a face's
    // corner overhangs the silhouette; first the diagonal neighbours' own
    // starts, on any face (the rescue may have reached the farther root from a
    // 4-neighbour's start that only a diagonal one avoids). At any silhouette
    // pixel, those on its own face only: the map's start too may lead to the
    // farther root of a thin rim (on every face it cost more for nothing).
    const bool rescued_rim = silhouette && rescued_[c_.map.index(i, j)];
    if (silhouette && unchanged()) rim_faces_in_front(i, j, best);
    if (silhouette && unchanged()) diagonal_starts(i, j, !rescued_rim, best);
    if (((step && !pit) || rescued_rim) && unchanged()) diagonal_faces(i, j, best);
    if (fronts.nfailed && step && !pit) {
        if (unchanged()) faces_beyond_failed(i, j, fronts, best);
        if (unchanged()) faces_joining_failed(i, j, fronts, best);
    }
    // Beyond the edge of a face in front, the faces joining it there, and those
    // joining the pixel's own face, the face behind: a wall rising from it
    // towards the edge, seen edge-on, lies between the two, too thin to show in
    // any map pixel.
    if (fronts.ncrossed && !pit && unchanged()) {
        fronts.crossed[fronts.ncrossed++] = p.face;
        beyond_edges(i, j, {fronts.crossed, fronts.crossed + fronts.ncrossed}, {}, best);
    }
    // Where the face in front ends unlinked (unlinked_end), the faces near on
    // screen stand in for the adjacency beyond_edges reads.
    if (fronts.unlinked && !pit && unchanged()) screen_faces(i, j, best);
    if (unchanged()) return false;
    out = best;
    return true;
}

void NearerSheet::silhouette_pair(int i, int j, int ni, int nj, PixelHit& best) const {
    const PixelHit& p = hits_[c_.map.index(i, j)];  // as find's tests: the pixel's hit, not best
    const PixelHit& n = hits_[c_.map.index(ni, nj)];
    if (!(n.t < p.t - sheet_gap(p.t)) || continues(p, n, 2 * ni - i, 2 * nj - j)) return;
    consider(n.face, i, j, n.u, n.v, solver_.robust, false, best);
    if (best.face != p.face || best.t != p.t) return;
    if (n.face != p.face)
        rim_own_mesh(i, j, best);
    else if (alone_on_face(i, j, p.t - sheet_gap(p.t)))
        across_own_rim(i, j, best);
}

bool NearerSheet::unlinked_end(const PixelHit& p, const PixelHit& n, Outcome o) const {
    const double step = p.t - n.t, gap = sheet_gap(p.t);
    return (o == kTrimmed || o == kLeftDomain) && step > gap && step < kUnlinkedStepGaps * gap &&
           c_.prepared.faces()[n.face - 1].adjacent.empty();
}

void NearerSheet::rim_own_mesh(int i, int j, PixelHit& best) const {
    const uint32_t f = best.face;
    if (!c_.prepared.faces()[f - 1].planar && (rescued_[c_.map.index(i, j)] || alone_on_face(i, j, -HUGE_VAL)))
        mesh_in_front(f, i, j, best);
}

void NearerSheet::across_own_rim(int i, int j, PixelHit& best) const {
    const PixelHit p = best;
    const size_t k = c_.map.index(i, j);
    if (c_.map.face[k] != p.face) return;
    const double du = double(c_.map.u[k]) - p.u, dv = double(c_.map.v[k]) - p.v;
    for (const double f : kAcrossRimSteps) {
        consider(p.face, i, j, static_cast<float>(p.u + f * du), static_cast<float>(p.v + f * dv), solver_.robust,
                 false, best);
        if (best.t != p.t) return;
    }
}

bool NearerSheet::alone_on_face(int i, int j, double nearer_than) const {
    const PixelHit& p = hits_[c_.map.index(i, j)];
    bool alone = true;
    for_each_neighbour(c_, i, j, 1, [&](int ni, int nj) {
        const PixelHit& h = hits_[c_.map.index(ni, nj)];
        alone = alone && ((ni == i && nj == j) || h.face != p.face || h.t < nearer_than);
    });
    return alone;
}

bool NearerSheet::fold_edge(const PixelHit& p, const PixelHit& n, const PixelHit& behind) const {
    return p.face && n.face == p.face && behind.face == p.face && behind.t > p.t + sheet_gap(p.t) &&
           uv_dist2(behind, p) > kUvJump2 * uv_dist2(n, p);
}

bool NearerSheet::fold_edge(size_t k, size_t a, size_t b) const {
    return fold_edge(hits_[k], hits_[a], hits_[b]) || fold_edge(hits_[k], hits_[b], hits_[a]);
}

template <class Accept>
void NearerSheet::from_neighbour_hits(int i, int j, std::span<const std::pair<int, int>> offsets, Accept accept,
                                      PixelHit& best) const {
    const PixelHit p = best;
    for (const auto& [di, dj] : offsets) {
        if (!c_.in_frame(i + di, j + dj)) continue;
        const PixelHit& h = hits_[c_.map.index(i + di, j + dj)];
        if (!h.face || !accept(di, dj, p, h)) continue;
        consider(h.face, i, j, h.u, h.v, solver_.robust, false, best);
        if (best.face != p.face || best.t != p.t) return;
    }
}

void NearerSheet::rim_faces_in_front(int i, int j, PixelHit& best) const {
    from_neighbour_hits(
        i, j, kSideOffsets,
        [&](int di, int dj, const PixelHit& p, const PixelHit& h) {
            if (h.face == p.face || !(h.t < p.t - spike_)) return false;
            // A sheet gap in front opposite the background: find's silhouette test tried it.
            const bool opposite_open = !c_.in_frame(i - di, j - dj) || !hits_[c_.map.index(i - di, j - dj)].face;
            return !(opposite_open && h.t < p.t - sheet_gap(p.t));
        },
        best);
}

void NearerSheet::diagonal_starts(int i, int j, bool own_face, PixelHit& best) const {
    from_neighbour_hits(
        i, j, kDiagonalOffsets,
        [&](int di, int dj, const PixelHit& p, const PixelHit& h) {
            if ((own_face && h.face != p.face) || !(h.t < p.t - sheet_gap(p.t))) return false;
            return !continues(p, h, i + 2 * di, j + 2 * dj);  // not one sheet turning away (see find)
        },
        best);
}

bool NearerSheet::continues(const PixelHit& p, const PixelHit& n, int fi, int fj) const {
    if (n.face != p.face || !c_.in_frame(fi, fj)) return false;
    const PixelHit& f = hits_[c_.map.index(fi, fj)];
    if (f.face != p.face) return false;
    const double du = double(p.u) - n.u, dv = double(p.v) - n.v;
    const double fu = double(n.u) - f.u, fv = double(n.v) - f.v;
    const double su = du - fu, sv = dv - fv;  // the second difference
    return su * su + sv * sv <= kUvSmooth2 * (fu * fu + fv * fv) && std::fabs(p.t - 2 * n.t + f.t) <= sheet_gap(p.t);
}

double NearerSheet::depth_in_front(double t, ScreenPoint sp) const { return c_.depth_behind(t, -kSheetFootprints, sp); }

Outcome NearerSheet::consider(uint32_t id, int i, int j, float u0, float v0, const NewtonParams& params, bool near,
                              PixelHit& best, double* crossing) const {
    PixelHit h;
    const Outcome o = solver_.solve(id, i, j, u0, v0, params, near, h, crossing);
    if ((o == kConverged || o == kNearTrim) && h.t < best.t - nearer_) best = h;
    return o;
}

namespace {

// Solves the thin faces' tries, from each pixel's nearest start per face, and
// adds the nearer hits found to updates.
void solve_thin(const FrameContext& c, const NearerSheet& nearer, std::vector<NearerSheet::ThinTry>& tries,
                std::vector<Update>& updates) {
    if (tries.empty()) return;
    using Try = NearerSheet::ThinTry;
    std::sort(tries.begin(), tries.end(), [](const Try& x, const Try& y) {
        return std::tie(x.k, x.face, x.reach, x.u, x.v) < std::tie(y.k, y.face, y.reach, y.u, y.v);
    });
    tries.erase(std::unique(tries.begin(), tries.end(),
                            [](const Try& x, const Try& y) { return x.k == y.k && x.face == y.face; }),
                tries.end());
    std::vector<PixelHit> hit(tries.size());
    std::vector<uint8_t> found(tries.size(), 0);
    c.arena.execute([&] {
        tbb::parallel_for(size_t(0), tries.size(), [&](size_t q) { found[q] = nearer.solve(tries[q], hit[q]); });
    });
    for (size_t q = 0; q < tries.size(); ++q)
        if (found[q]) updates.push_back({tries[q].k, hit[q]});
    tries.clear();
}

// A face is thin where at least this share of its pixels are thin pixels
// (NearerSheet::thin_tries): a ring or a strip narrower than a pixel is all thin
// pixels, while ordinary faces show a few at their corners and narrow ends,
// whose whole-mesh searches would cost far more than they find.
constexpr double kThinFaceShare = 0.5;

// The thin faces among those of the rows' thin pixels, ascending.
std::vector<uint32_t> thin_faces(const FrameContext& c, const FrameBuffers& b,
                                 const std::vector<std::vector<uint32_t>>& row_thin) {
    std::vector<uint32_t> thin(c.nfaces + 1, 0), all(c.nfaces + 1, 0), out;
    bool any = false;
    for (const std::vector<uint32_t>& r : row_thin)
        for (const uint32_t f : r) ++thin[f], any = true;
    if (!any) return out;
    for (size_t k = 0; k < c.pixels(); ++k) ++all[b.hits[k].face];
    for (uint32_t f = 1; f <= c.nfaces; ++f)
        if (thin[f] && thin[f] >= kThinFaceShare * all[f]) out.push_back(f);
    return out;
}

// The thin faces tried over their whole mesh too (NearerSheet::thin_face_tries),
// appended to tries.
void add_thin_face_tries(const FrameContext& c, const NearerSheet& nearer, const std::vector<uint32_t>& faces,
                         std::vector<NearerSheet::ThinTry>& tries) {
    std::vector<std::vector<NearerSheet::ThinTry>> per_face(faces.size());
    c.arena.execute([&] {
        tbb::parallel_for(size_t(0), faces.size(), [&](size_t q) { nearer.thin_face_tries(faces[q], per_face[q]); });
    });
    for (const std::vector<NearerSheet::ThinTry>& f : per_face) tries.insert(tries.end(), f.begin(), f.end());
}

// One update per pixel, its nearest hit (a pixel may be found by find and by
// several thin faces' tries).
void nearest_per_pixel(std::vector<Update>& updates) {
    std::sort(updates.begin(), updates.end(),
              [](const Update& x, const Update& y) { return std::tie(x.k, x.hit.t) < std::tie(y.k, y.hit.t); });
    updates.erase(
        std::unique(updates.begin(), updates.end(), [](const Update& x, const Update& y) { return x.k == y.k; }),
        updates.end());
}

}  // namespace

uint64_t nearer_sheet_pass(const FrameContext& c, const Solver& solver, const MeshScreenPoints& screen_points,
                           FrameBuffers& b) {
    const NearerSheet nearer(c, solver, screen_points, b);
    const int W = c.width;
    // The first pass examines every pixel; replacements are collected per row
    // (almost always none) and applied between passes: no frame-sized buffer for
    // a handful of pixels. Later passes examine only the 4-neighbours of those the
    // last pass changed (all 8 adds solves, mostly repeats), and where a changed
    // pixel is a thin face's, that face around it (a strip narrower than a pixel
    // is followed along, its pixels 2-3 apart).
    std::vector<std::vector<Update>> row_updates(c.height);
    std::vector<std::vector<NearerSheet::ThinTry>> row_tries(c.height);
    std::vector<std::vector<uint32_t>> row_thin(c.height);  // the faces of the row's thin pixels
    parallel_rows(c, false, [&](int j) {
        for (int i = 0; i < W; ++i) {
            PixelHit h;
            bool thin;
            if (nearer.maybe_spike(i, j, thin) && nearer.find(i, j, h))
                row_updates[j].push_back({c.map.index(i, j), h});
            if (thin && nearer.thin_tries(i, j, row_tries[j])) row_thin[j].push_back(b.hits[c.map.index(i, j)].face);
        }
    });
    std::vector<Update> updates;
    std::vector<NearerSheet::ThinTry> tries;
    for (const std::vector<Update>& r : row_updates) updates.insert(updates.end(), r.begin(), r.end());
    for (const std::vector<NearerSheet::ThinTry>& r : row_tries) tries.insert(tries.end(), r.begin(), r.end());
    add_thin_face_tries(c, nearer, thin_faces(c, b, row_thin), tries);
    solve_thin(c, nearer, tries, updates);
    nearest_per_pixel(updates);
    uint64_t replaced = 0;
    std::vector<size_t> cand;
    std::vector<PixelHit> cand_hit;
    std::vector<uint8_t> cand_changed;
    for (int pass = 0; pass < kMaxPeelPasses && !updates.empty(); ++pass) {
        throw_if_canceled(c.options);
        cand.clear();
        for (const Update& u : updates) {
            b.set(u.k, u.hit);
            const int i = static_cast<int>(u.k % W), j = static_cast<int>(u.k / W);
            for_each_neighbour(c, i, j, 1, [&](int ni, int nj) {
                if ((ni == i) != (nj == j)) cand.push_back(c.map.index(ni, nj));  // the 4-neighbours
            });
        }
        for (const Update& u : updates) nearer.thin_tries(static_cast<int>(u.k % W), static_cast<int>(u.k / W), tries);
        replaced += updates.size();
        std::sort(cand.begin(), cand.end());
        cand.erase(std::unique(cand.begin(), cand.end()), cand.end());
        cand_hit.assign(cand.size(), PixelHit{});
        cand_changed.assign(cand.size(), 0);
        c.arena.execute([&] {
            tbb::parallel_for(size_t(0), cand.size(), [&](size_t q) {
                const size_t k = cand[q];
                cand_changed[q] = nearer.find(static_cast<int>(k % W), static_cast<int>(k / W), cand_hit[q]);
            });
        });
        updates.clear();
        for (size_t q = 0; q < cand.size(); ++q)
            if (cand_changed[q]) updates.push_back({cand[q], cand_hit[q]});
        solve_thin(c, nearer, tries, updates);
        nearest_per_pixel(updates);
    }
    // The last pass's finds are nearer hits on their own rays like any other:
    // kept, though their neighbours are not examined again.
    for (const Update& u : updates) b.set(u.k, u.hit);
    return replaced + updates.size();
}

}  // namespace nurbsrt
