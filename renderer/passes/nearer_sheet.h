// The nearer-sheet pass's search for a nearer hit of one pixel (passes.h,
// nearer_sheet_pass): the spike, step and silhouette tests and the solves from
// the neighbours' starts (pass_nearer.cpp), and the searches for a face in front
// that no neighbour's start reaches (nearer_sheet_search.cpp). Internal to the
// renderer.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <span>
#include <utility>
#include <vector>

#include "renderer/frame/frame.h"
#include "renderer/frame/mesh_screen_points.h"
#include "renderer/frame/pixel_solver.h"

namespace nurbsrt {

// A pixel deeper than this many pixel footprints behind both of its pair is off
// their sheet: on one smooth sheet the second difference of depth is about a
// footprint squared over the curvature radius, far below one footprint except
// where the sheet is seen almost edge-on (a wasted re-solve there, never a wrong hit).
constexpr double kSheetFootprints = 1.0;
// unlinked_end's largest step, in sheet gaps: an unsewn continuation of a face
// lies about as deep as the face at its edge; a larger step is a silhouette.
constexpr double kUnlinkedStepGaps = 4.0;

class NearerSheet {
public:
    NearerSheet(const FrameContext& c, const Solver& solver, const MeshScreenPoints& screen_points,
                const FrameBuffers& b);
    // Whether find(i, j) can find anything: the pixel is a spike against one of
    // its pairs (on depths alone), a fold's edge, or a silhouette a sheet gap
    // behind the pair's other pixel. Read by the first pass for every pixel.
    // `thin`: whether thin_tries may apply (a 4-neighbour a sheet gap behind).
    bool maybe_spike(int i, int j, bool& thin) const;
    // A nearer hit for pixel (i, j) than its current one, if any.
    bool find(int i, int j, PixelHit& out) const;

