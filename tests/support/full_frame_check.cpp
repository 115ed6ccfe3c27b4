// The full-frame check (see full_frame_check.h).
#include "tests/support/full_frame_check.h"

#include <BRepBuilderAPI_MakeVertex.hxx>
#include <BRepExtrema_DistShapeShape.hxx>
#include <BRep_Tool.hxx>
#include <Geom_BSplineSurface.hxx>
#include <TColStd_Array1OfInteger.hxx>
#include <TColStd_Array1OfReal.hxx>
#include <TColStd_Array2OfReal.hxx>
#include <TColgp_Array2OfPnt.hxx>
#include <Standard_Failure.hxx>
#include <TopoDS.hxx>
#include <TopoDS_Vertex.hxx>
#include <gp_Pnt.hxx>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <iomanip>
#include <limits>
#include <map>
#include <sstream>

#include "importer/occt_shape.h"
#include "importer/reference/reference_intersector.h"
#include "renderer/solve/newton.h"
#include "renderer/map/preliminary_map.h"
#include "renderer/solve/prepared_data.h"
#include "tests/support/occt_distance.h"

namespace nurbsrt::test {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
// The diagnosis's search for the nearest root on a face: Newton from a grid of
// starts over its parameter box (16 x 16 finds the roots of every face seen so far;
// it runs only for the few pixels found).
constexpr int kRootGrid = 16;
// The rescue's robust solves may take this many steps (render.cpp's kRescueMinIterations).
constexpr int kDiagnoseIterations = 16;
// A root within this much of the diagonal of the reference's depth is the
// reference's root (the check's settlement tolerance is far below it; distinct
// roots of one face along one ray lie far apart at the scales where it matters).
constexpr double kSameRootRelative = 1e-3;

// OCCT's surface of a face's NURBS (the renderer's (u, v)): an evaluation of our
// data independent of the renderer's evaluator. Clamped knot vectors become
// OCCT's distinct knots with multiplicities; homogeneous points, poles and weights.
Handle(Geom_BSplineSurface) occt_surface(const NurbsSurface& s) {
    struct Knots {
        TColStd_Array1OfReal values;
        TColStd_Array1OfInteger mults;
    };
    auto knots = [](const std::vector<double>& k) {
        std::vector<double> v;
        std::vector<int> m;
        for (const double x : k) {
            if (!v.empty() && x == v.back())
                ++m.back();
            else
                v.push_back(x), m.push_back(1);
        }
        Knots out{TColStd_Array1OfReal(1, static_cast<int>(v.size())),
                  TColStd_Array1OfInteger(1, static_cast<int>(v.size()))};
        for (size_t q = 0; q < v.size(); ++q) {
            out.values.SetValue(static_cast<int>(q + 1), v[q]);
            out.mults.SetValue(static_cast<int>(q + 1), m[q]);
        }
        return out;
    };
    const Knots u = knots(s.knots_u), v = knots(s.knots_v);
    TColgp_Array2OfPnt poles(1, s.num_u, 1, s.num_v);
    TColStd_Array2OfReal weights(1, s.num_u, 1, s.num_v);
    for (int i = 0; i < s.num_u; ++i)
        for (int j = 0; j < s.num_v; ++j) {
            const Vec4& c = s.at(i, j);
            poles.SetValue(i + 1, j + 1, gp_Pnt(c.x / c.w, c.y / c.w, c.z / c.w));
            weights.SetValue(i + 1, j + 1, c.w);
        }
    return new Geom_BSplineSurface(poles, weights, u.values, v.values, u.mults, v.mults, s.degree_u, s.degree_v);
}

struct Checker {
    const Scene& scene;
    const occt::OcctModel& model;
    ReferenceIntersector& inter;
    const Camera& camera;
    const RenderImage& im;
    double diag = 0, t_max = 0;

    size_t idx(int i, int j) const { return static_cast<size_t>(j) * im.width + i; }
    bool hit(int i, int j) const {
        return i >= 0 && j >= 0 && i < im.width && j < im.height && im.face[idx(i, j)] != 0;
    }
    const TopoDS_Face& occt_face(int id) const { return TopoDS::Face(model.faces.FindKey(id)); }
    double on_face_tol(int id) const {
        return std::max(kDepthNoiseRelative * diag, kOnFaceTolFactor * BRep_Tool::Tolerance(occt_face(id)));
    }

