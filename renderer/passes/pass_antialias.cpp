// Anti-aliasing with exact rays. One ray per pixel centre leaves silhouettes,
// trim edges and face borders jagged; supersampling every pixel would multiply
// the frame's cost by the sample count although the colour varies within a pixel
// only where an edge crosses it. So only edge pixels (from the exact per-pixel
// hits: hit/background, another face, a depth step, a crease in the normal)
// across which the centre samples' colour is not smooth (kSmoothContrast) get
// extra samples. A sample between four centres that show the same thing is off
// any edge and takes their interpolated colour (EdgeSampler::interpolated);
// every other one is an exact ray, solved like the centre one by Newton (to
// kSamplePixels) from the (face, u, v) of the pixel and its 8 neighbours: the
// hits there lie within 1.5 pixels of any sub-pixel sample, on the same sheet.
// This is adaptive supersampling in the sense of Whitted 1980 (extra rays where
// adjacent samples differ), with stratified sample positions (Mitchell 1987: jittered
// strata make the edge error noise instead of a regular pattern). Where the
// samples show two things, the pixel's coverage by each is that of the straight
// edge between them (edge_coverage.h), finer than the fraction of samples. The
// AOVs keep the one exact sample at the pixel centre.
#include <algorithm>
#include <cstdint>
#include <cmath>

#include <tbb/enumerable_thread_specific.h>

#include "renderer/passes/edge_coverage.h"
#include "renderer/passes/sample_pattern.h"
#include "renderer/passes/passes.h"

namespace nurbsrt {

namespace {

// The 3x3 neighbourhood: its faces and starts are the candidates of every sample.
constexpr int kNeighbours = 9;
// An edge pixel across which the colour is smooth to within this (is_smooth),
// in a gamma-2 encoding of the premultiplied colour (close to how 8-bit sRGB
// spaces its steps), gets no extra rays (Mitchell 1987 refines where the
// samples' contrast exceeds a threshold): two tangent faces of one colour
// meeting, or a crease both sides of which the light hits alike. A step of
// contrast J through the pixel moves its box average from the centre sample's
// by at most J / 2, so under two steps of the encoding the pixel is off by at
// most one output step.
constexpr double kSmoothContrast = 2.0 / 255;

// A sample's hit is found to within this fraction of a pixel in the image plane
// (Newton's residual (12), in model units at the hit's depth), not to the
// frame's tolerance (~1e-5 of a pixel): a sample only decides which side of an
// edge it falls on, and an error of 1/256 pixel changes the coverage by at most
// ~1/180 of the pixel's area per sample, below one 8-bit step. From a start at
// most 1.5 pixels away, one Newton step mostly gets there.
constexpr double kSamplePixels = 1.0 / 256;

// Whether the robust Newton (newton.h) can end otherwise than a plain solve that
// ended in o. It differs only after a step that raises the residual (13),
// leaves the box a second time or stays clamped, or past the plain iteration
// limit: a plain solve that converged (inside the trim or not, or behind the
// eye) or met a singular Jacobian (14) never got there, and the robust one
// retraces it to the same end.
bool retried(Outcome o) { return !(o == kTrimmed || o == kBehind || o == kSingular); }

// The surface's derivatives at pixels' hits, the starts of the samples,
// evaluated on first use: a pixel's samples start from the same few neighbour
// hits, and the edge pixels around a hit (up to 3 rows, 3 columns) share it.
// One per thread; rows j and j +- 1 have distinct slots (row mod 4), and an
// entry remembers its row, so rows in any order stay correct. The samples'
// iterates are the same numbers as without it.
class StartCache {
public:
    explicit StartCache(int width) : width_(width), entries_(4 * static_cast<size_t>(width)) {}
    // The derivatives at h, the hit of pixel (i, j).
    const SurfaceDerivs& get(const Solver& solver, const PixelHit& h, int i, int j) {
        Entry& e = entries_[static_cast<size_t>(j & 3) * width_ + i];
        if (e.row != j) {
            e.derivs = solver.start_derivs(h.face, h.u, h.v);
            e.row = j;
        }
        return e.derivs;
    }

private:
    struct Entry {
        int row = -1;
        SurfaceDerivs derivs;
    };
    size_t width_;
    std::vector<Entry> entries_;
};

class EdgeSampler {
public:
    // `centres`: the image's colours before this pass (the centre samples),
    // unchanged while it runs.
    EdgeSampler(const FrameContext& c, const Solver& solver, const Shader& shader, const FrameBuffers& b,
                const std::vector<uint8_t>& diff, const std::vector<float>& centres, StartCache& starts)
        : c_(c),
          solver_(solver),
          hits_(b.hits),
          shader_(shader),
          diff_(diff),
          centres_(centres),
          start_cache_(starts),
          params_(solver.params),
          robust_(solver.robust) {}

