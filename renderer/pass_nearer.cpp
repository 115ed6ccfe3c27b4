// The nearer-sheet pass. Where a surface folds over itself (or two faces lie
// closer than the map mesh's deflection), the map can hand a pixel the farther of
// two sheets, and Newton converges there; it shows as an isolated depth spike: a
// hit deeper than the mean of both neighbours of a horizontal or vertical pair by
// more than the spike threshold. Such pixels are solved again from those
// neighbours' faces and (u, v); a hit on the pixel's own ray that is nearer by more
// than the nearer threshold replaces it: the nearest intersection is the visible
// one. A hit just outside the neighbour face's trim, within its tolerance band,
// counts where both neighbours are in front (a crack between two front faces
// otherwise shows the face behind). Reads only the hits so far, so the result
// stays independent of the thread count.
#include <algorithm>
#include <cmath>

#include "renderer/mesh_screen_points.h"
#include "renderer/passes.h"

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
// A neighbour's (u, v) "jumps" when it is 3x farther from the pixel's than the
// opposite neighbour's, or than half the distance between the two neighbours'
// (compared squared: 9): on one smooth sheet all three are about equal.
constexpr double kUvJump2 = 9.0;
// On one smooth sheet the pixel's (u, v) lies near the midpoint of its pair's;
// off it by more than the pair's whole distance (twice half of it; squared: 4),
// it lies on another sheet between two on one: a fold of the face, where the
// steps to both neighbours are alike and kUvJump2 does not tell (a bearing's
// fillet, seen where it turns away).
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
// Passes after the first: a run of far-sheet pixels is peeled one pixel per pass
// from each end, so runs of up to about 64 pixels are cleared; longer runs are not spikes
// but a whole region the map got wrong, which this pass does not claim to fix.
constexpr int kMaxPeelPasses = 32;
// A pixel deeper than this many pixel footprints behind both of its pair is off
// their sheet: on one smooth sheet the second difference of depth is about a
// footprint squared over the curvature radius, far below one footprint except
// where the sheet is seen almost edge-on (a wasted re-solve there, never a wrong hit).
constexpr double kSheetFootprints = 1.0;
// Faces adjacent to a pit's 3x3 that are tried when none of the 3x3's faces
// fills it; a thin face in front touches one of them. Bounds the cost at a
// vertex where many faces meet (per ring of adjacent_faces).
constexpr int kMaxAdjacentFaces = 12;
// ... and only those whose mesh comes within 2 pixels of the pit on screen (the
// faces adjacent to a pit's are sorted nearest first, so the rest are farther).
constexpr double kPitFacePixels = 2.0;
// Faces near on screen (screen_faces) tried at a pit nothing else filled, the
// nearest first: as many as the rescue's last resort tries at a hole.
constexpr int kMaxScreenFaces = 4;
// Sheets of the pixel's own face in front of its hit that are tried, nearest
// to the eye first: a face folded over itself many times (a dense spring or
// coil seen edge-on) puts several there, and the map's front one may be a mesh
// sheet the exact ray passes by.
constexpr int kMaxSheetsInFront = 4;

// The squared distance between two hits' (u, v).
double uv_dist2(const PixelHit& x, const PixelHit& y) {
    const double du = double(x.u) - y.u, dv = double(x.v) - y.v;
    return du * du + dv * dv;
}

struct Update {
    size_t k;
    PixelHit hit;
};