    // How far apart along `ray` two correct roots of one contact with the face at
    // ray(t) can lie (kContactSpreadMargin); +0 where the normal is undefined.
    double contact_spread(int id, const Ray& ray, double t) const {
        const double cosine = incidence_cosine(occt_face(id), at(ray, t), ray.dir);
        if (!(cosine > 0)) return 0;
        const double tolerances = default_newton_eps(scene.bbox) + ReferenceIntersector::kDefaultTolerance;
        return kContactSpreadMargin * tolerances / cosine;
    }

    // Background with hits on both sides within kEnclosureRadius along a line.
    bool enclosed(int i, int j) const {
        static constexpr int kDirs[4][2] = {{1, 0}, {0, 1}, {1, 1}, {1, -1}};
        for (const auto& d : kDirs) {
            bool before = false, after = false;
            for (int s = 1; s <= kEnclosureRadius; ++s) {
                before = before || hit(i - s * d[0], j - s * d[1]);
                after = after || hit(i + s * d[0], j + s * d[1]);
            }
            if (before && after) return true;
        }
        return false;
    }
    // How much farther than both neighbours of a row or column pair the pixel
    // is (the larger of the two pairs; <= 0: not farther than both).
    double spike_depth(int i, int j) const {
        const double t = im.z[idx(i, j)];
        double depth = -kInf;
        const int pairs[2][4] = {{i - 1, j, i + 1, j}, {i, j - 1, i, j + 1}};
        for (const auto& q : pairs) {
            if (!hit(q[0], q[1]) || !hit(q[2], q[3])) continue;
            depth = std::max(depth, t - std::max<double>(im.z[idx(q[0], q[1])], im.z[idx(q[2], q[3])]));
        }
        return depth;
    }
    // Farther than both neighbours of a row or column pair beyond the noise floor.
    bool spike(int i, int j) const { return spike_depth(i, j) > kDepthNoiseRelative * diag; }
    // How much farther the pixel is than a 4-neighbour on another sheet (0:
    // none): at least kStepFootprints pixel footprints at its depth farther,
    // while the neighbour opposite (continuing the pixel's own sheet) differs
    // from it by under 1/kStepAsymmetry of that, or is background. A smooth
    // slope, however steep, steps alike to both sides.
    double step_depth(int i, int j) const {
        const double t = im.z[idx(i, j)];
        const double footprint = 2.0 * camera.image_to_model_scale(t) / im.height;
        double depth = 0;
        for (const auto& [di, dj] : {std::pair{1, 0}, std::pair{-1, 0}, std::pair{0, 1}, std::pair{0, -1}}) {
            if (!hit(i + di, j + dj)) continue;
            const double gap = t - im.z[idx(i + di, j + dj)];
            if (!(gap > kStepFootprints * footprint)) continue;
            if (hit(i - di, j - dj) && !(kStepAsymmetry * std::abs(t - im.z[idx(i - di, j - dj)]) < gap)) continue;
            depth = std::max(depth, gap);
        }
        return depth;
    }
};

// ---- diagnosis: why did the renderer not find the reference's face there? ----
struct Diagnoser {
    const Checker& c;
    const PreparedScene& prepared;
    const PreliminaryMap& map;
    NewtonParams primary, robust;

    Diagnoser(const Checker& ck, const PreparedScene& p, const PreliminaryMap& m) : c(ck), prepared(p), map(m) {
        primary.eps = default_newton_eps(c.scene.bbox);
        robust = primary;
        robust.robust = true;
        robust.max_iterations = kDiagnoseIterations;
    }

    NewtonResult solve(uint32_t id, int i, int j, double u0, double v0, const NewtonParams& p) const {
        const PreparedFace& pf = prepared.faces()[id - 1];
        return newton_proposed(project_surface(c.camera, c.scene.faces[id - 1].surface), c.camera,
                               c.camera.pixel_screen(i, j), u0, v0, pf.box, p);
    }
    // "converged uv=(..) t=.. inside" / "... outside trim by d (band b)" / "<status>".
    std::string describe(uint32_t id, const NewtonResult& r) const {
        std::ostringstream o;
        o << newton_status_name(r.status) << " it=" << r.iterations << " uv=(" << r.u << "," << r.v << ")";
        if (r.status != NewtonStatus::converged) return o.str();
        const PreparedFace& pf = prepared.faces()[id - 1];
        o << " t=" << std::setprecision(10) << r.t << std::setprecision(4);
        if (pf.trim.inside({r.u, r.v})) {
            o << " inside-trim";
        } else {
            const double box = std::hypot(pf.box.u1 - pf.box.u0, pf.box.v1 - pf.box.v0);
            o << " TRIMMED by " << pf.trim.boundary_distance({r.u, r.v}, box) << " (band " << pf.near_uv << ")";
        }
        return o.str();
    }
    bool inside(uint32_t id, const NewtonResult& r) const {
        return r.status == NewtonStatus::converged && prepared.faces()[id - 1].trim.inside({r.u, r.v});
    }