    // A solve of a thin face at a pixel near one of its hits (thin_tries).
    struct ThinTry {
        size_t k;       // the pixel tried
        uint32_t face;  // the thin face, started from its hit's (u, v)
        float u, v;
        int reach;  // how far that hit lies (pixels, Chebyshev): the nearest start first
    };
    // Where pixel (i, j)'s hit is a thin face's, a line of pixels in front of
    // other faces (the same test as maybe_spike's `thin`): the pixels within
    // kThinReach a sheet gap behind it on other faces, to be solved on its face
    // from its (u, v). A face narrower than a pixel running diagonally covers only
    // every second or third pixel centre in the map, and the pixels between show
    // the face behind with no spike, step or pit to start a search.
    // Returns whether the pixel is a thin face's.
    bool thin_tries(int i, int j, std::vector<ThinTry>& out) const;
    // A thin face's tries over its whole mesh: the pixels within kThinFacePixels
    // of its mesh on screen where its frontmost mesh point lies a sheet gap in
    // front of the pixel's hit. Along a row or column a thin face's map pixels can
    // be far apart or missing, since mesh chords sag by up to the deflection.
    // Triangles hidden behind the hit at their centroid's pixel are skipped.
    void thin_face_tries(uint32_t face, std::vector<ThinTry>& out) const;
    // Solves a ThinTry; true, with out, where it is nearer than the pixel's hit.
    bool solve(const ThinTry& t, PixelHit& out) const;

private:
    // What find learnt at the steps around a pixel (one neighbour in front, on
    // another face) from the solve on the face in front, at most one per pair.
    struct StepFronts {
        // Faces crossed outside their trim in front of the hit (the ray passes
        // beyond their edge); room for the pixel's own face (beyond_edges).
        uint32_t crossed[3];
        int ncrossed = 0;
        // The steps (di, dj to the neighbour in front) where Newton failed, and how.
        struct Failed {
            int di, dj;
            Outcome how;
        } failed[2];
        int nfailed = 0;
        bool unlinked = false;  // the face in front ends unlinked (unlinked_end)
    };
    // At a step that its 4-neighbours' faces did not fill: the faces that only
    // diagonal neighbours show a sheet gap in front of the hit, from their hits,
    // then the 3x3's map faces not tried yet, from the map's starts, robustly. A
    // strip narrower than a pixel can touch the ray while its map pixels run
    // diagonally past it, or while its own solves there failed.
    void diagonal_faces(int i, int j, PixelHit& best) const;
    // At a step where Newton diverged or stalled on the face in front (no crossing
    // outside its trim for beyond_edges to follow): the faces hit in front of the
    // pixel's hit two pixels away on that side (kRingSide pixels centred on the
    // step's line) that the 3x3 does not show, i.e. a blend a pixel or two wide
    // between the two faces. Not where Newton left the parameter box (the face
    // ends there; those steps cost much and found nothing). See docs/BENCHMARKS.md.
    static constexpr int kRingSide = 3;
    void faces_beyond_failed(int i, int j, const StepFronts& fronts, PixelHit& best) const;
    // At a step where Newton failed on the face in front (any way), the faces
    // joining it (PreparedFace::adjacent) hit between it and the pixel's hit in
    // the block beyond the 3x3 on the step's side (2 to kJoiningReach pixels out,
    // kJoiningReach either way): a blend strip hidden behind the front face's edge
    // but for a few pixels along it. Solved from its mesh's starts at the pixel,
    // not from those pixels' hits: a blend seen edge-on is crossed twice, and a
    // start along it can lead to the farther crossing. At most kMaxJoiningFaces.
    static constexpr int kJoiningReach = 3;
    static constexpr int kMaxJoiningFaces = 8;
    void faces_joining_failed(int i, int j, const StepFronts& fronts, PixelHit& best) const;
    // At a silhouette pixel, the 4-neighbours on other faces in front of its hit
    // (by more than the spike threshold) that find's silhouette test did not try,
    // each from its own (u, v), robustly, until one is nearer: a face whose rim
    // meets the silhouette, its pixels beside the silhouette rather than across it.
    void rim_faces_in_front(int i, int j, PixelHit& best) const;
    // The diagonal neighbours' hits in front of the pixel's by a sheet gap (with
    // own_face, only those on the pixel's face), each from its own (u, v),
    // robustly, until one is nearer.
    void diagonal_starts(int i, int j, bool own_face, PixelHit& best) const;
    // The hits of the neighbours at `offsets` (di, dj) that accept(di, dj,
    // pixel's hit, neighbour's hit) takes, in order, each solved at the pixel
    // from its own (u, v), robustly, until one is nearer (the two above).
    template <class Accept>
    void from_neighbour_hits(int i, int j, std::span<const std::pair<int, int>> offsets, Accept accept,
                             PixelHit& best) const;
    // Whether hit p, with neighbour n on its face, has the pair's other neighbour
    // a sheet gap behind on the same face with (u, v) jumping (kUvJump2: a steep
    // smooth sheet steps more in depth, but evenly): the silhouette of a face
    // folded over itself. There the ray can cross the near sheet twice and the
    // map's start lead to the farther root; the nearer lies past p's (u, v), on
    // along n's step. Only on the same face: with any face behind it was costly.
    bool fold_edge(const PixelHit& p, const PixelHit& n, const PixelHit& behind) const;
    bool fold_edge(size_t k, size_t a, size_t b) const;
    // At a silhouette pixel behind another face's neighbour that did not fill it:
    // a rescued pixel's own face may have a nearer sheet that no neighbour shows
    // (a rim face the rescue filled from its farther root), searched in its mesh
    // in front (mesh_in_front). Likewise a primary hit whose face no 8-neighbour
    // shows: the map's start lies on its mesh's edge, a chord that barely reaches
    // the pixel, from where Newton can run over the rim to the far root. Not at
    // every primary hit (too costly for what it finds); never on a plane.
    void rim_own_mesh(int i, int j, PixelHit& best) const;
    // Whether no 8-neighbour of pixel (i, j) shows the face its hit is on but
    // at a distance under nearer_than (-HUGE_VAL: none at all; a sheet gap in
    // front of the hit: none on the hit's own sheet).
    bool alone_on_face(int i, int j, double nearer_than) const;
    // At a silhouette pixel beside its own face's other sheet in front, that
    // sheet's start failing, with no 8-neighbour on the pixel's sheet
    // (alone_on_face): the ray may clip the face by its rim, and the map's start
    // led Newton to the exit. The map's (u, v) lies on the mesh chord between the
    // two roots, so the entry lies beyond it from the exit: robust starts along
    // that line (kAcrossRimSteps) until one is nearer.
    void across_own_rim(int i, int j, PixelHit& best) const;
    // Whether the pixel's hit p continues the sheet of its neighbour n's hit and
    // of the hit beyond n, pixel (fi, fj): all three on one face, p where n and
    // the next extrapolate it in (u, v) and depth. Such a pit is one because of its
    // other side, most often an occluder's edge in front of a face sloping towards
    // the eye. Two sheets of one face closer than a footprint still pass, so a
    // solve from n is kept.
    bool continues(const PixelHit& p, const PixelHit& n, int fi, int fj) const;
    // One side of the pair through pixel (i, j) is background, its neighbour
    // (ni, nj) a hit nearer by more than a footprint: at a fold's silhouette, or
    // where the ray crosses a curved face twice near its rim (a fillet, a sphere)
    // and the map's start led to the farther root. Solved from that neighbour
    // unless the pixel continues its sheet (continues(): a surface turning away
    // steps more in depth towards its silhouette, evenly, on one sheet).
    void silhouette_pair(int i, int j, int ni, int nj, PixelHit& best) const;
    // At a step, whether the neighbour n's face in front (not p's) ends at the
    // pixel with no face linked there: solved from n, its surface is met outside
    // its trim or Newton leaves its parameter box (o), and the face has no
    // adjacent faces (PreparedFace::adjacent; an unsewn IGES face shares no mesh
    // node). beyond_edges needs adjacency; here a piece continuing the face in
    // front may lie between it and the hit. Only for steps of more than one
    // footprint (smaller ones are a slope across an unsewn seam) and below
    // kUnlinkedStepGaps, which keep the screen search rare.
    bool unlinked_end(const PixelHit& p, const PixelHit& n, Outcome o) const;
    // How far in front of a hit at distance t another sheet must lie to count as one.
    double sheet_gap(double t) const { return kSheetFootprints * c_.pixel_footprint(t); }
    // The depth along the view direction (the mesh's measure, MeshScreenPoints)
    // in front of which another sheet than a hit at distance t through sp lies.
    double depth_in_front(double t, ScreenPoint sp) const;
    // Solves face id at (i, j) from (u0, v0); keeps the hit if it is nearer than best.
    // Returns the solve's outcome.
    // `crossing`: as Solver::solve's.
    Outcome consider(uint32_t id, int i, int j, float u0, float v0, const NewtonParams& params, bool near,
                     PixelHit& best, double* crossing = nullptr) const;
    // A pit that the pair's own starts did not fill, tried further with the
    // robust Newton (clamp-and-continue, backtracking), cheapest first until a
    // nearer hit turns up, inside a trim only (a hit in the trim band would make
    // the pixel a pit for its neighbours, and the peeling would spread the band
    // over the face behind a pixel at a time): from every 3x3 neighbour's (u, v),
    // from the pixel's own face's mesh in front of its hit (mesh_in_front), from
    // the 3x3's map starts, then the faces adjacent to these that none shows (a
    // strip too thin for the map, between the faces it touches), last any face
    // near on screen in front of the hit (screen_faces). One start per face: the
    // 3x3's starts of one face lie on one sheet and end at one root, except on the
    // pixel's own face (other_sheet_starts).
    // `edge_of_other_face`: the pixel is a pit only because its hit continues one
    // neighbour's sheet (continues()) while the other shows another face, and no
    // neighbour shows another sheet of the pixel's face: it lies by the edge of a
    // face in front, and mesh_in_front, adjacent_faces and screen_faces are
    // skipped (they found nothing there at a large share of the pass's cost).
    void fill_pit(int i, int j, bool edge_of_other_face, PixelHit& best) const;
    // The distinct faces of the 3x3 around pixel (i, j), hit or in the map, into
    // out (room for kFaces3x3); returns how many.
    static constexpr int kFaces3x3 = 2 * 9;
    int faces_3x3(int i, int j, uint32_t* out) const;
    // The faces a search beyond the 3x3 (faces_beyond_failed,
    // faces_joining_failed) has tried at one pixel: the 3x3's, which the
    // searches before tried, read at the first face that needs the test (most
    // calls have none), then those it adds (at most kMaxBeyondFaces).
    static constexpr int kMaxBeyondFaces = 8;
    static_assert(2 * kRingSide <= kMaxBeyondFaces && kMaxJoiningFaces <= kMaxBeyondFaces);
    struct TriedFaces {
        uint32_t ids[kFaces3x3 + kMaxBeyondFaces];
        int n = -1;  // -1: the 3x3's not read yet
    };
    // Whether face id is new to `tried` at pixel (i, j), recording it if so.
    bool first_try(TriedFaces& tried, int i, int j, uint32_t id) const;
    // Any faces whose mesh comes within reach of pixel (i, j) on screen nearer
    // than its hit, but those of the 3x3: a face seen through a gap between faces
    // that do not touch it, which the map hides and adjacency does not offer. The
    // last resort of a pit, as the rescue's D is of a hole; rarely reached.
    void screen_faces(int i, int j, PixelHit& best) const;
    // Where the pixel's hit is a farther root of the face its neighbours show in
    // front (a closed or folded face seen through its near side), the pixel lies
    // near that sheet's silhouette, where Newton from one start runs over the fold
    // and from the next stays on the near sheet: every neighbour hit on the
    // pixel's face on another sheet (a footprint nearer, as in find) is a robust
    // start until one gives a nearer root, but the first, which fill_pit's round
    // of one start per face has solved from already.
    void other_sheet_starts(int i, int j, PixelHit& best) const;
    // Starts from the mesh of face id in front of the pixel's hit by a footprint.
    // Where no neighbour's hit starts Newton on the pixel's own face's nearer
    // sheet (its neighbours show other faces, or the same far sheet), that mesh
    // may: at a fold seen near its silhouette the near sheet's mesh, a chord,
    // stops short of pixels its surface covers, and the map shows the far sheet
    // there; the near root then lies by that mesh's frontmost part within
    // reach. A face folded many times puts several sheets in front, the map's
    // front one possibly a mesh sheet the exact ray passes by: each sheet
    // covering the pixel, front to back.
    void mesh_in_front(uint32_t id, int i, int j, PixelHit& best) const;
    // The faces adjacent to those of the 3x3 around pixel (i, j), hit or in the
    // map (PreparedFace::adjacent), that none of them shows, from their mesh
    // starts; failing those, the faces adjacent to those whose surface the ray
    // crosses outside their trim (a face joining it beyond that edge may lie in
    // front). Both only within reach on screen.
    void adjacent_faces(int i, int j, PixelHit& best) const;
    // The faces adjacent to `crossed` (faces whose surface the ray crosses outside
    // their trim, so a face joining them beyond the edge, e.g. a fillet strip too
    // thin for the map, may lie in front; find adds the pixel's own face at a
    // step), within reach on screen, but those in `tried`; from their mesh
    // starts, robustly.
    void beyond_edges(int i, int j, std::span<const uint32_t> crossed, std::span<const uint32_t> tried,
                      PixelHit& best) const;
    // Solves face f.id from each of its mesh starts (robustly, keeping the
    // nearest hit in best); whether any ended outside its trim.
    bool from_mesh_starts(const MeshScreenPoints::FarFace& f, int i, int j, PixelHit& best) const;
    const FrameContext& c_;
    const Solver& solver_;
    const PixelArray<PixelHit>& hits_;
    const PixelArray<double>& depth_;
    const std::vector<uint8_t>& rescued_;
    const MeshScreenPoints& screen_points_;
    double spike_ = 0, nearer_ = 0;
};

// Inline: the first pass calls it for every pixel of the frame.
inline bool NearerSheet::maybe_spike(int i, int j, bool& thin) const {
    const size_t k = c_.map.index(i, j);
    const double d = depth_[k];
    thin = false;
    if (!(d < HUGE_VAL)) return false;
    const double gap = sheet_gap(d), behind = d + gap;
    auto spike_or_fold = [&](size_t a, size_t b) {
        const double near = std::min(depth_[a], depth_[b]), far = std::max(depth_[a], depth_[b]);
        return d > 0.5 * (near + far) + spike_ || (far == HUGE_VAL && near < d - gap) ||
               (far > behind && far < HUGE_VAL && fold_edge(k, a, b));
    };
    const bool row = i > 0 && i + 1 < c_.width, column = j > 0 && j + 1 < c_.height;
    if (row && column) {
        // thin_tries' test: a pair on other faces, one of them a hit behind.
        auto hit_behind = [&](size_t n) { return depth_[n] > behind && depth_[n] < HUGE_VAL; };
        auto thin_pair = [&](size_t a, size_t b) {
            return (hit_behind(a) || hit_behind(b)) && hits_[a].face != hits_[k].face && hits_[b].face != hits_[k].face;
        };
        const size_t w = static_cast<size_t>(c_.width);
        thin = thin_pair(k - 1, k + 1) || thin_pair(k - w, k + w);
    }
    return (row && spike_or_fold(k - 1, k + 1)) || (column && spike_or_fold(k - c_.width, k + c_.width));
}

}  // namespace nurbsrt