class NearerSheet {
public:
    NearerSheet(const FrameContext& c, const Solver& solver, const MeshScreenPoints& screen_points,
                const FrameBuffers& b)
        : c_(c), solver_(solver), hits_(b.hits), depth_(b.depth), screen_points_(screen_points) {
        const double diag = std::max(c.scene.bbox.diagonal(), 1e-300);
        spike_ = kSpikeRelative * diag;
        nearer_ = kNearerRelative * diag;
    }
    // Whether find(i, j) can find anything: the pixel is a spike against one of
    // its pairs (on the hits' depths alone, t, +inf where no hit) or a fold's
    // edge, the first tests of find, which the first pass reads for every pixel.
    // The hits are read only where the depths allow a fold's edge (one of the
    // pair a sheet gap behind).
    bool maybe_spike(int i, int j) const {
        const size_t k = c_.map.index(i, j);
        const double d = depth_[k];
        if (!(d < HUGE_VAL)) return false;
        const double behind = d + sheet_gap(d);
        auto spike_or_fold = [&](size_t a, size_t b) {
            return d > 0.5 * (depth_[a] + depth_[b]) + spike_ ||
                   (std::max(depth_[a], depth_[b]) > behind && fold_edge(k, a, b));
        };
        const bool row = i > 0 && i + 1 < c_.width, column = j > 0 && j + 1 < c_.height;
        return (row && spike_or_fold(k - 1, k + 1)) || (column && spike_or_fold(k - c_.width, k + c_.width));
    }
    // A nearer hit for pixel (i, j) than its current one, if any.
    bool find(int i, int j, PixelHit& out) const {
        const PixelHit& p = hits_[c_.map.index(i, j)];
        if (!p.face) return false;
        PixelHit best = p;
        bool pit = false;
        const int pairs[2][4] = {{i - 1, j, i + 1, j}, {i, j - 1, i, j + 1}};
        // Pits where a neighbour continues the pixel's sheet and the other is on
        // another face; and whether a pit's neighbour on the pixel's face does not.
        bool continued = false, own_face_jump = false;
        for (const auto& pq : pairs) {
            if (!c_.in_frame(pq[0], pq[1]) || !c_.in_frame(pq[2], pq[3])) continue;
            const PixelHit& a = hits_[c_.map.index(pq[0], pq[1])];
            const PixelHit& b = hits_[c_.map.index(pq[2], pq[3])];
            if (!a.face != !b.face) {
                // One side background: the pixel lies on a silhouette, next to a
                // neighbour nearer by more than a footprint (another sheet), where a
                // fold's near sheet reaches the silhouette over a run of far-sheet
                // pixels that the pairs above peel down to here (a dense folded face
                // seen edge-on, step/bug29715_slow.stp): solved from that neighbour.
                const PixelHit& n = a.face ? a : b;
                if (n.t < p.t - sheet_gap(p.t))
                    consider(n.face, i, j, n.u, n.v, solver_.robust, false, best);
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
            // face: its (u, v) jumps. A smoothly curved concave sheet, where depth
            // also rises above the pair's mean, changes (u, v) evenly (the pixel's
            // (u, v) lies about midway between its neighbours') and is not solved
            // again. Two ways to be on another sheet: one neighbour is far in (u, v)
            // while the other is near (the pixel sits at the edge of a run of
            // far-sheet pixels), or both are far compared with their own distance
            // (an isolated far-sheet pixel between two near-sheet ones).
            const double half_pair2 = 0.25 * uv_dist2(a, b);
            // (u, v) distances mislead where a face's parametrization is very
            // anisotropic (two sheets a tenth of a pixel's v-step apart in u); in
            // model units, a pixel deeper than both of its pair by more than its own
            // footprint is not on their smooth sheet either (on a slope it lies
            // between them, so grazing views cost no extra solves).
            const bool deep = p.t - std::max(a.t, b.t) > sheet_gap(p.t);
            const float mid_u = 0.5f * (a.u + b.u), mid_v = 0.5f * (a.v + b.v);
            const double off_u = double(p.u) - mid_u, off_v = double(p.v) - mid_v;
            const bool off_pair = a.face == p.face && b.face == p.face &&
                                  off_u * off_u + off_v * off_v > kUvOffPair2 * half_pair2;
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
            // Where both neighbours are in front (a pit), the pixel is a crack in the
            // front surface: a hit just outside a neighbour's trim, within its
            // tolerance band, counts (as for the rescue's cracks), so that the crack
            // does not show the face behind. Never at a mere step in depth: there the
            // band would spread a face past its edge pixel by pixel.
            // Where each neighbour's surface meets the pixel's ray (NaN: no
            // convergence), for telling a concave corner from a crack below.
            double crossing[2] = {NAN, NAN};
            for (int q = 0; q < 2; ++q) {
                const PixelHit& n = q == 0 ? a : b;
                if (from[q]) consider(n.face, i, j, n.u, n.v, solver_.params, jumps == 2, best, &crossing[q]);
            }
            // A pit between two nearer neighbours on one face: the middle of their
            // (u, v) starts next to the root between them, where Newton from either
            // end can still run to another sheet (near a silhouette, a sheet's two
            // roots lie close together).
            if (jumps == 2 && a.face == b.face)
                consider(a.face, i, j, 0.5f * (a.u + b.u), 0.5f * (a.v + b.v), solver_.params, true, best);
            // A pit whose two neighbours' surfaces both meet the ray at or behind
            // the pixel's hit is a concave corner (a groove, a fillet's foot seen
            // from outside: every concave edge's pixels), not a crack: a crack's
            // front surface continues over the gap, so at least one of them meets
            // the ray in front, outside its trim. Searching further there found
            // nothing (1 nearer hit in 1,757 such pits per frame of the cylinder
            // block, 12,890 solves) and cost a quarter of its frame.
            const bool corner = crossing[0] >= p.t - nearer_ && crossing[1] >= p.t - nearer_;
            if (jumps == 2 && !corner) {
                pit = true;
                continued |= (cont[0] && b.face != p.face) || (cont[1] && a.face != p.face);
                own_face_jump |= (!cont[0] && a.face == p.face) || (!cont[1] && b.face == p.face);
            }
        }
        if (pit && best.face == p.face && best.t == p.t) fill_pit(i, j, continued && !own_face_jump, best);
        if (best.face == p.face && best.t == p.t) return false;
        out = best;
        return true;
    }

private:
    // Whether hit p, with neighbour n on its face, has the pair's other
    // neighbour a sheet gap behind on the same face, (u, v) jumping (kUvJump2:
    // a steep smooth sheet steps more in depth, but evenly): the silhouette of
    // a face folded over itself (step/bug29715_slow.stp seen edge-on). There
    // the ray can cross the near sheet twice and the map's start lead to the
    // farther root; the nearer lies past p's (u, v), on along n's step to it.
    // (With any face behind, i.e. at every silhouette, it cost 5-70 % of the
    // frame on 10 models and changed pixels only of that file.)
    bool fold_edge(const PixelHit& p, const PixelHit& n, const PixelHit& behind) const {
        return p.face && n.face == p.face && behind.face == p.face && behind.t > p.t + sheet_gap(p.t) &&
               uv_dist2(behind, p) > kUvJump2 * uv_dist2(n, p);
    }
    bool fold_edge(size_t k, size_t a, size_t b) const {
        return fold_edge(hits_[k], hits_[a], hits_[b]) || fold_edge(hits_[k], hits_[b], hits_[a]);
    }
    // Whether the pixel's hit p continues the sheet of its neighbour n's hit
    // and of the hit beyond n, pixel (fi, fj): all three on one face, with p
    // where n and the next pixel extrapolate it, in (u, v) and in depth. Such
    // a pixel is a pit because of its other side: most often the edge of an
    // occluder in front of a face that slopes towards the eye (three quarters
    // of a cylinder block's pits). Two sheets of one face closer than a pixel
    // footprint still pass (a fold of the duck), so a solve from n is kept.
    bool continues(const PixelHit& p, const PixelHit& n, int fi, int fj) const {
        if (n.face != p.face || !c_.in_frame(fi, fj)) return false;
        const PixelHit& f = hits_[c_.map.index(fi, fj)];
        if (f.face != p.face) return false;
        const double du = double(p.u) - n.u, dv = double(p.v) - n.v;
        const double fu = double(n.u) - f.u, fv = double(n.v) - f.v;
        const double su = du - fu, sv = dv - fv;  // the second difference
        return su * su + sv * sv <= kUvSmooth2 * (fu * fu + fv * fv) &&
               std::fabs(p.t - 2 * n.t + f.t) <= sheet_gap(p.t);
    }
    // How far in front of a hit at distance t another sheet must lie to count as one.
    double sheet_gap(double t) const { return kSheetFootprints * c_.pixel_footprint(t); }
    // The depth along the view direction (the mesh's measure, MeshScreenPoints)
    // in front of which another sheet than a hit at distance t through sp lies.
    double depth_in_front(double t, ScreenPoint sp) const {
        return (t - sheet_gap(t)) / c_.camera.hit_distance_from_depth(1.0, sp);
    }
    // Solves face id at (i, j) from (u0, v0); keeps the hit if it is nearer than best.
    // Returns the solve's outcome.
    // `crossing`: as Solver::solve's.
    Outcome consider(uint32_t id, int i, int j, float u0, float v0, const NewtonParams& params, bool near,
                     PixelHit& best, double* crossing = nullptr) const {
        PixelHit h;
        const Outcome o = solver_.solve(id, i, j, u0, v0, params, near, h, crossing);
        if ((o == kConverged || o == kNearTrim) && h.t < best.t - nearer_) best = h;
        return o;
    }
    // A pit that the pair's own starts did not fill, tried further with the
    // robust Newton (clamp-and-continue at borders, backtracking), in order of
    // cost until a nearer hit turns up, inside a trim only: a hit in the trim
    // band here makes the pixel a pit for its neighbours in turn, and the
    // peeling passes would spread the band over the face behind, a pixel at a
    // time (it did, on a machine component, over 1.6 mm beyond a face's edge): from every 3x3 neighbour's converged
    // (u, v), from the pixel's own face's mesh in front of its hit (mesh_in_front),
    // from the 3x3's map starts (the map may show the nearer face next to
    // the pixel while the neighbours' hits lie on others), then the faces adjacent
    // to these that none of them shows: a face too thin for the map to show any
    // pixel of it here (a fillet or blend strip seen edge-on) lies in front,
    // between the faces it touches; last, any face near on screen in front of
    // the hit (screen_faces).
    // One start per face (the first in for_each_neighbour's order): the 3x3's
    // starts of one face lie on one sheet within a pixel or two and end at one
    // root; except on the pixel's own face (other_sheet_starts).
    // `edge_of_other_face`: the pixel is a pit only because its hit continues
    // one neighbour's sheet (continues()) while the other neighbour shows
    // another face, and no neighbour shows another sheet of the pixel's face:
    // the pixel lies by the edge of a face in front, and its own face's mesh
    // in front of the hit (mesh_in_front) is not searched. Where a neighbour
    // does show another sheet of it (a closed face seen through its near side:
    // the duck), it is. 3.5 of the 17 ms of the cylinder block's nearer-sheet
    // pass, with the same frames on 10 models x 2 views and the same full-frame
    // test results.
    void fill_pit(int i, int j, bool edge_of_other_face, PixelHit& best) const {
        const PixelHit p = best;
        auto found = [&] { return best.face != p.face || best.t != p.t; };
        uint32_t tried[kFaces3x3];
        int ntried = 0;
        auto once = [&](uint32_t id) {
            if (!id || id > c_.nfaces || std::find(tried, tried + ntried, id) != tried + ntried) return false;
            tried[ntried++] = id;
            return true;
        };
        for (int kind = 0; kind < 2 && !found(); ++kind) {
            for_each_neighbour(c_, i, j, 1, [&](int ni, int nj) {
                const size_t n = c_.map.index(ni, nj);
                if (ni == i && nj == j) return;
                if (kind == 0 && once(hits_[n].face))
                    consider(hits_[n].face, i, j, hits_[n].u, hits_[n].v, solver_.robust, false, best);
                if (kind == 1 && once(c_.map.face[n]))
                    consider(c_.map.face[n], i, j, c_.map.u[n], c_.map.v[n], solver_.robust, false, best);
            });
            if (kind == 0 && !found()) other_sheet_starts(i, j, best);
            if (kind == 0 && !edge_of_other_face && !found()) mesh_in_front(p.face, i, j, best);
        }
        // The map's own face at the pixel, where it is another than the hit's:
        // the primary solve from its map start failed; its mesh in front of the
        // hit within reach may start Newton on its root.
        const uint32_t own_map = c_.map.face[c_.map.index(i, j)];
        if (!found() && own_map != p.face && once(own_map)) mesh_in_front(own_map, i, j, best);
        if (!found()) adjacent_faces(i, j, best);
        if (!found() && !edge_of_other_face) screen_faces(i, j, best);
    }
    // The distinct faces of the 3x3 around pixel (i, j), hit or in the map, into
    // out (room for kFaces3x3); returns how many.
    static constexpr int kFaces3x3 = 2 * 9;
    int faces_3x3(int i, int j, uint32_t* out) const {
        int n = 0;
        for_each_neighbour(c_, i, j, 1, [&](int ni, int nj) {
            const size_t k = c_.map.index(ni, nj);
            for (const uint32_t id : {hits_[k].face, c_.map.face[k]})
                if (id && id <= c_.nfaces && std::find(out, out + n, id) == out + n) out[n++] = id;
        });
        return n;
    }
    // Any faces whose mesh comes within reach of pixel (i, j) on screen and
    // nearer to the eye than its hit, but those of the 3x3 (hit or in the map):
    // a face seen through a gap between faces that do not touch it, which the
    // map hides behind them and adjacency does not offer (a capsule's panel in
    // front of a pit whose 3x3 shows only the faces behind it, iges/marsCapsule.igs).
    // The last resort of a pit, as the rescue's D is of a hole: by the time the
    // pits of occluders' edges (edge_of_other_face) and concave corners are left
    // out, some 150 pixels of a cylinder block's frame get here, for ~1 ms.
    void screen_faces(int i, int j, PixelHit& best) const {
        uint32_t near[kFaces3x3];
        const int nn = faces_3x3(i, j, near);
        const ScreenPoint sp = c_.camera.pixel_screen(i, j);
        const double reach = c_.screen_distance(kPitFacePixels);
        MeshScreenPoints::FarFace faces[kMaxScreenFaces];
        const int nf = screen_points_.faces_near(sp, near, nn, faces, kMaxScreenFaces, reach * reach,
                                                 depth_in_front(best.t, sp));
        for (int q = 0; q < nf; ++q)
            for (int k = 0; k < faces[q].nstarts; ++k)
                consider(faces[q].id, i, j, static_cast<float>(faces[q].starts[k].x),
                         static_cast<float>(faces[q].starts[k].y), solver_.robust, false, best);
    }
    // Where the pixel's hit is a farther root of the very face its neighbours
    // show in front (a closed or folded face: the duck's body seen through its
    // near side; a dense face folded over itself), the pixel lies near that
    // sheet's silhouette, where Newton from one start runs over the fold to the
    // far root and from the next one stays on the near sheet: every neighbour
    // hit on the pixel's face that lies on another sheet (nearer by a pixel
    // footprint, as in find) is a robust start, until one gives a nearer root;
    // but the first hit on the face, which fill_pit's round of one start per
    // face has solved from already.
    void other_sheet_starts(int i, int j, PixelHit& best) const {
        const PixelHit p = best;
        const double sheet = sheet_gap(p.t);
        bool first = true;
        for_each_neighbour(c_, i, j, 1, [&](int ni, int nj) {
            const PixelHit& h = hits_[c_.map.index(ni, nj)];
            if ((ni == i && nj == j) || h.face != p.face) return true;
            if (first) {
                first = false;
                return true;
            }
            if (h.t < p.t - sheet) consider(h.face, i, j, h.u, h.v, solver_.robust, false, best);
            return best.face == p.face && best.t == p.t;  // on until found
        });
    }
    // Starts from the mesh of face id in front of the pixel's hit by a footprint.
    // Where no neighbour's hit starts Newton on the pixel's own face's nearer
    // sheet (its neighbours show other faces, or the same far sheet), that mesh
    // may: at a fold seen near its silhouette the near sheet's mesh, a chord,
    // stops short of pixels its surface covers, and the map shows the far sheet
    // there; the near root then lies by that mesh's frontmost part within
    // reach. A face folded many times puts several sheets in front, the map's
    // front one possibly a mesh sheet the exact ray passes by: each sheet
    // covering the pixel, front to back.
    void mesh_in_front(uint32_t id, int i, int j, PixelHit& best) const {
        const PixelHit p = best;
        const ScreenPoint sp = c_.camera.pixel_screen(i, j);
        const double reach = c_.screen_distance(kPitFacePixels);
        const double max_depth = depth_in_front(p.t, sp);
        Vec2 start;
        double depth = 0;
        auto from = [&](Vec2 uv) {
            consider(id, i, j, static_cast<float>(uv.x), static_cast<float>(uv.y), solver_.robust, false, best);
            return best.face != p.face || best.t != p.t;
        };
        if (screen_points_.frontmost_point(id, sp, reach * reach, start, depth) && depth < max_depth &&
            from(start))
            return;
        Vec2 starts[kMaxSheetsInFront];
        const int n = screen_points_.starts_in_front(id, sp, reach * reach, max_depth, starts, kMaxSheetsInFront);
        for (int k = 0; k < n; ++k)
            if (from(starts[k])) return;
    }
    // The faces adjacent to those of the 3x3 around pixel (i, j), hit or in the
    // map (PreparedFace::adjacent), that none of them shows, from their mesh
    // starts; failing those, the faces adjacent to those whose surface the ray
    // crosses outside their trim (the ray passes beyond that face's edge, where a
    // face joining it there may lie in front: a Russian part's flange behind a
    // thin face, step/bug31670_russian.stp). Both rings only within reach on screen.
    void adjacent_faces(int i, int j, PixelHit& best) const {
        uint32_t near[kFaces3x3 + kMaxAdjacentFaces];
        int nn = faces_3x3(i, j, near);
        const ScreenPoint sp = c_.camera.pixel_screen(i, j);
        // A face in front of the pixel covers it on screen: its mesh comes within
        // the mesh's deflection of the pixel centre, well inside kPitFacePixels.
        const double reach = c_.screen_distance(kPitFacePixels);
        const PixelHit p = best;
        uint32_t crossed[kMaxAdjacentFaces];  // the first ring's faces crossed outside their trim
        int nc = 0;
        MeshScreenPoints::FarFace faces[kMaxAdjacentFaces];
        const int nf = screen_points_.adjacent_far_faces(near, nn, sp, faces, kMaxAdjacentFaces, reach * reach);
        for (int q = 0; q < nf; ++q) {
            bool outside = false;
            for (int k = 0; k < faces[q].nstarts; ++k)
                outside |= consider(faces[q].id, i, j, static_cast<float>(faces[q].starts[k].x),
                                    static_cast<float>(faces[q].starts[k].y), solver_.robust, false, best) == kTrimmed;
            if (outside) crossed[nc++] = faces[q].id;
            near[nn++] = faces[q].id;
        }
        if (!nc || best.face != p.face || best.t != p.t) return;
        const int nf2 = screen_points_.adjacent_far_faces(crossed, nc, sp, faces, kMaxAdjacentFaces, reach * reach);
        for (int q = 0; q < nf2; ++q) {
            if (std::find(near, near + nn, faces[q].id) != near + nn) continue;  // tried already
            for (int k = 0; k < faces[q].nstarts; ++k)
                consider(faces[q].id, i, j, static_cast<float>(faces[q].starts[k].x),
                         static_cast<float>(faces[q].starts[k].y), solver_.robust, false, best);
        }
    }
    const FrameContext& c_;
    const Solver& solver_;
    const PixelArray<PixelHit>& hits_;
    const PixelArray<double>& depth_;
    const MeshScreenPoints& screen_points_;
    double spike_ = 0, nearer_ = 0;
};

}  // namespace

uint64_t nearer_sheet_pass(const FrameContext& c, const Solver& solver, const MeshScreenPoints& screen_points,
                           FrameBuffers& b) {
    const NearerSheet nearer(c, solver, screen_points, b);
    const int W = c.width;
    // The first pass examines every pixel; replacements are collected per row
    // (almost always none) and applied between passes: no frame-sized buffer for
    // a handful of pixels. Later passes examine only the 4-neighbours of those the
    // last pass changed (all 8: 7-19 % more solves here, most of them repeats).
    std::vector<std::vector<Update>> row_updates(c.height);
    parallel_rows(c, false, [&](int j) {
        for (int i = 0; i < W; ++i) {
            PixelHit h;
            if (nearer.maybe_spike(i, j) && nearer.find(i, j, h)) row_updates[j].push_back({c.map.index(i, j), h});
        }
    });
    std::vector<Update> updates;
    for (const std::vector<Update>& r : row_updates) updates.insert(updates.end(), r.begin(), r.end());
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
    }
    // The last pass's finds are nearer hits on their own rays like any other:
    // kept, though their neighbours are not examined again.
    for (const Update& u : updates) b.set(u.k, u.hit);
    return replaced + updates.size();
}

}  // namespace nurbsrt