    void run(FullFrameFinding& f) const {
        std::ostringstream o;
        const int i = f.i, j = f.j;
        const size_t k = map.index(i, j);
        o << "map face " << map.face[k];
        if (map.face[k] && map.face[k] <= c.scene.faces.size())
            o << " from uv=(" << map.u[k] << "," << map.v[k] << ") -> "
              << describe(map.face[k], solve(map.face[k], i, j, map.u[k], map.v[k], primary));
        const uint32_t F = static_cast<uint32_t>(f.ref_face);
        if (!F || F > c.scene.faces.size()) {
            f.cause = "reference face outside the scene";
            f.detail = o.str();
            return;
        }
        // Is F among the rescue's candidates (8-neighbourhood / 5x5), in our hits or the map?
        bool in8 = false, in25 = false;
        for (int dj = -2; dj <= 2; ++dj)
            for (int di = -2; di <= 2; ++di) {
                const int a = i + di, b = j + dj;
                if (a < 0 || b < 0 || a >= c.im.width || b >= c.im.height) continue;
                const size_t n = c.idx(a, b);
                if (c.im.face[n] != F && map.face[n] != F) continue;
                in25 = true;
                if (std::abs(di) <= 1 && std::abs(dj) <= 1) in8 = true;
            }
        // The rescue's start: each 8-neighbour's converged (u, v) on F; ok counts
        // the solves that reach the reference's root (not another root of F).
        int tried = 0, ok = 0;
        std::string first;
        for (int dj = -1; dj <= 1; ++dj)
            for (int di = -1; di <= 1; ++di) {
                const int a = i + di, b = j + dj;
                if ((!di && !dj) || !c.hit(a, b) || c.im.face[c.idx(a, b)] != F) continue;
                ++tried;
                const NewtonResult r = solve(F, i, j, c.im.u[c.idx(a, b)], c.im.v[c.idx(a, b)], robust);
                if (inside(F, r) && std::fabs(r.t - f.ref_t) < kSameRootRelative * c.diag) ++ok;
                if (first.empty()) first = describe(F, r);
            }
        // Does F touch a face of the 5x5 (PreparedFace::adjacent: the rescue's C)?
        std::string touching;
        for (int dj = -2; dj <= 2 && touching.empty(); ++dj)
            for (int di = -2; di <= 2 && touching.empty(); ++di) {
                const int a = i + di, b = j + dj;
                if (a < 0 || b < 0 || a >= c.im.width || b >= c.im.height) continue;
                for (const uint32_t g : {c.im.face[c.idx(a, b)], map.face[map.index(a, b)]}) {
                    if (!g || g > c.scene.faces.size()) continue;
                    const std::vector<uint32_t>& adj = prepared.faces()[g - 1].adjacent;
                    if (std::binary_search(adj.begin(), adj.end(), F)) touching = std::to_string(g);
                }
            }
        o << " | face " << F
          << (in8    ? " in 3x3"
              : in25 ? " in 5x5 only"
                     : " NOT within 5x5")
          << (touching.empty() ? ", touches no face of the 5x5" : ", touches face " + touching);
        o << " | robust Newton from " << tried << " neighbour hits on it: " << ok << " reach the reference root";
        if (!first.empty()) o << " (first: " << first << ")";
        // The nearest root on F from a grid of starts.
        const PreparedFace& pf = prepared.faces()[F - 1];
        NewtonResult best;
        bool found = false;
        for (int a = 0; a < kRootGrid; ++a)
            for (int b = 0; b < kRootGrid; ++b) {
                const double u0 = pf.box.u0 + (a + 0.5) / kRootGrid * (pf.box.u1 - pf.box.u0);
                const double v0 = pf.box.v0 + (b + 0.5) / kRootGrid * (pf.box.v1 - pf.box.v0);
                const NewtonResult r = solve(F, i, j, u0, v0, robust);
                if (r.status == NewtonStatus::converged && std::fabs(r.t - f.ref_t) < kSameRootRelative * c.diag &&
                    (!found || std::fabs(r.t - f.ref_t) < std::fabs(best.t - f.ref_t)))
                    best = r, found = true;
            }
        o << " | root near the reference t on face " << F << ": " << (found ? describe(F, best) : "none");
        if (!found)
            f.cause = "no Newton root on our NURBS of the reference face";
        else if (!inside(F, best)) {
            const double box = std::hypot(pf.box.u1 - pf.box.u0, pf.box.v1 - pf.box.v0);
            const double d = pf.trim.boundary_distance({best.u, best.v}, box);
            f.cause = d <= pf.near_uv ? "root within the near-trim band, not accepted" : "root outside our trim loops";
        } else if (!in25)
            f.cause = "face not in the rescue's candidate set";
        else if (ok > 0)
            f.cause = "root reachable from a neighbour's start, not taken";
        else
            f.cause = "root inside the trim, Newton from the rescue's starts misses it";
        f.detail = o.str();
    }
};

std::string label_of(FullFrameFinding::Kind k) {
    switch (k) {
        case FullFrameFinding::Kind::hole:
            return "hole";
        case FullFrameFinding::Kind::speckle:
            return "speckle";
        case FullFrameFinding::Kind::off_ray:
            return "off-ray hit";
    }
    return "";
}

// Every hit pixel: the point its (face, u, v) AOVs name, evaluated by OCCT, lies
// on the pixel's ray (full_frame_check.h, off-ray hit).
void check_off_ray(const Checker& c, FullFrameReport& rep) {
    std::map<uint32_t, Handle(Geom_BSplineSurface)> surfaces;
    for (int j = 0; j < c.im.height; ++j)
        for (int i = 0; i < c.im.width; ++i) {
            const size_t k = c.idx(i, j);
            const uint32_t id = c.im.face[k];
            if (!id) continue;
            Handle(Geom_BSplineSurface)& s = surfaces[id];
            if (s.IsNull()) s = occt_surface(c.scene.faces[id - 1].surface);
            const gp_Pnt p = s->Value(c.im.u[k], c.im.v[k]);
            const Ray ray = c.camera.pixel_ray(i, j);
            const Vec3 q = Vec3{p.X(), p.Y(), p.Z()} - ray.origin;
            const double off = length(q - dot(q, ray.dir) * ray.dir);
            const double footprint = 2.0 * c.camera.image_to_model_scale(c.im.z[k]) / c.im.height;
            if (off <= std::max(kOffRayPixels * footprint, c.on_face_tol(static_cast<int>(id)))) continue;
            FullFrameFinding f;
            f.kind = FullFrameFinding::Kind::off_ray;
            f.i = i;
            f.j = j;
            f.face = id;
            f.t = c.im.z[k];
            f.off_distance = off;
            f.off_footprints = off / footprint;
            ++rep.off_ray;
            rep.findings.push_back(f);
        }
}

}  // namespace

