// The nearer-sheet pass. Where a surface folds over itself (or two faces lie
// closer than the map mesh's deflection), the map can hand a pixel the farther of
// two sheets, and Newton converges there; it shows as an isolated depth spike: a
// hit deeper than the mean of both neighbours of a horizontal or vertical pair by
// more than the spike threshold. Such pixels are solved again from those
// neighbours' faces and (u, v); a hit on the pixel's own ray that is nearer by more
// than the nearer threshold replaces it: the nearest intersection is the visible
// one. Reads only the hits so far, so the result stays independent of the thread
// count.
#include <algorithm>

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
// opposite neighbour's (compared squared: 9): on one smooth sheet the two
// distances are about equal.
constexpr double kUvJump2 = 9.0;
// Passes after the first: a run of far-sheet pixels is peeled one pixel per pass
// from each end, so runs of up to about 64 pixels are cleared; longer runs are not spikes
// but a whole region the map got wrong, which this pass does not claim to fix.
constexpr int kMaxPeelPasses = 32;

struct Update {
    size_t k;
    PixelHit hit;
};

class NearerSheet {
public:
    NearerSheet(const FrameContext& c, const Solver& solver, const std::vector<PixelHit>& hits)
        : c_(c), solver_(solver), hits_(hits) {
        const double diag = std::max(c.scene.bbox.diagonal(), 1e-300);
        spike_ = kSpikeRelative * diag;
        nearer_ = kNearerRelative * diag;
    }
    // A nearer hit for pixel (i, j) than its current one, if any.
    bool find(int i, int j, PixelHit& out) const {
        const PixelHit& p = hits_[c_.map.index(i, j)];
        if (!p.face) return false;
        PixelHit best = p;
        const int pairs[2][4] = {{i - 1, j, i + 1, j}, {i, j - 1, i, j + 1}};
        for (const auto& q : pairs) {
            if (!c_.in_frame(q[0], q[1]) || !c_.in_frame(q[2], q[3])) continue;
            const PixelHit& a = hits_[c_.map.index(q[0], q[1])];
            const PixelHit& b = hits_[c_.map.index(q[2], q[3])];
            if (!a.face || !b.face || !(p.t > 0.5 * (a.t + b.t) + spike_)) continue;
            // Only from a neighbour on another face, or on another sheet of the same
            // face: its (u, v) jumps. A smoothly curved concave sheet, where depth
            // also rises above the pair's mean, changes (u, v) evenly and is not
            // solved again.
            auto uv_dist2 = [&](const PixelHit& x) {
                const double du = double(x.u) - p.u, dv = double(x.v) - p.v;
                return du * du + dv * dv;
            };
            for (const PixelHit* n : {&a, &b}) {
                const PixelHit& other = n == &a ? b : a;
                const bool jump = n->face != p.face || other.face != p.face || uv_dist2(*n) > kUvJump2 * uv_dist2(other);
                PixelHit h;
                if (jump && n->t < p.t - nearer_ &&
                    solver_.solve(n->face, i, j, n->u, n->v, solver_.params, false, h) == kConverged &&
                    h.t < best.t - nearer_)
                    best = h;
            }
        }
        if (best.face == p.face && best.t == p.t) return false;
        out = best;
        return true;
    }

private:
    const FrameContext& c_;
    const Solver& solver_;
    const std::vector<PixelHit>& hits_;
    double spike_ = 0, nearer_ = 0;
};

}  // namespace

uint64_t nearer_sheet_pass(const FrameContext& c, const Solver& solver, FrameBuffers& b) {
    const NearerSheet nearer(c, solver, b.hits);
    const int W = c.width;
    // The first pass examines every pixel; replacements are collected per row
    // (almost always none) and applied between passes, so no frame-sized buffer is
    // needed for a handful of pixels. Later passes examine only the 4-neighbours of
    // the pixels the last pass changed.
    std::vector<std::vector<Update>> row_updates(c.height);
    parallel_rows(c, false, [&](int j) {
        for (int i = 0; i < W; ++i) {
            PixelHit h;
            if (nearer.find(i, j, h)) row_updates[j].push_back({c.map.index(i, j), h});
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
            b.hits[u.k] = u.hit;
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
    return replaced;
}

}  // namespace nurbsrt
