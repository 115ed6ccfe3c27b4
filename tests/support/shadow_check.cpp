// shadow_check (see shadow_check.h).
#include "tests/support/shadow_check.h"

#include <BRepBuilderAPI_MakeEdge.hxx>
#include <BRepExtrema_DistShapeShape.hxx>
#include <Standard_Failure.hxx>
#include <TopoDS_Edge.hxx>

#include <chrono>
#include <cmath>
#include <cstdint>
#include <iomanip>
#include <sstream>
#include <vector>

#include "importer/occt_shape.h"
#include "importer/reference/reference_intersector.h"
#include "renderer/frame/frame.h"
#include "renderer/passes/lighting.h"

namespace nurbsrt::test {

namespace {

// Pixels facing the light at a grazing angle below this cosine are left out:
// there the key light adds under 5 % of a colour and a flag either way is invisible.
constexpr double kFacingCosine = 0.05;
// The reference ray starts this far (relative to the diagonal, divided by the
// cosine to the light) towards the light from the pixel's point: past the
// point's own surface, whose crossing lies within the Z AOV's float rounding
// (~6e-8 of the diagonal) over the cosine, and past our NURBS conversion's
// distance from the original surface (~1e-7); far short of any occluder that
// matters (a contact shadow narrower than 1e-5 of the model is invisible).
constexpr double kStartOffsetRelative = 1e-5;
constexpr size_t kMaxListed = 6;
// A light ray meets the shape when its segment comes this close (relative to the
// diagonal): the depth noise floor of the full-frame check (kDepthNoiseRelative),
// 10x below the start's offset from the point's own surface.
constexpr double kRayMeetsRelative = 1e-6;

// A fixed pseudo-random number in [0, 1) per pixel index (SplitMix64's finalizer,
// Steele et al. 2014): the same pixels are sampled in every run.
double unit_hash(size_t k) {
    uint64_t z = static_cast<uint64_t>(k) + 0x9e3779b97f4a7c15ull;
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    z ^= z >> 31;
    return static_cast<double>(z >> 11) * 0x1p-53;
}

// The face the segment from a to b comes nearest to, when within `tol` of it; 0
// when it passes farther (or OCCT fails).
int face_met(const occt::OcctModel& model, const Vec3& a, const Vec3& b, double tol) {
    try {
        const TopoDS_Edge seg = BRepBuilderAPI_MakeEdge(gp_Pnt(a.x, a.y, a.z), gp_Pnt(b.x, b.y, b.z)).Edge();
        BRepExtrema_DistShapeShape d(seg, model.shape);
        if (!d.IsDone() || d.NbSolution() == 0 || !(d.Value() <= tol)) return 0;
        for (int s = 1; s <= d.NbSolution(); ++s)
            if (d.SupportTypeShape2(s) == BRepExtrema_IsInFace) return model.faces.FindIndex(d.SupportOnShape2(s));
        return -1;  // on an edge or a vertex of the shape
    } catch (const Standard_Failure&) {
        return 0;
    }
}

}  // namespace

std::string ShadowCheckReport::text(const std::string& label) const {
    std::ostringstream o;
    o << "[ shadows ] " << label << ": " << facing << " px facing the key light, " << shadowed << " shadowed; "
      << checked << " re-cast: FALSE SHADOWS " << false_shadows << ", LEAKS " << leaks
      << " (within a pixel of the boundary: " << boundary_false_shadows << " false, " << boundary_leaks
      << " leaks); reference threw " << ref_errors << ", missed " << ref_misses << "; check " << std::fixed
      << std::setprecision(2) << check_s << " s\n"
      << detail;
    return o.str();
}

ShadowCheckReport shadow_check(const Scene& scene, const occt::OcctModel& model, ReferenceIntersector& inter,
                               const Camera& camera, const RenderImage& im) {
    using Clock = std::chrono::steady_clock;
    const auto t0 = Clock::now();  // for the report only
    ShadowCheckReport rep;
    const int W = im.width, H = im.height;
    if (im.shadow.size() != static_cast<size_t>(W) * H) return rep;
    const Vec3 light = light_rig(camera).key;
    const double diag = scene.bbox.diagonal();
    auto index = [&](int i, int j) { return static_cast<size_t>(j) * W + i; };
    auto cosine = [&](size_t k) {
        const Vec3 n{im.normal[3 * k], im.normal[3 * k + 1], im.normal[3 * k + 2]};
        return im.face[k] ? dot(n, light) : 0.0;
    };
    // Pixels to re-cast, and whether each lies at the shadow's boundary.
    struct Pick {
        int i, j;
        bool boundary;
    };
    std::vector<Pick> singles, shadowed, lit;
    for (int j = 0; j < H; ++j)
        for (int i = 0; i < W; ++i) {
            const size_t k = index(i, j);
            if (!(cosine(k) > kFacingCosine)) continue;
            ++rep.facing;
            rep.shadowed += im.shadow[k];
            int others = 0, facing_neighbours = 0;
            for_each_neighbour(W, H, i, j, 1, [&](int ni, int nj) {
                const size_t n = index(ni, nj);
                if (n == k || !(cosine(n) > kFacingCosine)) return;
                ++facing_neighbours;
                others += im.shadow[n] != im.shadow[k];
            });
            if (facing_neighbours > 0 && others == facing_neighbours)
                singles.push_back({i, j, false});  // a speckle if wrong, not a boundary
            else
                (im.shadow[k] ? shadowed : lit).push_back({i, j, others > 0});
        }
    // Singles first, then samples of the rest: each pixel is taken when its own
    // hash falls below cap / count, so whether a pixel is sampled does not depend
    // on the others (an even stride over the list moved every sample when one
    // pixel more was shadowed, and the counts jumped by chance).
    std::vector<Pick> picks(singles.begin(), singles.begin() + std::min(singles.size(), kMaxSingles));
    for (const auto& [all, cap] : {std::pair{&shadowed, kMaxShadowedSamples}, std::pair{&lit, kMaxLitSamples}}) {
        const double fraction = static_cast<double>(cap) / static_cast<double>(std::max<size_t>(all->size(), 1));
        for (const Pick& p : *all)
            if (unit_hash(index(p.i, p.j)) < fraction) picks.push_back(p);
    }
    std::ostringstream detail;
    size_t listed = 0;
    for (size_t q = 0; q < picks.size(); ++q) {
        const Pick& p = picks[q];
        const size_t k = index(p.i, p.j);
        const Ray view = camera.pixel_ray(p.i, p.j);
        const Vec3 x = view.origin + static_cast<double>(im.z[k]) * view.dir;
        const double c = cosine(k);
        const Vec3 start = x + (kStartOffsetRelative * diag / c) * light;
        const ReferenceHit ref = inter.cast({start, light}, 4 * diag);
        ++rep.checked;
        if (ref.error) {
            ++rep.ref_errors;
            continue;
        }
        const bool ours = im.shadow[k] != 0;
        if (ours == ref.hit) continue;
        if (ours) {
            const int met = face_met(model, start, start + 4 * diag * light, kRayMeetsRelative * diag);
            if (met != 0) {
                ++rep.ref_misses;
                if (listed++ < kMaxListed)
                    detail << "   reference missed px(" << p.i << "," << p.j << "): the light ray meets face " << met
                           << " (BRepExtrema; -1: an edge)\n";
                continue;
            }
        }
        if (p.boundary) {
            (ours ? rep.boundary_false_shadows : rep.boundary_leaks) += 1;
            continue;
        }
        (ours ? rep.false_shadows : rep.leaks) += 1;
        if (listed++ < kMaxListed)
            detail << "   " << (ours ? "FALSE SHADOW" : "LEAK") << " px(" << p.i << "," << p.j << ") face "
                   << im.face[k] << " cos " << c << " p " << std::setprecision(9) << x.x << " " << x.y << " " << x.z
                   << (ref.hit ? " | reference: face " + std::to_string(ref.face) + " at t=" + std::to_string(ref.t)
                               : std::string(" | reference: no hit"))
                   << "\n";
    }
    rep.detail = detail.str();
    rep.check_s = std::chrono::duration<double>(Clock::now() - t0).count();
    return rep;
}

}  // namespace nurbsrt::test