double reference_ray_limit(const Scene& scene, const Camera& camera) {
    return 4.0 * scene.bbox.diagonal() + length(camera.spec().eye - scene.bbox.center());
}

FullFrameReport full_frame_check(const std::string& label, const Scene& scene, const occt::OcctModel& model,
                                 ReferenceIntersector& inter, const Camera& camera, const RenderImage& im,
                                 double budget_seconds, size_t max_diagnosed) {
    const auto t0 = std::chrono::steady_clock::now();
    Checker c{scene, model, inter, camera, im, scene.bbox.diagonal(), reference_ray_limit(scene, camera)};
    FullFrameReport rep;
    rep.label = label;
    rep.width = im.width;
    rep.height = im.height;
    // Candidates: every enclosed background pixel, then the depth spikes and
    // steps, deepest first (relative to the pixel's own depth), so that a time
    // budget cut leaves only the shallowest unchecked: those of smooth concave
    // sheets.
    struct Candidate {
        int i, j;
        double score;  // -1 for a hole candidate
    };
    std::vector<Candidate> cand;
    for (int j = 0; j < im.height; ++j)
        for (int i = 0; i < im.width; ++i) {
            const size_t k = c.idx(i, j);
            const bool ours = im.face[k] != 0;
            rep.pixels_hit += ours;
            if (!ours && c.enclosed(i, j)) cand.push_back({i, j, -1.0}), ++rep.enclosed;
            if (ours && c.spike(i, j)) {
                cand.push_back({i, j, c.spike_depth(i, j) / im.z[k]}), ++rep.spikes;
            } else if (ours) {
                const double step = c.step_depth(i, j);
                if (step > 0) cand.push_back({i, j, step / im.z[k]}), ++rep.steps;
            }
        }
    std::stable_sort(cand.begin(), cand.end(), [](const Candidate& a, const Candidate& b) {
        return (a.score < 0) != (b.score < 0) ? a.score < 0 : a.score > b.score;
    });
    for (const Candidate& cd : cand) {
        if (std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() > budget_seconds) {
            ++rep.unchecked;
            continue;
        }
        const int i = cd.i, j = cd.j;
        const size_t k = c.idx(i, j);
        const bool ours = im.face[k] != 0;
        const Ray ray = camera.pixel_ray(i, j);
        const ReferenceHit ref = inter.cast(ray, c.t_max);
        if (ref.error) {
            ++rep.ref_errors;
            continue;
        }
        if (!ref.hit || ref.face <= 0) continue;
        const double t = ours ? static_cast<double>(im.z[k]) : kInf;
        // A farther sheet: the reference is nearer by more than the noise floor
        // and the model's own uncertainty where faces meet (their tolerances).
        double margin = kDepthNoiseRelative * c.diag;
        if (ours) margin = std::max({margin, c.on_face_tol(ref.face), c.on_face_tol(static_cast<int>(im.face[k]))});
        if (ours && !(ref.t < t - margin)) continue;
        const double d = dist_to_face(c.occt_face(ref.face), at(ray, ref.t));
        if (!(d <= c.on_face_tol(ref.face))) {
            ++rep.ref_spurious;
            continue;
        }
        if (ours && ref.face == static_cast<int>(im.face[k]) && ref.t >= t - c.contact_spread(ref.face, ray, ref.t)) {
            ++rep.grazing;
            continue;
        }
        FullFrameFinding f;
        f.kind = ours ? FullFrameFinding::Kind::speckle : FullFrameFinding::Kind::hole;
        f.i = i;
        f.j = j;
        f.face = im.face[k];
        f.t = t;
        f.ref_face = ref.face;
        f.ref_t = ref.t;
        f.ref_on_face = d;
        (ours ? rep.speckles : rep.holes) += 1;
        rep.findings.push_back(f);
    }
    std::stable_sort(rep.findings.begin(), rep.findings.end(),
                     [](const FullFrameFinding& a, const FullFrameFinding& b) {
                         return a.kind == FullFrameFinding::Kind::hole && b.kind != FullFrameFinding::Kind::hole;
                     });
    if (!rep.findings.empty() && max_diagnosed > 0) {
        const PreparedScene prepared = prepare(scene);
        const PreliminaryMap map = render_preliminary_map(prepared, camera);
        const Diagnoser dg(c, prepared, map);
        for (size_t q = 0; q < rep.findings.size() && q < max_diagnosed; ++q) dg.run(rep.findings[q]);
    }
    check_off_ray(c, rep);
    rep.check_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    return rep;
}

