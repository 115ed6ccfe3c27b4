// Accuracy of the direct NURBS renderer against an independent reference.
//
// For real CAD models (and a few generated fixtures) the whole pipeline runs as a
// user runs it: import_file -> named view -> render (`proposed`, and `martin` on a
// subset). A few thousand pixels, chosen with a fixed-seed RNG, are then re-cast
// as the SAME contract pixel ray (Camera::pixel_ray) against the ORIGINAL OCCT
// shape with IntCurvesFace_ShapeIntersector: it intersects the true surfaces
// (planes, cylinders, offset surfaces, ... as the file defines them), not our
// NURBS conversion, and trims with OCCT's own face classifier, so it shares no
// code with the renderer or with the importer's conversion and trim loops.
//
// Per sample: hit/miss, hit distance t and face id, ours vs OCCT.
//  * Samples within one pixel of a silhouette or trim edge (one of the 8 neighbours
//    in OUR face AOV carries a different id, background included) are excluded from
//    the criteria and reported separately ("edge band"): at an edge the pixel centre
//    may legitimately fall on either side within the trim-loop/intersector tolerances.
//    Exception: a pixel whose 8 neighbours all carry one and the same id different
//    from its own is an isolated speckle, not an edge, and stays IN the criteria
//    (otherwise the edge rule would hide exactly the single-pixel misses it should
//    catch). Conversely, our AOV cannot show a silhouette where a face occludes
//    itself (a fold: both sides carry the same id), nor an edge we drew in the wrong
//    place; so a sample that fails is also checked against the TRUE image: if one of
//    its 8 neighbours' OCCT rays differs in hit/face or jumps in t (near_true_edge),
//    it is within one pixel of a real edge and moves to the edge band (counted and
//    printed separately).
//  * Criteria on the non-edge samples:
//      hit/miss agreement >= 99.9 %;
//      where both hit, |t_ours - t_occt| <= 1e-6 x bbox diagonal on >= 99.9 %;
//      face id agrees (or a different face at the same t that our hit point lies on:
//      coincident faces / shared edges) on >= 99.9 %.
//  * Disputes are settled with BRepExtrema_DistShapeShape from the claimed hit point
//    to the claimed face (the intersector misses ~0.2 % of near roots on some
//    models, seen on grazing rays over folded B-spline faces). If our hit lies on our face and is nearer than OCCT's (or OCCT
//    has none), OCCT missed a root: "verified ours", not a failure. If OCCT's claimed
//    hit does not lie on its face, OCCT's answer is spurious: also not our failure.
// Printed per model, view and method (stdout and RecordProperty): samples, edge
// excluded, agreement, |dt|/diag percentiles 50/90/99/99.9/max, face mismatches,
// verified-ours counts, edge-band agreement, and the worst pixels of every failure
// with a diagnosis from the renderer's own parts (map start, Newton outcome from it
// and from the neighbours' hits, the nearest root from a start grid and its trim test).
#include <gtest/gtest.h>

#include <BRepBuilderAPI_MakeVertex.hxx>
#include <BRepExtrema_DistShapeShape.hxx>
#include <BRep_Tool.hxx>
#include <Precision.hxx>
#include <Standard_Failure.hxx>
#include <TopoDS.hxx>
#include <TopoDS_Vertex.hxx>
#include <gp_Pnt.hxx>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <limits>
#include <sstream>
#include <string>
#include <unordered_set>
#include <vector>

#include "core/split_mix.h"
#include "importer/importer.h"
#include "importer/occt_shape.h"
#include "importer/reference/reference_intersector.h"
#include "renderer/camera.h"
#include "renderer/solve/newton.h"
#include "renderer/map/preliminary_map.h"
#include "renderer/render.h"
#include "core/scene/scene.h"
#include "core/scene/trim.h"
#include "tests/support/fixtures.h"
#include "tests/support/occt_distance.h"

