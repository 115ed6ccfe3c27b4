// The nearer-sheet pass's searches for a face in front of a pixel's hit that
// none of its neighbours' starts reaches (nearer_sheet.h): at a pit, the 3x3's
// faces robustly, the pixel's own face's mesh in front, adjacent faces and faces
// near on screen; at a step, the diagonal neighbours' faces and the faces beyond
// the edge of the face in front.
#include <algorithm>
#include <cmath>
#include <utility>

#include "renderer/frame/mesh_screen_points.h"
#include "renderer/passes/nearer_sheet.h"

namespace nurbsrt {

namespace {

// A face in front of a pit covers it on screen: its mesh comes within the
// mesh's deflection of the pixel centre, well inside 2 pixels.
constexpr double kPitFacePixels = 2.0;
// Faces adjacent to a pit's 3x3 that are tried when none of the 3x3's faces
// fills it; a thin face in front touches one of them. 12 bounds the cost at a
// vertex where many faces meet (per ring of adjacent_faces); the faces adjacent
// to a pit's are sorted nearest first, so the rest are farther.
constexpr NearFaceBound kPitAdjacentFaces{12, kPitFacePixels};
// Faces near on screen (screen_faces) tried at a pit nothing else filled, the
// nearest first: as many as the rescue's last resort tries at a hole.
constexpr NearFaceBound kPitScreenFaces{4, kPitFacePixels};
// Sheets of the pixel's own face in front of its hit that are tried, nearest
// to the eye first: a face folded over itself many times (a dense coil
// seen edge-on) puts several there, and the map's front one may be a mesh
// sheet the exact ray passes by.
constexpr int kMaxSheetsInFront = 4;
// The faces a step tries at the most: its 4 neighbours' (tried by the pair
// tests), its 4 diagonal neighbours' and its 3x3's map faces (beyond these
// the rest are solved without being remembered, a repeat at worst).
constexpr int kStepFaces = 12;
// How far from a thin face's pixel its face is tried (thin_tries): a strip
// narrower than a pixel that runs diagonally covers a pixel centre every one to
// three pixels, so the pixels between lie within 2 of one of its map pixels.
constexpr int kThinReach = 2;
// thin_face_tries: the pixels within this of a thin face's mesh on screen. The
// map mesh's chords lie within its deflection of the surface, under a pixel at
// the views rendered; half a pixel more for the pixel centre's offset.
constexpr double kThinFacePixels = 1.5;
// ... and not for a face whose mesh's triangles' screen boxes hold more pixel
// centres than this (a face covering much of the frame, which a few thin
// pixels made a candidate: the map shows it anyway).
constexpr size_t kMaxThinFaceTested = size_t(1) << 16;

}  // namespace

bool NearerSheet::thin_tries(int i, int j, std::vector<ThinTry>& out) const {
    if (i <= 0 || j <= 0 || i + 1 >= c_.width || j + 1 >= c_.height) return false;  // no pairs
    const size_t k = c_.map.index(i, j);
    const double d = depth_[k];
    if (!(d < HUGE_VAL)) return false;
    const double behind = d + sheet_gap(d);
    const PixelHit& p = hits_[k];
    // A pair on other faces (hits: a thin face against the background is the
    // rescue's), one of them behind the hit: the thin face lies in front of
    // that one, beside it or in front of the other (a strip between a face in
    // front and a face behind, as a ring between a wall and its base).
    auto other = [&](size_t n) { return depth_[n] < HUGE_VAL && hits_[n].face != p.face; };
    auto thin = [&](size_t a, size_t b) { return other(a) && other(b) && (depth_[a] > behind || depth_[b] > behind); };
    if (!thin(k - 1, k + 1) && !thin(k - c_.width, k + c_.width)) return false;
    for_each_neighbour(c_, i, j, kThinReach, [&](int ni, int nj) {
        const int reach = std::max(std::abs(ni - i), std::abs(nj - j));
        if (reach + std::min(std::abs(ni - i), std::abs(nj - j)) <= 1) return;  // the pixel, its 4-neighbours
        const size_t n = c_.map.index(ni, nj);
        if (depth_[n] > behind && depth_[n] < HUGE_VAL && hits_[n].face != p.face)
            out.push_back({n, p.face, p.u, p.v, reach});
    });
    return true;
}

void NearerSheet::thin_face_tries(uint32_t face, std::vector<ThinTry>& out) const {
    std::vector<MeshScreenPoints::MeshPixel> pixels;
    // Pixels on the background are the rescue's; those on the face itself need nothing.
    if (!screen_points_.pixels_near(face, kThinFacePixels, kMaxThinFaceTested, hits_, depth_, kSheetFootprints, pixels))
        return;
    for (const MeshScreenPoints::MeshPixel& m : pixels) {
        const PixelHit& h = hits_[m.k];
        const int i = static_cast<int>(m.k % c_.width), j = static_cast<int>(m.k / c_.width);
        if (m.depth < depth_in_front(h.t, c_.camera.pixel_screen(i, j)))
            out.push_back({m.k, face, static_cast<float>(m.uv.x), static_cast<float>(m.uv.y), kThinReach + 1});
    }
}

bool NearerSheet::solve(const ThinTry& t, PixelHit& out) const {
    const PixelHit& p = hits_[t.k];
    PixelHit best = p;
    // Plain Newton, as for find's pairs: the start lies a pixel or two away on
    // the thin face. The robust one costs more and found next to nothing more.
    consider(t.face, static_cast<int>(t.k % c_.width), static_cast<int>(t.k / c_.width), t.u, t.v, solver_.params,
             false, best);
    if (best.face == p.face && best.t == p.t) return false;
    out = best;
    return true;
}

void NearerSheet::diagonal_faces(int i, int j, PixelHit& best) const {
    const PixelHit p = best;
    uint32_t tried[kStepFaces];
    int ntried = 0;
    for (const auto& [di, dj] : {std::pair{-1, 0}, std::pair{1, 0}, std::pair{0, -1}, std::pair{0, 1}})
        if (c_.in_frame(i + di, j + dj)) tried[ntried++] = hits_[c_.map.index(i + di, j + dj)].face;
    for (const auto& [di, dj] : {std::pair{-1, -1}, std::pair{1, -1}, std::pair{-1, 1}, std::pair{1, 1}}) {
        if (!c_.in_frame(i + di, j + dj)) continue;
        const PixelHit& h = hits_[c_.map.index(i + di, j + dj)];
        if (!h.face || h.face == p.face || std::find(tried, tried + ntried, h.face) != tried + ntried ||
            !(h.t < p.t - sheet_gap(p.t)))
            continue;
        tried[ntried++] = h.face;
        consider(h.face, i, j, h.u, h.v, solver_.robust, false, best);
        if (best.face != p.face || best.t != p.t) return;
    }
    for_each_neighbour(c_, i, j, 1, [&](int ni, int nj) {
        const size_t n = c_.map.index(ni, nj);
        const uint32_t id = c_.map.face[n];
        if (!id || id > c_.nfaces || id == p.face || std::find(tried, tried + ntried, id) != tried + ntried)
            return true;
        if (ntried < kStepFaces) tried[ntried++] = id;
        consider(id, i, j, c_.map.u[n], c_.map.v[n], solver_.robust, false, best);
        return best.face == p.face && best.t == p.t;
    });
}

void NearerSheet::faces_beyond_failed(int i, int j, const StepFronts& fronts, PixelHit& best) const {
    // Not where Newton left the face's parameter box (see the header).
    auto stalled = [](const StepFronts::Failed& f) { return f.how != kLeftDomain; };
    const auto failed = std::span(fronts.failed, fronts.nfailed);
    if (std::none_of(failed.begin(), failed.end(), stalled)) return;
    const PixelHit p = best;
    const double in_front = p.t - sheet_gap(p.t);
    // The 4-neighbours' faces, then (first_try) the whole 3x3's.
    uint32_t side_faces[4];
    int n4 = 0;
    for (const auto& [di, dj] : {std::pair{-1, 0}, std::pair{1, 0}, std::pair{0, -1}, std::pair{0, 1}})
        if (c_.in_frame(i + di, j + dj)) side_faces[n4++] = hits_[c_.map.index(i + di, j + dj)].face;
    TriedFaces tried;
    for (const StepFronts::Failed& f : failed) {
        if (!stalled(f)) continue;
        for (int k = -kRingSide / 2; k <= kRingSide / 2; ++k) {
            const int ni = i + 2 * f.di + k * f.dj, nj = j + 2 * f.dj + k * f.di;
            if (!c_.in_frame(ni, nj)) continue;
            const PixelHit& h = hits_[c_.map.index(ni, nj)];
            if (!h.face || h.face == p.face || !(h.t < in_front) ||
                std::find(side_faces, side_faces + n4, h.face) != side_faces + n4 || !first_try(tried, i, j, h.face))
                continue;
            consider(h.face, i, j, h.u, h.v, solver_.robust, false, best);
            if (best.face != p.face || best.t != p.t) return;
        }
    }
}

void NearerSheet::fill_pit(int i, int j, bool edge_of_other_face, PixelHit& best) const {
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
    if (!found() && !edge_of_other_face) adjacent_faces(i, j, best);
    if (!found() && !edge_of_other_face) screen_faces(i, j, best);
}

int NearerSheet::faces_3x3(int i, int j, uint32_t* out) const {
    int n = 0;
    for_each_neighbour(c_, i, j, 1, [&](int ni, int nj) {
        const size_t k = c_.map.index(ni, nj);
        for (const uint32_t id : {hits_[k].face, c_.map.face[k]})
            if (id && id <= c_.nfaces && std::find(out, out + n, id) == out + n) out[n++] = id;
    });
    return n;
}

void NearerSheet::screen_faces(int i, int j, PixelHit& best) const {
    uint32_t near[kFaces3x3];
    const int nn = faces_3x3(i, j, near);
    const ScreenPoint sp = c_.camera.pixel_screen(i, j);
    MeshScreenPoints::FarFace faces[kPitScreenFaces.max_faces];
    const int nf = screen_points_.faces_near(sp, near, nn, faces, kPitScreenFaces, depth_in_front(best.t, sp));
    for (int q = 0; q < nf; ++q) from_mesh_starts(faces[q], i, j, best);
}

void NearerSheet::other_sheet_starts(int i, int j, PixelHit& best) const {
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

void NearerSheet::mesh_in_front(uint32_t id, int i, int j, PixelHit& best) const {
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
    if (screen_points_.frontmost_point(id, sp, reach * reach, start, depth) && depth < max_depth && from(start)) return;
    Vec2 starts[kMaxSheetsInFront];
    const int n = screen_points_.starts_in_front(id, sp, reach * reach, max_depth, starts, kMaxSheetsInFront);
    for (int k = 0; k < n; ++k)
        if (from(starts[k])) return;
}

void NearerSheet::adjacent_faces(int i, int j, PixelHit& best) const {
    uint32_t near[kFaces3x3 + kPitAdjacentFaces.max_faces];
    int nn = faces_3x3(i, j, near);
    const ScreenPoint sp = c_.camera.pixel_screen(i, j);
    const PixelHit p = best;
    uint32_t crossed[kPitAdjacentFaces.max_faces];  // the first ring's faces crossed outside their trim
    int nc = 0;
    MeshScreenPoints::FarFace faces[kPitAdjacentFaces.max_faces];
    const int nf = screen_points_.adjacent_far_faces(near, nn, sp, faces, kPitAdjacentFaces);
    for (int q = 0; q < nf; ++q) {
        if (from_mesh_starts(faces[q], i, j, best)) crossed[nc++] = faces[q].id;
        near[nn++] = faces[q].id;
    }
    if (nc && best.face == p.face && best.t == p.t)
        beyond_edges(i, j, {crossed, crossed + nc}, {near, near + nn}, best);
}

void NearerSheet::faces_joining_failed(int i, int j, const StepFronts& fronts, PixelHit& best) const {
    const PixelHit p = best;
    const double in_front = p.t - sheet_gap(p.t);
    TriedFaces tried;
    int njoining = 0;
    const ScreenPoint sp = c_.camera.pixel_screen(i, j);
    for (const StepFronts::Failed& f : std::span(fronts.failed, fronts.nfailed)) {
        const PixelHit& front = hits_[c_.map.index(i + f.di, j + f.dj)];
        const std::vector<uint32_t>& joining = c_.prepared.faces()[front.face - 1].adjacent;
        // The block beyond the 3x3 on the step's side: 2..kJoiningReach pixels
        // out, kJoiningReach either way across.
        for (int along = 2; along <= kJoiningReach; ++along)
            for (int across = -kJoiningReach; across <= kJoiningReach; ++across) {
                const int ni = i + along * f.di + across * f.dj, nj = j + along * f.dj + across * f.di;
                if (!c_.in_frame(ni, nj)) continue;
                const PixelHit& h = hits_[c_.map.index(ni, nj)];
                // Between the face in front and the pixel's hit, joining the former.
                if (!h.face || h.face == p.face || !(h.t < in_front) || !(h.t > front.t) ||
                    !std::binary_search(joining.begin(), joining.end(), h.face) || !first_try(tried, i, j, h.face))
                    continue;
                MeshScreenPoints::FarFace far;
                far.id = h.face;
                far.nstarts = screen_points_.nearest_starts(h.face, sp, far.starts);
                from_mesh_starts(far, i, j, best);
                if (best.face != p.face || best.t != p.t || ++njoining == kMaxJoiningFaces) return;
            }
    }
}

bool NearerSheet::first_try(TriedFaces& tried, int i, int j, uint32_t id) const {
    if (tried.n < 0) tried.n = faces_3x3(i, j, tried.ids);
    if (std::find(tried.ids, tried.ids + tried.n, id) != tried.ids + tried.n) return false;
    tried.ids[tried.n++] = id;
    return true;
}

void NearerSheet::beyond_edges(int i, int j, std::span<const uint32_t> crossed, std::span<const uint32_t> tried,
                               PixelHit& best) const {
    const ScreenPoint sp = c_.camera.pixel_screen(i, j);
    MeshScreenPoints::FarFace faces[kPitAdjacentFaces.max_faces];
    const int nf = screen_points_.adjacent_far_faces(crossed.data(), static_cast<int>(crossed.size()), sp, faces,
                                                     kPitAdjacentFaces);
    for (int q = 0; q < nf; ++q)
        if (std::find(tried.begin(), tried.end(), faces[q].id) == tried.end()) from_mesh_starts(faces[q], i, j, best);
}

bool NearerSheet::from_mesh_starts(const MeshScreenPoints::FarFace& f, int i, int j, PixelHit& best) const {
    bool outside = false;
    for (int k = 0; k < f.nstarts; ++k)
        outside |= consider(f.id, i, j, static_cast<float>(f.starts[k].x), static_cast<float>(f.starts[k].y),
                            solver_.robust, false, best) == kTrimmed;
    return outside;
}

}  // namespace nurbsrt