std::string FullFrameReport::text(size_t max_listed) const {
    std::ostringstream o;
    o << "[ full-frame ] " << label << " " << width << "x" << height << ": hit " << pixels_hit << " px; candidates "
      << enclosed << " enclosed background + " << spikes << " depth spikes + " << steps << " depth steps; HOLES "
      << holes << ", SPECKLES " << speckles << ", OFF-RAY HITS " << off_ray << "; reference threw " << ref_errors
      << ", reference off its face " << ref_spurious << ", reference nearer within a grazing contact's spread "
      << grazing << (unchecked ? "; UNCHECKED (time budget) " + std::to_string(unchecked) : std::string()) << "; check "
      << std::fixed << std::setprecision(2) << check_s << " s" << std::defaultfloat << "\n";
    for (size_t q = 0; q < findings.size() && q < max_listed; ++q) {
        const FullFrameFinding& f = findings[q];
        o << "   " << label_of(f.kind) << " px(" << f.i << "," << f.j << ") ours: ";
        if (f.face)
            o << "face " << f.face << " t=" << std::setprecision(10) << f.t;
        else
            o << "background";
        if (f.kind == FullFrameFinding::Kind::off_ray) {
            o << " | the point at its (u, v) lies " << std::setprecision(3) << f.off_distance << " from the ray ("
              << f.off_footprints << " pixel footprints)\n";
            continue;
        }
        o << " | reference: face " << f.ref_face << " t=" << std::setprecision(10) << f.ref_t << " (on its face within "
          << std::setprecision(3) << f.ref_on_face << ")";
        if (!f.cause.empty()) o << "\n      cause: " << f.cause << "\n      why: " << f.detail;
        o << "\n";
    }
    if (findings.size() > max_listed) o << "   ... " << findings.size() - max_listed << " more\n";
    return o.str();
}

}  // namespace nurbsrt::test