namespace {

namespace fs = std::filesystem;
namespace T = nurbsrt::test;
using T::at;
using T::dist_to_face;
using namespace nurbsrt;

constexpr double kInf = std::numeric_limits<double>::infinity();

// ---------------------------------------------------------------------------------
// Tolerances (each one's reason)
// ---------------------------------------------------------------------------------
// The accuracy bound on the hit distance, relative to the bbox diagonal.
// Our Z AOV is float: its quantization (2^-24 relative, t <= ~2 diagonals for the
// fitted named views) is ~1e-7 of the diagonal, an order below this bound, so
// reading t from the AOV does not eat the budget. We reconstruct the hit point from
// the same float t, which is likewise ~1e-7 x diag off along the ray.
constexpr double kDtRel = 1e-6;
// The pass rates: at most 1 failing sample per 1000.
constexpr int kPerMille = 1;
// "Our hit lies on the face": distance from the point to the (trimmed) face at most
// max(kOnFaceRel x diag, kOnFaceTolFactor x BRep_Tool::Tolerance(face)). The first
// term is the criterion's own precision (a point that agrees with OCCT to 1e-6 x
// diag along the ray cannot be asked to be closer to the face than that); the face
// tolerance is the precision the file's modeller guarantees for that face's
// geometry (points of the face are only defined to within it), times a margin of 4
// for the float t and DistShapeShape's own extrema precision. Both are far below a
// pixel (1/240 of the view ~ 2e-3 x diag), so a root on a different sheet of the
// surface or a point outside the trim can never pass.
constexpr double kOnFaceRel = 1e-6;
constexpr double kOnFaceTolFactor = 4.0;
// Tolerance given to IntCurvesFace_ShapeIntersector::Load: the 2D classification
// tolerance of its hits against the face boundary. Confusion (1e-7 mm) keeps its
// trimming sharp; the criteria only look at samples a pixel away from any edge.
const double kIntersectorTol = Precision::Confusion();
// Samples per view: near our hits (the object, dilated by kDilate pixels so that
// holes, speckles and the silhouette ring are included), plus from the whole image
// (to catch anything we miss entirely). With ~3000 samples, 99.9 % allows 2-3
// failing pixels. The budget is the intersector's speed (~1-10k rays/s on these
// models): 3000 rays per view keep the whole suite near 40 s.
constexpr int kSamplesNearHits = 2600;
constexpr int kSamplesWholeImage = 400;
constexpr int kDilate = 2;
// Cap on DistShapeShape settlements per view and method (each costs ~0.1-5 ms); a
// renderer so broken that it needs more fails the criteria anyway.
constexpr int kMaxSettlements = 400;
constexpr int kImageW = 320, kImageH = 240;

// ---------------------------------------------------------------------------------
// Parameters
// ---------------------------------------------------------------------------------
struct ViewSpec {
    const char* name;
    Projection projection;
};
struct AccCase {
    std::string name;     // gtest parameter name
    std::string fixture;  // a generated fixture, or
    std::string rel;      // a path under ../shared/models
    std::vector<ViewSpec> views;
    bool martin = false;  // also render with `martin`
};

std::vector<AccCase> cases() {
    const ViewSpec iso{"iso", Projection::perspective};
    auto ortho = [](const char* v) { return ViewSpec{v, Projection::orthographic}; };
    auto fixture = [&](const char* f, ViewSpec second, bool martin) {
        return AccCase{std::string("fixture_") + f, f, "", {iso, second}, martin};
    };
    auto shared = [&](const std::string& rel, ViewSpec second, bool martin) {
        return AccCase{T::sanitize_test_name(rel), "", rel, {iso, second}, martin};
    };
    return {
        fixture("box_with_holes", ortho("top"), true),
        fixture("sphere", ortho("front"), true),
        fixture("torus", ortho("top"), false),
        fixture("freeform_rational", ortho("front"), false),
        shared("step/bug27693_cornetta-step.stp", ortho("front"), true),
        shared("step/trj8_b1-ec-214.stp", ortho("top"), true),
        shared("step/as1-oc-214.stp", ortho("front"), false),
        shared("iges/bearing.iges", ortho("right"), false),
        shared("iges/hammer.iges", ortho("front"), false),
        shared("duck/duck_from_glscene.igs", ortho("left"), true),
        shared("step/linkrods.step", ortho("top"), false),
    };
}

// ---------------------------------------------------------------------------------
// Helpers
// ---------------------------------------------------------------------------------
using Rng = SplitMix64;

uint64_t hash_name(const std::string& s) {
    uint64_t h = 1469598103934665603ull;  // FNV-1a
    for (unsigned char c : s) h = (h ^ c) * 1099511628211ull;
    return h;
}

// Distinct pixel indices: kSamplesNearHits from the pixels within kDilate of one of
// our hits (the object, any holes and speckles in it, and a ring around its
// silhouette: where every kind of disagreement lives), kSamplesWholeImage from the
// whole image (a face we miss entirely).
std::vector<int> choose_samples(const RenderImage& im, uint64_t seed) {
    const int W = im.width, H = im.height;
    std::vector<uint8_t> near(static_cast<size_t>(W) * H, 0);
    for (int j = 0; j < H; ++j)
        for (int i = 0; i < W; ++i)
            if (im.face[static_cast<size_t>(j) * W + i] != 0)
                for (int b = std::max(0, j - kDilate); b <= std::min(H - 1, j + kDilate); ++b)
                    for (int a = std::max(0, i - kDilate); a <= std::min(W - 1, i + kDilate); ++a)
                        near[static_cast<size_t>(b) * W + a] = 1;
    std::vector<int> pool;
    for (size_t k = 0; k < near.size(); ++k)
        if (near[k]) pool.push_back(static_cast<int>(k));
    Rng rng{seed};
    std::unordered_set<int> seen;
    std::vector<int> out;
    auto draw = [&](int n, auto&& pick, int available) {
        const int want = std::min(n, available);
        for (int got = 0, tries = 0; got < want && tries < 50 * n; ++tries) {
            const int k = pick();
            if (seen.insert(k).second) out.push_back(k), ++got;
        }
    };
    if (!pool.empty())
        draw(
            kSamplesNearHits, [&] { return pool[static_cast<size_t>(rng.below(static_cast<int>(pool.size())))]; },
            static_cast<int>(pool.size()));
    draw(
        kSamplesWholeImage, [&] { return rng.below(W * H); }, W * H);
    return out;
}

// Within one pixel of an edge in our face AOV; an isolated speckle (all 8
// neighbours share one id different from the pixel's) is NOT an edge.
bool near_edge(const RenderImage& im, int i, int j) {
    const uint32_t c = im.face[static_cast<size_t>(j) * im.width + i];
    bool differs = false, uniform = true;
    int count = 0;
    uint32_t first = 0;
    for (int dj = -1; dj <= 1; ++dj)
        for (int di = -1; di <= 1; ++di) {
            if (!di && !dj) continue;
            const int a = i + di, b = j + dj;
            if (a < 0 || b < 0 || a >= im.width || b >= im.height) continue;
            const uint32_t n = im.face[static_cast<size_t>(b) * im.width + a];
            if (count++ == 0)
                first = n;
            else if (n != first)
                uniform = false;
            if (n != c) differs = true;
        }
    if (!differs) return false;
    return !(uniform && count == 8);
}

// The intersector's answer for one ray (importer/reference/reference_intersector.h).
using OcctHit = ReferenceHit;

enum class Verdict {
    both_miss,
    match,                   // both hit, |dt| within bound, same face
    face_coincident,         // both hit, |dt| within bound, other face; our point lies on ours
    verified_occt_missed,    // ours nearer (or OCCT none), our point on our face
    verified_occt_spurious,  // OCCT's claimed point not on its face; ours (if any) on ours
    fail_we_missed,          // OCCT hit on its face, we have none
    fail_our_spurious,       // we hit, OCCT none, our point not on our face
    fail_dt,                 // both hit, |dt| too large, not settled in our favour
    fail_face,               // same t, different face, our point not on our face
    unsettled,               // dispute beyond the settlement cap
    edge_disagree,           // edge band, hit/miss differ (reported, not judged)
};
const char* verdict_name(Verdict v) {
    switch (v) {
        case Verdict::both_miss:
            return "both_miss";
        case Verdict::match:
            return "match";
        case Verdict::face_coincident:
            return "face_coincident";
        case Verdict::verified_occt_missed:
            return "verified_ours(occt_missed_root)";
        case Verdict::verified_occt_spurious:
            return "verified_ours(occt_spurious)";
        case Verdict::fail_we_missed:
            return "FAIL_we_missed";
        case Verdict::fail_our_spurious:
            return "FAIL_our_spurious_hit";
        case Verdict::fail_dt:
            return "FAIL_dt";
        case Verdict::fail_face:
            return "FAIL_face";
        case Verdict::unsettled:
            return "FAIL_unsettled";
        case Verdict::edge_disagree:
            return "edge_band_disagree(not judged)";
    }
    return "?";
}
bool is_fail(Verdict v) {
    return v == Verdict::fail_we_missed || v == Verdict::fail_our_spurious || v == Verdict::fail_dt ||
           v == Verdict::fail_face || v == Verdict::unsettled;
}

struct Sample {
    int i = 0, j = 0;
    bool edge = false;
    bool edge_by_occt = false;  // failed, but within one pixel of an edge of OCCT's image
    uint32_t face = 0;          // ours
    double t = kInf;            // ours
    int iterations = 0;
    OcctHit occt;
    Verdict verdict = Verdict::both_miss;
    double d_ours = -1, d_occt = -1, d_ours_to_occt_face = -1;  // settlement distances (-1: not computed)
    double dt_rel() const { return std::fabs(t - occt.t); }
};

std::string sci(double x, int prec = 2) {
    std::ostringstream s;
    s << std::scientific << std::setprecision(prec) << x;
    return s.str();
}
std::string pct(long num, long den) {
    std::ostringstream s;
    s << std::fixed << std::setprecision(3) << (den ? 100.0 * static_cast<double>(num) / den : 100.0) << "%";
    return s.str();
}
double percentile(const std::vector<double>& sorted, double p) {
    if (sorted.empty()) return 0;
    const size_t k = static_cast<size_t>(std::ceil(p * static_cast<double>(sorted.size())));
    return sorted[std::min(sorted.size() - 1, k == 0 ? 0 : k - 1)];
}

// ---------------------------------------------------------------------------------
// The check of one render against the OCCT rays of its view
// ---------------------------------------------------------------------------------
struct Context {
    const Scene& scene;
    const occt::OcctModel& model;
    const Camera& camera;
    double diag;
    std::string label;  // model / view / method
    ReferenceIntersector& inter;
};

// The nearest OCCT hit on the contract ray of pixel (i, j) (the intersector
// reloads itself after a ray it throws on: seen, Standard_NullObject on trj8).
OcctHit cast(ReferenceIntersector& inter, const Camera& camera, int i, int j, double t_max) {
    return inter.cast(camera.pixel_ray(i, j), t_max);
}
double ray_limit(const Scene& scene, const Camera& camera) {
    return 4.0 * scene.bbox.diagonal() + length(camera.spec().eye - scene.bbox.center());
}

// Within one pixel of an edge of the TRUE image: one of the 8 neighbours' OCCT rays
// differs from the pixel's in hit/miss or face, or its t jumps by more than
// kJumpFootprints pixel footprints (a silhouette where a face occludes ITSELF, a
// fold, which our face AOV cannot show: both sides carry the same id). A smooth
// surface changes t by that much from one pixel to the next only when inclined
// more than atan(10) = 84 deg to the ray, i.e. within 6 deg of its silhouette.
// Asked only for samples that fail the criteria, so its 8 extra rays are cheap.
constexpr double kJumpFootprints = 10.0;
bool near_true_edge(const Context& c, const Sample& s) {
    const double t_max = ray_limit(c.scene, c.camera);
    auto footprint = [&](double t) {
        return c.camera.perspective() ? 2.0 * t * c.camera.tan_half_fov() / c.camera.height()
                                      : c.camera.spec().ortho_height / c.camera.height();
    };
    for (int dj = -1; dj <= 1; ++dj)
        for (int di = -1; di <= 1; ++di) {
            const int a = s.i + di, b = s.j + dj;
            if ((!di && !dj) || a < 0 || b < 0 || a >= c.camera.width() || b >= c.camera.height()) continue;
            const OcctHit n = cast(c.inter, c.camera, a, b, t_max);
            if (n.error) continue;
            if (n.hit != s.occt.hit || n.face != s.occt.face) return true;
            if (n.hit && std::fabs(n.t - s.occt.t) > kJumpFootprints * footprint(s.occt.t)) return true;
        }
    return false;
}

double on_face_tol(const Context& c, int face) {
    const TopoDS_Face& f = TopoDS::Face(c.model.faces.FindKey(face));
    return std::max(kOnFaceRel * c.diag, kOnFaceTolFactor * BRep_Tool::Tolerance(f));
}
double dist_face(const Context& c, int face, const gp_Pnt& p) {
    return dist_to_face(TopoDS::Face(c.model.faces.FindKey(face)), p);
}

// Judges one sample (ours vs OCCT), settling disputes with DistShapeShape.
void judge(const Context& c, Sample& s, int& settlements, bool settle) {
    const bool ours = s.face != 0, theirs = s.occt.hit;
    const double dt_tol = kDtRel * c.diag;
    const Ray ray = c.camera.pixel_ray(s.i, s.j);
    if (!ours && !theirs) {
        s.verdict = Verdict::both_miss;
        return;
    }
    if (ours && theirs && std::fabs(s.t - s.occt.t) <= dt_tol) {
        if (static_cast<int>(s.face) == s.occt.face) {
            s.verdict = Verdict::match;
            return;
        }
        if (!settle || settlements >= kMaxSettlements) {
            s.verdict = Verdict::unsettled;
            return;
        }
        ++settlements;
        const gp_Pnt p = at(ray, s.t);
        s.d_ours = dist_face(c, static_cast<int>(s.face), p);
        s.d_ours_to_occt_face = dist_face(c, s.occt.face, p);
        s.verdict =
            s.d_ours <= on_face_tol(c, static_cast<int>(s.face)) ? Verdict::face_coincident : Verdict::fail_face;
        return;
    }
    // A dispute: hit/miss, or both hit at different t.
    if (!settle || settlements >= kMaxSettlements) {
        s.verdict = Verdict::unsettled;
        return;
    }
    ++settlements;
    bool ours_ok = false, theirs_ok = false;
    if (ours) {
        s.d_ours = dist_face(c, static_cast<int>(s.face), at(ray, s.t));
        ours_ok = s.d_ours <= on_face_tol(c, static_cast<int>(s.face));
    }
    if (theirs) {
        s.d_occt = dist_face(c, s.occt.face, at(ray, s.occt.t));
        theirs_ok = s.d_occt <= on_face_tol(c, s.occt.face);
        if (ours) s.d_ours_to_occt_face = dist_face(c, s.occt.face, at(ray, s.t));
    }
    if (ours && (!theirs || s.t < s.occt.t)) {
        // We claim a nearer hit: valid iff it lies on our face (then OCCT missed a root).
        s.verdict = ours_ok ? Verdict::verified_occt_missed : theirs ? Verdict::fail_dt : Verdict::fail_our_spurious;
        return;
    }
    // OCCT claims a nearer hit (or the only one): valid iff it lies on its face.
    if (theirs_ok) {
        s.verdict = ours ? Verdict::fail_dt : Verdict::fail_we_missed;
        return;
    }
    // OCCT's claim is spurious: ours stands if we have none or ours is on our face.
    s.verdict = (!ours || ours_ok) ? Verdict::verified_occt_spurious : Verdict::fail_dt;
}

struct Summary {
    long samples = 0, edge = 0, nonedge = 0;
    long both_hit = 0, raw_hit_disagree = 0, hit_fail = 0;
    long dt_fail = 0, face_mismatch = 0, face_coincident = 0, face_fail = 0;
    long verified_missed = 0, verified_spurious = 0, unsettled = 0;
    long edge_disagree = 0, edge_both_hit = 0, edge_dt_over = 0;
    long occt_errors = 0;    // samples without a reference (intersector threw)
    long edge_by_occt = 0;   // of `edge`: failing samples moved there by near_true_edge
    std::vector<double> dt;  // |dt|/diag over non-edge both-hit samples
    double edge_dt_max = 0;
};

Summary summarize(const Context& c, std::vector<Sample>& samples) {
    Summary m;
    int settlements = 0;
    for (Sample& s : samples) {
        ++m.samples;
        if (s.occt.error) {
            ++m.occt_errors;
            continue;
        }
        const bool ours = s.face != 0, theirs = s.occt.hit;
        if (!s.edge) {
            judge(c, s, settlements, true);
            if (is_fail(s.verdict) && near_true_edge(c, s)) s.edge = s.edge_by_occt = true, ++m.edge_by_occt;
        }
        if (s.edge) {
            ++m.edge;
            // Edge band: raw comparison only (no settlement, not a criterion).
            if (ours != theirs) ++m.edge_disagree;
            if (ours && theirs) {
                ++m.edge_both_hit;
                const double r = s.dt_rel() / c.diag;
                m.edge_dt_max = std::max(m.edge_dt_max, r);
                if (r > kDtRel) ++m.edge_dt_over;
            }
            if (!s.edge_by_occt)
                s.verdict = ours == theirs ? (ours ? Verdict::match : Verdict::both_miss) : Verdict::edge_disagree;
            continue;
        }
        ++m.nonedge;
        if (ours != theirs) ++m.raw_hit_disagree;
        if (ours && theirs) {
            ++m.both_hit;
            m.dt.push_back(s.dt_rel() / c.diag);
            if (static_cast<int>(s.face) != s.occt.face) ++m.face_mismatch;
        }
        switch (s.verdict) {
            case Verdict::verified_occt_missed:
                ++m.verified_missed;
                break;
            case Verdict::verified_occt_spurious:
                ++m.verified_spurious;
                break;
            case Verdict::face_coincident:
                ++m.face_coincident;
                break;
            case Verdict::fail_face:
                ++m.face_fail;
                break;
            case Verdict::unsettled:
                ++m.unsettled;
                break;
            default:
                break;
        }
        if (is_fail(s.verdict) && s.verdict != Verdict::fail_face) {  // fail_face counted above
            if (ours && theirs)
                ++m.dt_fail;
            else
                ++m.hit_fail;
        }
    }
    std::sort(m.dt.begin(), m.dt.end());
    return m;
}

// Why a pixel failed, from the renderer's own building blocks: the preliminary
// map's face and start (u,v) at the pixel, the Newton outcome of the test's method
// from that start, and from the converged (u,v) of a neighbour that hit the face
// OCCT reports (what the rescue could have used). Evidence for the report only.
std::string diagnose(const Context& c, const RenderImage& im, const PreliminaryMap& map, NewtonMethod method,
                     const Sample& s) {
    std::ostringstream o;
    NewtonParams params;
    params.eps = default_newton_eps(c.scene.bbox);
    auto run = [&](uint32_t id, double u0, double v0) {
        const Face& f = c.scene.faces[id - 1];
        const UvBox box = face_uv_box(f.surface, f.u_min, f.u_max, f.v_min, f.v_max, 1e-7 * c.scene.bbox.diagonal());
        const NewtonResult r = method == NewtonMethod::proposed
                                   ? newton_proposed(project_surface(c.camera, f.surface), c.camera,
                                                     c.camera.pixel_screen(s.i, s.j), u0, v0, box, params)
                                   : newton_martin(f.surface, c.camera.pixel_ray(s.i, s.j), u0, v0, box, params);
        std::ostringstream q;
        q << newton_status_name(r.status) << " it=" << r.iterations << " uv=(" << r.u << "," << r.v << ")";
        if (r.status == NewtonStatus::converged)
            q << " t=" << std::setprecision(12) << r.t << std::setprecision(6)
              << (TrimTester(f.loops).inside({r.u, r.v}) ? " inside-trim" : " TRIMMED");
        return q.str();
    };
    const size_t k = map.index(s.i, s.j);
    o << "map: face " << map.face[k];
    if (map.face[k] && map.face[k] <= c.scene.faces.size())
        o << " uv0=(" << map.u[k] << "," << map.v[k] << ") -> " << run(map.face[k], map.u[k], map.v[k]);
    const uint32_t want = s.occt.hit ? static_cast<uint32_t>(s.occt.face) : 0;
    if (!want || want > c.scene.faces.size()) return o.str();
    {
        // The nearest root on OCCT's face from a 16 x 16 grid of starts over its
        // parameter box, and our trim test there: tells a wrong root (nearest root
        // inside our trim: the start picked another sheet) from a trim problem
        // (nearest root outside our trim loops).
        const Face& f = c.scene.faces[want - 1];
        const UvBox box{f.u_min, f.u_max, f.v_min, f.v_max};
        const NurbsSurface projected = project_surface(c.camera, f.surface);
        const TrimTester trim(f.loops);
        NewtonResult best;
        bool found = false;
        constexpr int kGrid = 16;
        for (int a = 0; a < kGrid; ++a)
            for (int b = 0; b < kGrid; ++b) {
                const double u0 = f.u_min + (a + 0.5) / kGrid * (f.u_max - f.u_min);
                const double v0 = f.v_min + (b + 0.5) / kGrid * (f.v_max - f.v_min);
                const NewtonResult r =
                    method == NewtonMethod::proposed
                        ? newton_proposed(projected, c.camera, c.camera.pixel_screen(s.i, s.j), u0, v0, box, params)
                        : newton_martin(f.surface, c.camera.pixel_ray(s.i, s.j), u0, v0, box, params);
                if (r.status == NewtonStatus::converged && (!found || r.t < best.t)) best = r, found = true;
            }
        o << " | nearest root from a 16x16 start grid on face " << want << ": ";
        if (found)
            o << "t=" << std::setprecision(12) << best.t << std::setprecision(6) << " uv=(" << best.u << "," << best.v
              << ")" << (trim.inside({best.u, best.v}) ? " inside-trim" : " TRIMMED");
        else
            o << "none";
    }
    // Every neighbour that hit OCCT's face: how many of their (u,v) starts converge
    // here, and the first one that does (else the first that does not).
    int tried = 0, converged = 0;
    std::string shown;
    for (int dj = -1; dj <= 1; ++dj)
        for (int di = -1; di <= 1; ++di) {
            const int a = s.i + di, b = s.j + dj;
            if ((!di && !dj) || a < 0 || b < 0 || a >= im.width || b >= im.height) continue;
            const size_t n = static_cast<size_t>(b) * im.width + a;
            if (im.face[n] != want) continue;
            ++tried;
            const std::string r = run(want, im.u[n], im.v[n]);
            const bool ok = r.rfind("converged", 0) == 0 && r.find("inside-trim") != std::string::npos;
            if (ok) ++converged;
            if (shown.empty() || (ok && converged == 1)) {
                std::ostringstream q;
                q << "(" << a << "," << b << ") uv=(" << im.u[n] << "," << im.v[n] << ") -> " << r;
                shown = q.str();
            }
        }
    o << " | neighbour starts on face " << want << ": " << converged << "/" << tried << " converge inside";
    if (!shown.empty()) o << ", e.g. " << shown;
    return o.str();
}

// Our face ids in the 3x3 neighbourhood, row by row ("-" outside the image).
std::string neighbourhood(const RenderImage& im, int i, int j) {
    std::ostringstream o;
    o << "[";
    for (int dj = -1; dj <= 1; ++dj) {
        for (int di = -1; di <= 1; ++di) {
            const int a = i + di, b = j + dj;
            if (a < 0 || b < 0 || a >= im.width || b >= im.height)
                o << "-";
            else
                o << im.face[static_cast<size_t>(b) * im.width + a];
            if (di < 1) o << " ";
        }
        if (dj < 1) o << " / ";
    }
    o << "]";
    return o.str();
}

std::string describe(const Context& c, const RenderImage& im, const Sample& s) {
    std::ostringstream o;
    o << c.label << " px(" << s.i << "," << s.j << ")" << (s.edge ? " [edge]" : "") << " aov3x3 "
      << neighbourhood(im, s.i, s.j) << " ours: ";
    if (s.face)
        o << "face " << s.face << " t=" << std::setprecision(12) << s.t << " it=" << s.iterations;
    else
        o << "miss";
    o << " | occt: ";
    if (s.occt.hit)
        o << "face " << s.occt.face << " t=" << std::setprecision(12) << s.occt.t;
    else
        o << "miss";
    if (s.face && s.occt.hit) o << " | dt/diag=" << sci(s.dt_rel() / c.diag);
    if (s.d_ours >= 0) o << " | d(our pt, our face)=" << sci(s.d_ours);
    if (s.d_occt >= 0) o << " d(occt pt, occt face)=" << sci(s.d_occt);
    if (s.d_ours_to_occt_face >= 0) o << " d(our pt, occt face)=" << sci(s.d_ours_to_occt_face);
    if (s.face) o << " tol_on(ours)=" << sci(on_face_tol(c, static_cast<int>(s.face)));
    o << " -> " << verdict_name(s.verdict);
    return o.str();
}

std::string model_path(const AccCase& a) {
    return a.fixture.empty() ? T::shared_model(a.rel) : T::fixture_by_name(a.fixture);
}

// gtest prints the parameter of a failing test with this (instead of its bytes).
[[maybe_unused]] void PrintTo(const AccCase& a, std::ostream* os) { *os << a.name; }

class RenderAccuracy : public testing::TestWithParam<AccCase> {
protected:
    void record(const std::string& key, const std::string& value) { RecordProperty(key, value); }
};

TEST_P(RenderAccuracy, PixelRaysMatchIntCurvesFace) {
    const AccCase& a = GetParam();
    if (!a.rel.empty()) NURBSRT_REQUIRE_SHARED_MODELS();
    const std::string path = model_path(a);
    ASSERT_TRUE(fs::exists(path)) << path;

    using Clock = std::chrono::steady_clock;
    const auto t_import = Clock::now();
    const Scene scene = import_file(path);
    const occt::OcctModel model = occt::read_model(path, true);
    ASSERT_EQ(static_cast<int>(scene.faces.size()), model.faces.Extent()) << "face-index contract broken";
    const double import_s = std::chrono::duration<double>(Clock::now() - t_import).count();
    const double diag = scene.bbox.diagonal();
    ASSERT_GT(diag, 0);

    ReferenceIntersector inter(model, kIntersectorTol);

    std::cout << "[ accuracy ] " << a.name << ": " << scene.faces.size() << " faces, diag " << diag
              << " mm, import+read " << std::fixed << std::setprecision(2) << import_s << " s" << std::defaultfloat
              << "\n";

    for (const ViewSpec& vs : a.views) {
        CameraSpec base;
        base.width = kImageW;
        base.height = kImageH;
        base.projection = vs.projection;
        const Camera camera(named_view(vs.name, scene.bbox, base));
        const std::string view_label =
            std::string(vs.name) + (vs.projection == Projection::perspective ? "_persp" : "_ortho");

        std::vector<NewtonMethod> methods{NewtonMethod::proposed};
        if (a.martin) methods.push_back(NewtonMethod::martin);
        std::vector<RenderResult> renders;
        for (NewtonMethod m : methods) {
            RenderOptions opt;
            opt.method = m;
            renders.push_back(render(scene, camera, opt));
        }

        // The samples come from the `proposed` render and are shared by both methods,
        // so the OCCT rays are cast once per view.
        const std::vector<int> pix = choose_samples(renders[0].image, hash_name(a.name + view_label));
        const auto t_occt = Clock::now();
        std::vector<OcctHit> ref(pix.size());
        const double t_max = ray_limit(scene, camera);
        for (size_t k = 0; k < pix.size(); ++k) {
            ref[k] = cast(inter, camera, pix[k] % kImageW, pix[k] / kImageW, t_max);
            if (ref[k].error)
                std::cout << "[ accuracy ] " << a.name << "/" << view_label << ": IntCurvesFace threw at px("
                          << pix[k] % kImageW << "," << pix[k] / kImageW << "): sample excluded\n";
            if (ref[k].hit && ref[k].face == 0) ADD_FAILURE() << "intersector face not in the face map";
        }
        const double occt_s = std::chrono::duration<double>(Clock::now() - t_occt).count();

        for (size_t mi = 0; mi < methods.size(); ++mi) {
            const RenderImage& im = renders[mi].image;
            const std::string method = methods[mi] == NewtonMethod::proposed ? "proposed" : "martin";
            const std::string key = view_label + "_" + method;
            const Context ctx{scene, model, camera, diag, a.name + "/" + view_label + "/" + method, inter};
            std::vector<Sample> samples;
            samples.reserve(pix.size());
            for (size_t k = 0; k < pix.size(); ++k) {
                Sample s;
                s.i = pix[k] % kImageW;
                s.j = pix[k] / kImageW;
                s.edge = near_edge(im, s.i, s.j);
                s.face = im.face[pix[k]];
                s.t = s.face ? static_cast<double>(im.z[pix[k]]) : kInf;
                s.iterations = im.iterations[pix[k]];
                s.occt = ref[k];
                samples.push_back(s);
            }
            const auto t_judge = Clock::now();
            const Summary m = summarize(ctx, samples);
            const double judge_s = std::chrono::duration<double>(Clock::now() - t_judge).count();

            const long hit_ok = m.nonedge - m.hit_fail;
            const long dt_ok = m.both_hit - m.dt_fail;
            const long face_ok = m.both_hit - m.face_fail;
            std::ostringstream out;
            out << "[ accuracy ] " << ctx.label << ": samples " << m.samples << ", edge-excluded " << m.edge
                << " (of which " << m.edge_by_occt << " failing samples at an edge of OCCT's image)"
                << ", non-edge " << m.nonedge << ", no reference (intersector threw) " << m.occt_errors << "\n"
                << "             hit/miss agreement " << pct(hit_ok, m.nonedge) << " (raw "
                << pct(m.nonedge - m.raw_hit_disagree, m.nonedge) << ", failures " << m.hit_fail << ")"
                << "; verified ours: " << m.verified_missed << " occt-missed-root + " << m.verified_spurious
                << " occt-spurious; unsettled " << m.unsettled << "\n"
                << "             both hit " << m.both_hit << ": |dt|/diag p50 " << sci(percentile(m.dt, 0.5)) << " p90 "
                << sci(percentile(m.dt, 0.9)) << " p99 " << sci(percentile(m.dt, 0.99)) << " p99.9 "
                << sci(percentile(m.dt, 0.999)) << " max " << sci(m.dt.empty() ? 0 : m.dt.back())
                << "; within 1e-6 (after settlement) " << pct(dt_ok, m.both_hit) << " (failures " << m.dt_fail << ")\n"
                << "             face mismatches " << m.face_mismatch << " (coincident, same t: " << m.face_coincident
                << ", bad: " << m.face_fail << "); face agreement " << pct(face_ok, m.both_hit) << "\n"
                << "             edge band: " << m.edge << " samples, hit/miss agreement (raw) "
                << pct(m.edge - m.edge_disagree, m.edge) << " (" << m.edge_disagree << " disagree), both hit "
                << m.edge_both_hit << " of which |dt| > 1e-6 diag: " << m.edge_dt_over << " (max " << sci(m.edge_dt_max)
                << ")\n"
                << "             time: render " << std::fixed << std::setprecision(0) << renders[mi].stats.total_ms
                << " ms, occt rays " << std::setprecision(2) << occt_s << " s (" << pix.size()
                << " rays, shared by methods), settlement " << judge_s << " s" << std::defaultfloat << "\n";

            // Worst pixels: every failure (up to 12), the largest non-edge |dt|, and a few
            // edge-band disagreements (information for the speckle work).
            std::vector<const Sample*> fails, edge_dis;
            const Sample* worst_dt = nullptr;
            for (const Sample& s : samples) {
                if (!s.edge && is_fail(s.verdict)) fails.push_back(&s);
                if (s.edge_by_occt)
                    out << "   at an edge of OCCT's image (excluded): " << describe(ctx, im, s) << "\n";
                else if (s.edge && (s.face != 0) != s.occt.hit)
                    edge_dis.push_back(&s);
                if (!s.edge && s.face && s.occt.hit && (!worst_dt || s.dt_rel() > worst_dt->dt_rel())) worst_dt = &s;
            }
            std::sort(fails.begin(), fails.end(), [](const Sample* x, const Sample* y) {
                const double dx = x->face && x->occt.hit ? x->dt_rel() : kInf;
                const double dy = y->face && y->occt.hit ? y->dt_rel() : kInf;
                return dx > dy;
            });
            if (!fails.empty()) {
                const PreliminaryMap map = render_preliminary_map(scene, camera);
                for (size_t k = 0; k < fails.size() && k < 12; ++k)
                    out << "   fail: " << describe(ctx, im, *fails[k])
                        << "\n         why: " << diagnose(ctx, im, map, methods[mi], *fails[k]) << "\n";
            }
            if (fails.size() > 12) out << "   ... " << fails.size() - 12 << " more failures\n";
            if (worst_dt) out << "   worst |dt|: " << describe(ctx, im, *worst_dt) << "\n";
            for (const Sample& s : samples)
                if (s.verdict == Verdict::verified_occt_missed || s.verdict == Verdict::verified_occt_spurious ||
                    s.verdict == Verdict::face_coincident)
                    out << "   settled: " << describe(ctx, im, s) << "\n";
            for (size_t k = 0; k < edge_dis.size() && k < 4; ++k)
                out << "   edge-band: " << describe(ctx, im, *edge_dis[k]) << "\n";
            std::cout << out.str() << std::flush;

            record(key + "_samples", std::to_string(m.samples));
            record(key + "_edge_excluded", std::to_string(m.edge));
            record(key + "_hit_agreement_percent", pct(hit_ok, m.nonedge));
            record(key + "_raw_hit_agreement_percent", pct(m.nonedge - m.raw_hit_disagree, m.nonedge));
            record(key + "_both_hit", std::to_string(m.both_hit));
            record(key + "_dt_over_diag_p50", sci(percentile(m.dt, 0.5)));
            record(key + "_dt_over_diag_p90", sci(percentile(m.dt, 0.9)));
            record(key + "_dt_over_diag_p99", sci(percentile(m.dt, 0.99)));
            record(key + "_dt_over_diag_p999", sci(percentile(m.dt, 0.999)));
            record(key + "_dt_over_diag_max", sci(m.dt.empty() ? 0 : m.dt.back()));
            record(key + "_dt_within_percent", pct(dt_ok, m.both_hit));
            record(key + "_face_mismatches", std::to_string(m.face_mismatch));
            record(key + "_face_mismatch_bad", std::to_string(m.face_fail));
            record(key + "_verified_ours", std::to_string(m.verified_missed + m.verified_spurious));
            record(key + "_edge_band_disagree", std::to_string(m.edge_disagree));
            record(key + "_edge_by_occt_neighbourhood", std::to_string(m.edge_by_occt));
            record(key + "_no_reference", std::to_string(m.occt_errors));
            record(key + "_verified_ours_occt_missed_root", std::to_string(m.verified_missed));
            record(key + "_verified_ours_occt_spurious", std::to_string(m.verified_spurious));

            // Enough evidence to judge at all (a blank render must not pass trivially).
            EXPECT_GT(m.both_hit, 300) << ctx.label << ": too few hit samples to judge";
            EXPECT_LE(m.hit_fail * 1000, kPerMille * m.nonedge)
                << ctx.label << ": hit/miss agreement " << pct(hit_ok, m.nonedge) << " < 99.9%";
            EXPECT_LE(m.dt_fail * 1000, kPerMille * m.both_hit)
                << ctx.label << ": |dt| <= 1e-6 diag on only " << pct(dt_ok, m.both_hit) << " < 99.9%";
            EXPECT_LE(m.face_fail * 1000, kPerMille * m.both_hit)
                << ctx.label << ": face agreement " << pct(face_ok, m.both_hit) << " < 99.9%";
        }
    }
}

INSTANTIATE_TEST_SUITE_P(Models, RenderAccuracy, testing::ValuesIn(cases()),
                         [](const testing::TestParamInfo<AccCase>& i) { return i.param.name; });

}  // namespace