    // Pixel (i, j)'s colour from its centre sample (`rgba`, straight alpha) and
    // its n stratified sub-pixel samples: where they show two things (two faces,
    // or a face and background) on either side of a straight edge, each side's
    // mean colour weighted by the coverage of that side (straight_edge_coverage,
    // with the 8 neighbours' centres as further samples); elsewhere the mean of
    // all samples. Back in straight alpha. Returns the number of rays traced
    // (samples not interpolated).
    int resolve(int i, int j, int n, float* rgba) const {
        collected_ = false;  // the starts are collected for the first traced sample
        ci_ = i, cj_ = j;
        samples_.resize(static_cast<size_t>(n) + 1);
        samples_[0] = {0.5,
                       0.5,
                       hits_[c_.map.index(i, j)].face,
                       {rgba[0] * rgba[3], rgba[1] * rgba[3], rgba[2] * rgba[3], rgba[3]}};
        const uint32_t seed = hash32(static_cast<uint32_t>(c_.map.index(i, j)));
        int traced = 0;
        for (int s = 1; s <= n; ++s) {
            Sample& q = samples_[s];
            sample_position(s - 1, n, seed, q.x, q.y);
            traced += trace(i + q.x, j + q.y, q.rgba, q.face);
        }
        double mean[4];
        if (!two_sided_mean(mean)) {
            for (double& m : mean) m = 0;
            for (const Sample& q : samples_)
                for (int k = 0; k < 4; ++k) mean[k] += q.rgba[k] / (n + 1);
        }
        if (mean[3] > 0)
            for (int q = 0; q < 3; ++q) rgba[q] = static_cast<float>(mean[q] / mean[3]);
        rgba[3] = static_cast<float>(mean[3]);
        return traced;
    }

private:
    struct Sample {
        double x, y;  // in the pixel, [0, 1)^2
        uint32_t face;
        double rgba[4];  // premultiplied
    };
    // The samples' mean colour as two sides of a straight edge (see resolve);
    // false where the samples show one thing or more than two, or no straight
    // line separates them.
    bool two_sided_mean(double mean[4]) const {
        const uint32_t a = samples_[0].face;
        uint32_t b = a;
        for (const Sample& q : samples_) {
            if (q.face == a) continue;
            if (b != a && q.face != b) return false;  // a third thing
            b = q.face;
        }
        if (b == a) return false;
        side_a_.clear(), side_b_.clear();
        double sum_a[4] = {0, 0, 0, 0}, sum_b[4] = {0, 0, 0, 0};
        for (const Sample& q : samples_) {
            (q.face == a ? side_a_ : side_b_).add(q.x, q.y);
            double* sum = q.face == a ? sum_a : sum_b;
            for (int k = 0; k < 4; ++k) sum[k] += q.rgba[k];
        }
        const int n_a = side_a_.size(), n_b = side_b_.size();  // the pixel's own samples
        for_each_neighbour(c_, ci_, cj_, 1, [&](int ni, int nj) {
            const uint32_t f = hits_[c_.map.index(ni, nj)].face;
            if ((ni != ci_ || nj != cj_) && (f == a || f == b))
                (f == a ? side_a_ : side_b_).add(ni - ci_ + 0.5, nj - cj_ + 0.5);
        });
        const double cover = straight_edge_coverage(side_a_, side_b_);
        if (std::isnan(cover)) return false;
        for (int k = 0; k < 4; ++k) mean[k] = cover * sum_a[k] / n_a + (1 - cover) * sum_b[k] / n_b;
        return true;
    }
    struct Start {
        uint32_t face;
        float u, v;
        double t;       // the depth of that pixel's hit
        int di, dj;     // the pixel it comes from, relative to the edge pixel
        double cx, cy;  // that pixel's centre in pixel coordinates (exact: integers + 0.5)
    };
    // The hits of the 3x3 around (i, j): every sample's candidate starts.
    void collect_starts() const {
        const int i = ci_, j = cj_;
        collected_ = true;
        nstarts_ = 0;
        for_each_neighbour(c_, i, j, 1, [&](int ni, int nj) {
            const PixelHit& h = hits_[c_.map.index(ni, nj)];
            if (h.face) starts_[nstarts_++] = {h.face, h.u, h.v, h.t, ni - i, nj - j, ni + 0.5, nj + 0.5};
        });
        // Front first (starts_[0] is the nearest hit, and equal keys in
        // candidates keep this order). Insertion sort, stable (equal depths keep
        // the walk's order): at most 9 entries, and std::stable_sort allocated a
        // buffer per edge pixel.
        for (int q = 1; q < nstarts_; ++q)
            for (int r = q; r > 0 && starts_[r].t < starts_[r - 1].t; --r) std::swap(starts_[r], starts_[r - 1]);
        own_hit_ = hits_[c_.map.index(i, j)].face != 0;
        // The samples' Newton tolerance: kSamplePixels at the nearest of these
        // hits (a pixel's footprint grows with depth, so farther hits get a
        // tighter one in pixels), never tighter than the frame's own.
        if (nstarts_ > 0) {
            const double eps = kSamplePixels * c_.pixel_footprint(starts_[0].t);
            params_.eps = std::max(solver_.params.eps, eps);
            robust_.eps = std::max(solver_.robust.eps, eps);
        }
        // Each start's face as an index among the distinct faces, for candidates.
        int first_of_face[kNeighbours];  // each distinct face's first start
        nfaces_ = 0;
        for (int q = 0; q < nstarts_; ++q) {
            int g = 0;
            while (g < nfaces_ && starts_[first_of_face[g]].face != starts_[q].face) ++g;
            if (g == nfaces_) first_of_face[nfaces_++] = q;
            face_of_start_[q] = static_cast<uint8_t>(g);
        }
    }
    // The premultiplied colour at pixel coordinates (px, py) and the face seen
    // there (0: background): interpolated where no edge can cross
    // (interpolated), else the exact ray's (returns 1).
    int trace(double px, double py, double out[4], uint32_t& face) const {
        if (interpolated(px, py, out, face)) return 0;
        if (!collected_) collect_starts();
        const ScreenPoint sp = c_.camera.screen(px, py);
        PixelHit best, best_near;
        int order[kNeighbours];
        const int ncand = candidates(px, py, order);
        // The robust Newton only where the plain one found nothing on any face
        // and the pixel itself is hit (a sample of a background pixel that the
        // plain solves from neighbours a pixel away miss is background: the
        // robust retries there cost more than the rest of the pass), and only
        // from starts whose plain solve it could change (retried).
        Outcome plain[kNeighbours];
        for (const NewtonParams* p : {&params_, &robust_}) {
            if (p == &robust_ && !own_hit_) break;
            for (int m = 0; m < ncand && !best.face; ++m) {
                if (p == &robust_ && !retried(plain[m])) continue;
                const Start& s = starts_[order[m]];
                PixelHit h;
                const Outcome o = solver_.solve(s.face, sp, s.u, s.v, *p, true, h, &start_derivs(order[m]));
                plain[m] = o;
                if (o == kConverged) best = h;
                if (o == kNearTrim && h.t < best_near.t) best_near = h;
            }
            if (best.face || best_near.face) break;
        }
        // As in the rescue: inside the trim wins unless a near-trim hit is in front.
        if (best_near.face && best_near.t < best.t) best = best_near;
        face = best.face;
        if (!best.face) {  // background or ground, premultiplied like every sample here
            float bg[4];
            shader_.background(c_.camera.ray(sp), bg);
            for (int q = 0; q < 3; ++q) out[q] = double(bg[q]) * bg[3];
            out[3] = bg[3];
            return 1;
        }
        Vec3 n;
        const int pi = std::clamp(static_cast<int>(c_.camera.pixel_x(sp.sx)), 0, c_.width - 1);
        const int pj = std::clamp(static_cast<int>(c_.camera.pixel_y(sp.sy)), 0, c_.height - 1);
        const Vec3 rgb = shader_.colour(best, c_.camera.ray(sp), n, nullptr, nullptr, c_.map.index(pi, pj));
        out[0] = rgb.x, out[1] = rgb.y, out[2] = rgb.z, out[3] = 1.0;
        return 1;
    }
    // A sample inside the square of four pixel centres around it where all four
    // show the same thing (one face with no depth step or crease between any two
    // of them, or all background: no difference bit between them) lies where, by
    // the assumption that decides the edge pixels themselves (features are seen
    // by the centre samples), no edge crosses: on that face's smooth shading, or
    // on background. Its colour is the bilinear interpolation of the four centre
    // colours, which differs from the exact ray's by the shading's second-order
    // variation over a pixel, as a pixel centre's one sample differs from its
    // pixel's mean everywhere off the edges. Only samples in squares an edge
    // crosses are traced: about half of each edge pixel's samples, as an edge
    // between two centres crosses one of the two pixels.
    bool interpolated(double px, double py, double out[4], uint32_t& face) const {
        const double gx = px - 0.5, gy = py - 0.5;  // in the lattice of pixel centres
        // floor(), for gx, gy >= -0.5 (samples lie in the frame): truncation
        // where they are not negative, without a libm call per sample.
        const int i0 = gx < 0 ? -1 : static_cast<int>(gx), j0 = gy < 0 ? -1 : static_cast<int>(gy);
        if (i0 < 0 || j0 < 0 || i0 + 1 >= c_.width || j0 + 1 >= c_.height) return false;
        const size_t k00 = c_.map.index(i0, j0), k10 = c_.map.index(i0 + 1, j0);
        const size_t k01 = c_.map.index(i0, j0 + 1), k11 = c_.map.index(i0 + 1, j0 + 1);
        if ((diff_[k00] & (kDiffRight | kDiffDown | kDiffDownRight)) || (diff_[k10] & (kDiffDown | kDiffDownLeft)) ||
            (diff_[k01] & kDiffRight))
            return false;
        face = hits_[k00].face;
        const double fx = gx - i0, fy = gy - j0;
        const double w[4] = {(1 - fx) * (1 - fy), fx * (1 - fy), (1 - fx) * fy, fx * fy};
        const size_t ks[4] = {k00, k10, k01, k11};
        for (int q = 0; q < 4; ++q) out[q] = 0;
        for (int m = 0; m < 4; ++m) {
            const float* rgba = &centres_[4 * ks[m]];
            for (int q = 0; q < 3; ++q) out[q] += w[m] * rgba[q] * rgba[3];
            out[3] += w[m] * rgba[3];
        }
        return true;
    }
    const SurfaceDerivs& start_derivs(int q) const {
        const Start& s = starts_[q];
        const int ni = ci_ + s.di, nj = cj_ + s.dj;
        return start_cache_.get(solver_, hits_[c_.map.index(ni, nj)], ni, nj);
    }
    // The starts a sample at (px, py) is solved from, in order (returns how
    // many): per face its start nearest to the sample (ties: the first), the
    // face in front first (the first hit inside a trim ends the search), but of
    // faces whose starts lie within about a depth step of each other (one
    // surface continuing across the edge between two faces) the one nearer on
    // screen, on whose side of the edge the sample more likely is: the order key
    // is the start's depth plus kDepthStepFootprints (passes.h) pixel footprints
    // per pixel of distance.
    int candidates(double px, double py, int order[kNeighbours]) const {
        double d2[kNeighbours], key[kNeighbours];
        int best[kNeighbours];
        std::fill(best, best + nfaces_, -1);
        for (int q = 0; q < nstarts_; ++q) {
            const double dx = starts_[q].cx - px, dy = starts_[q].cy - py;
            d2[q] = dx * dx + dy * dy;
            int& b = best[face_of_start_[q]];
            if (b < 0 || d2[q] < d2[b]) b = q;
        }
        for (int g = 0; g < nfaces_; ++g) {
            const Start& s = starts_[best[g]];
            key[g] = s.t + kDepthStepFootprints * c_.pixel_footprint(s.t) * std::sqrt(d2[best[g]]);
            order[g] = best[g];
            for (int m = g; m > 0 && key[m] < key[m - 1]; --m) {
                std::swap(key[m], key[m - 1]);
                std::swap(order[m], order[m - 1]);
            }
        }
        return nfaces_;
    }
    const FrameContext& c_;
    const Solver& solver_;
    const PixelArray<PixelHit>& hits_;
    const Shader& shader_;
    const std::vector<uint8_t>& diff_;
    const std::vector<float>& centres_;
    StartCache& start_cache_;
    // Scratch of the pixel being resolved; one EdgeSampler per thread.
    mutable std::vector<Sample> samples_;  // the pixel's: [0] the centre
    mutable SidePoints side_a_, side_b_;   // the samples by the side they show
    mutable Start starts_[kNeighbours];
    mutable uint8_t face_of_start_[kNeighbours];  // index of the start's face among the distinct faces
    mutable int nfaces_ = 0;
    mutable NewtonParams params_, robust_;  // the solver's, with the samples' tolerance
    mutable int nstarts_ = 0, ci_ = 0, cj_ = 0;
    mutable bool own_hit_ = false, collected_ = false;
};

// Whether each pixel of row j differs from one of its 8 neighbours in what it
// shows (out[i], 0 or 1): its own forward bits, or the bit of a neighbour
// before it pointing at it. Branch-free over the row's interior, so that the
// compiler vectorizes the scan of a whole frame (most of it shows no edge).
void edge_row(const FrameContext& c, const std::vector<uint8_t>& diff, int j, uint8_t* out) {
    const int W = c.width;
    const uint8_t* d = &diff[c.map.index(0, j)];
    const uint8_t* up = j > 0 ? &diff[c.map.index(0, j - 1)] : nullptr;
    auto at = [&](int i) {  // any column, borders included
        bool e = d[i] || (i > 0 && (d[i - 1] & kDiffRight));
        if (up)
            e = e || (up[i] & kDiffDown) || (i > 0 && (up[i - 1] & kDiffDownRight)) ||
                (i + 1 < W && (up[i + 1] & kDiffDownLeft));
        return static_cast<uint8_t>(e);
    };
    out[0] = at(0);
    if (W > 1) out[W - 1] = at(W - 1);
    if (!up) {
        for (int i = 1; i + 1 < W; ++i) out[i] = static_cast<uint8_t>((d[i] | (d[i - 1] & kDiffRight)) != 0);
        return;
    }
    for (int i = 1; i + 1 < W; ++i)
        out[i] = static_cast<uint8_t>((d[i] | (d[i - 1] & kDiffRight) | (up[i] & kDiffDown) |
                                       (up[i - 1] & kDiffDownRight) | (up[i + 1] & kDiffDownLeft)) != 0);
}

// A pixel's colour in the encoding kSmoothContrast is measured in: gamma 2 of
// the premultiplied colour (close to how 8-bit sRGB spaces its steps), and alpha.
struct Encoded {
    double q[4];
};
Encoded encoded(const RenderImage& img, size_t k) {
    const float* px = &img.rgba[4 * k];
    Encoded e;
    for (int q = 0; q < 3; ++q) e.q[q] = std::sqrt(std::max(0.0, double(px[q]) * px[3]));
    e.q[3] = px[3];
    return e;
}

// Whether the image is smooth across pixel (i, j): on each of the four lines of
// its 3x3 through the centre (row, column, both diagonals) the centre samples'
// second difference stays under kSmoothContrast in every channel. An edge
// through the pixel or between it and a neighbour is a step in the colour, and a
// step J shows as a second difference of J (or J/2 where the step is shared),
// however the shading slopes around it; where there is none, the colour is
// linear to second order across the pixel and its box-filtered value is the
// centre sample's up to 1/24 of the second difference (Taylor expansion of the
// pixel's mean). A pixel at the frame's border (lines cut short) is smooth only
// where all the centre samples it has agree.
bool is_smooth(const FrameContext& c, const RenderImage& img, int i, int j) {
    const Encoded m = encoded(img, c.map.index(i, j));
    if (i > 0 && j > 0 && i + 1 < c.width && j + 1 < c.height) {
        constexpr int kLines[4][2] = {{1, 0}, {0, 1}, {1, 1}, {1, -1}};
        for (const auto& d : kLines) {
            const Encoded a = encoded(img, c.map.index(i - d[0], j - d[1]));
            const Encoded b = encoded(img, c.map.index(i + d[0], j + d[1]));
            for (int q = 0; q < 4; ++q)
                if (std::abs(a.q[q] + b.q[q] - 2 * m.q[q]) >= kSmoothContrast) return false;
        }
        return true;
    }
    bool flat = true;
    for_each_neighbour(c, i, j, 1, [&](int ni, int nj) {
        const Encoded e = encoded(img, c.map.index(ni, nj));
        for (int q = 0; q < 4; ++q) flat = flat && std::abs(e.q[q] - m.q[q]) < kSmoothContrast;
    });
    return flat;
}

}  // namespace

void antialias_pass(const FrameContext& c, const Solver& solver, const Shader& shader, const FrameBuffers& b,
                    const std::vector<uint8_t>& diff, RenderImage& img, RenderStats& st) {
    const int n = c.options.antialias;
    st.antialias = std::max(n, 0);
    if (n <= 0) return;
    // Which pixels are edges is decided from the centre samples only, before any
    // colour changes, so the result does not depend on the order of the rows.
    std::vector<uint8_t> edge(c.pixels(), 0);
    parallel_rows(c, false, [&](int j) {
        uint8_t* e = &edge[c.map.index(0, j)];
        edge_row(c, diff, j, e);
        for (int i = next_set(e, 0, c.width); i < c.width; i = next_set(e, i + 1, c.width))
            e[i] = !is_smooth(c, img, i, j);
    });
    // The samples read the centre colours around their pixel: the resolved
    // colours go to per-row lists, written into the image after every row is
    // done (a copy of the whole image for the pass to read instead was a fresh
    // 4 MB per 512x512 frame, for a few percent of its pixels).
    struct Resolved {
        size_t k;
        float rgba[4];
    };
    std::vector<std::vector<Resolved>> row_resolved(c.height);
    std::atomic<uint64_t> pixels{0}, rays{0};
    tbb::enumerable_thread_specific<StartCache> start_caches([&] { return StartCache(c.width); });
    parallel_rows(c, true, [&](int j) {
        const EdgeSampler sampler(c, solver, shader, b, diff, img.rgba, start_caches.local());
        uint64_t r = 0;
        std::vector<Resolved>& out = row_resolved[j];
        const uint8_t* e = &edge[c.map.index(0, j)];
        for (int i = next_set(e, 0, c.width); i < c.width; i = next_set(e, i + 1, c.width)) {
            const size_t k = c.map.index(i, j);
            Resolved& q = out.emplace_back(Resolved{k, {}});
            std::copy_n(&img.rgba[4 * k], 4, q.rgba);
            r += sampler.resolve(i, j, n, q.rgba);
        }
        pixels += out.size();
        rays += r;
    });
    throw_if_canceled(c.options);
    for (const std::vector<Resolved>& row : row_resolved)
        for (const Resolved& q : row) std::copy_n(q.rgba, 4, &img.rgba[4 * q.k]);
    st.antialias_pixels = pixels;
    st.antialias_rays = rays;
}

}  // namespace nurbsrt
