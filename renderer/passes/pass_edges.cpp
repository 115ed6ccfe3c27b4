// Feature lines over the shading: silhouettes, face borders and creases, found
// in the exact per-pixel hits the way Saito & Takahashi 1990 ("Comprehensible
// rendering of 3-D shapes") find them in a G-buffer: between two adjacent pixels
// that show background and a face, two faces, a step in depth, or normals at an
// angle. The line lies on the boundary between the two pixels; each pixel's
// coverage comes from its distance to the nearest such boundary point (half the
// width plus half a pixel of falloff), which anti-aliases the line and keeps its
// width in pixels whatever the resolution.
#include <algorithm>
#include <cmath>
#include <cstdint>

#include "renderer/passes/passes.h"

namespace nurbsrt {

namespace {

// A crease: the shading normals of two adjacent pixels differ by more than 30
// degrees (cos 30 = 0.866). A smooth face turns by far less between pixels
// except seen almost edge-on, where a silhouette is next anyway.
constexpr double kCreaseCos = 0.866;
// The smallest cosine of incidence the depth-step test below divides by: a
// sheet seen within 0.06 degrees of edge-on may step 1000 footprints a pixel.
constexpr double kMinIncidenceCos = 1e-3;
// Whether hits p and q, with AOV normals a and b, show different things (passes.h,
// neighbour_differences); inline in the frame's loop (a call per pair was most of
// that loop's cost). `dir`: p's pixel ray direction, asked for only at a depth
// step. One sheet seen at incidence angle theta steps in depth by up to a
// footprint times tan(theta) from one pixel to the next, smoothly: a step counts
// (a fold, or another sheet of the face behind) beyond kDepthStepFootprints times
// the larger of 1 and the steeper slope of the two pixels. (A fixed 3 footprints
// drew lines all over a hole's wall seen 17 degrees from edge-on.)
template <class Dir>
inline bool hits_differ(const FrameContext& c, const PixelHit& p, const PixelHit& q, const float* a, const float* b,
                        Dir dir) {
    if (!p.face && !q.face) return false;
    if (!p.face || !q.face || p.face != q.face) return true;  // silhouette, face border
    const double step = std::abs(p.t - q.t), allowed = kDepthStepFootprints * c.pixel_footprint(std::min(p.t, q.t));
    if (step > allowed) {
        const Vec3 d = dir();
        const double ca = std::abs(a[0] * d.x + a[1] * d.y + a[2] * d.z);
        const double cb = std::abs(b[0] * d.x + b[1] * d.y + b[2] * d.z);
        const double cos_min = std::max(std::min(ca, cb), kMinIncidenceCos);
        const double slope = std::sqrt(std::max(0.0, 1 - cos_min * cos_min)) / cos_min;
        if (step > allowed * std::max(1.0, slope)) return true;  // one face folding over itself
    }
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2] < kCreaseCos;
}

}  // namespace

std::vector<uint8_t> neighbour_differences(const FrameContext& c, const FrameBuffers& b, const RenderImage& img) {
    constexpr int kBlock = 8;
    const int W = c.width, H = c.height;
    const bool diagonals = c.options.antialias > 0;  // only anti-aliasing reads them
    std::vector<uint8_t> diff;
    assign_cancelable(diff, c.pixels(), uint8_t(0), c);
    const PixelHit* hits = b.hits.data();
    const float* normal = img.normal.data();
    const uint32_t* face = img.face.data();  // the hits' faces, 4 bytes a pixel (the shading's AOV)
    parallel_rows(c, false, [&](int j) {
        const bool last_row = j + 1 == H;
        // Background with background right of it and below it differs from
        // neither (most of a frame): tested on the face AOV alone, without
        // reading the 40-byte hits.
        const uint32_t* below = last_row ? nullptr : face + c.map.index(0, j + 1);
        const uint32_t* row = face + c.map.index(0, j);
        // Eight such pixels at a time (their faces, their right neighbours' and
        // the row below's, ORed: a loop the compiler vectorizes), then one at a time.
        auto none = [](const uint32_t* f, int n) {
            uint32_t any = 0;
            for (int q = 0; q < n; ++q) any |= f[q];
            return any == 0;
        };
        for (int i = 0; i < W; ++i) {
            if (row[i] == 0 && i > 0 && i + kBlock + 1 <= W && none(row + i, kBlock + 1) &&
                (!below || none(below + i - 1, kBlock + 2))) {
                i += kBlock - 1;
                continue;
            }
            const size_t k = c.map.index(i, j);
            if ((row[i] | (i + 1 < W ? row[i + 1] : 0u)) == 0 &&
                (!below || (below[i] | (i + 1 < W ? below[i + 1] : 0u) | (i > 0 ? below[i - 1] : 0u)) == 0))
                continue;  // diff[k] stays 0
            const PixelHit& p = hits[k];
            const float* a = normal + 3 * k;
            auto dir = [&] { return c.camera.pixel_ray(i, j).dir; };
            auto differs = [&](size_t n) {
                // Section caps (render.h kCapFace): a cap differs from anything
                // but a cap of the same body; two of its planes meet at a crease.
                if (face[k] >= kCapFace || face[n] >= kCapFace) {
                    const float* q = normal + 3 * n;
                    return face[k] != face[n] || a[0] * q[0] + a[1] * q[1] + a[2] * q[2] < kCreaseCos;
                }
                return hits_differ(c, p, hits[n], a, normal + 3 * n, dir);
            };
            uint8_t bits = 0;
            if (i + 1 < W && differs(k + 1)) bits |= kDiffRight;
            if (!last_row) {
                if (differs(k + W)) bits |= kDiffDown;
                if (diagonals && i + 1 < W && differs(k + W + 1)) bits |= kDiffDownRight;
                if (diagonals && i > 0 && differs(k + W - 1)) bits |= kDiffDownLeft;
            }
            diff[k] = bits;
        }
    });
    throw_if_canceled(c.options);
    return diff;
}

void edges_pass(const FrameContext& c, const std::vector<uint8_t>& diff, RenderImage& img) {
    const RenderOptions& o = c.options;
    if (!o.edges || !(o.edge_width > 0)) return;
    const int W = c.width, H = c.height;
    // Boundary points: the midpoints of the right and lower sides of pixels whose
    // neighbour there differs, in pixel coordinates (pixel (i, j) spans [i, i+1) x [j, j+1)).
    // A pixel's coverage by the line: 1 within half the width of a boundary
    // point, falling to 0 over one more pixel (a box filter's footprint). The
    // boundary points of each row are listed first: a pixel then looks only at
    // the listed points of the rows within reach, not at every pixel of its
    // window (boundaries are a few percent of a frame's pixels; the window scan
    // was most of this pass).
    // A pixel is covered where its centre lies nearer than half + 0.5 to a
    // boundary point, which lies half a pixel off the centres of the pixels
    // it separates: within fewer than half + 1 columns and rows, reach of them.
    const double half = 0.5 * o.edge_width;
    const int reach = static_cast<int>(std::ceil(half + 1.0)) - 1;
    std::vector<std::vector<int>> row_right(H), row_down(H);  // columns of each row's boundary points
    parallel_rows(c, false, [&](int j) {
        const uint8_t* d = &diff[c.map.index(0, j)];
        for (int i = next_set(d, 0, W); i < W; i = next_set(d, i + 1, W)) {
            if (d[i] & kDiffRight) row_right[j].push_back(i);
            if (d[i] & kDiffDown) row_down[j].push_back(i);
        }
    });
    // Each row's coverage, then the line "over" the row's pixels (Porter & Duff
    // 1984), in the image's straight alpha: rows are independent.
    const float er = o.edge_color.r, eg = o.edge_color.g, eb = o.edge_color.b;
    parallel_rows(c, false, [&](int j) {
        const int nj0 = std::max(j - reach, 0), nj1 = std::min(j + reach, H - 1);
        bool any = false;
        for (int nj = nj0; nj <= nj1 && !any; ++nj) any = !row_right[nj].empty() || !row_down[nj].empty();
        if (!any) return;  // no boundary point within reach (most rows of a frame)
        std::vector<double> d2(W, HUGE_VAL);
        int lo = W, hi = -1;  // the columns reached
        for (int nj = nj0; nj <= nj1; ++nj) {
            const double cy = nj - j;
            for (const bool is_down : {false, true}) {
                for (const int ni : is_down ? row_down[nj] : row_right[nj]) {
                    const int i0 = std::max(ni - reach, 0), i1 = std::min(ni + reach, W - 1);
                    lo = std::min(lo, i0);
                    hi = std::max(hi, i1);
                    for (int i = i0; i <= i1; ++i) {
                        const double cx = ni - i;
                        const double d =
                            is_down ? cx * cx + (cy + 0.5) * (cy + 0.5) : (cx + 0.5) * (cx + 0.5) + cy * cy;
                        d2[i] = std::min(d2[i], d);
                    }
                }
            }
        }
        for (int i = lo; i <= hi; ++i) {
            if (d2[i] == HUGE_VAL) continue;  // no boundary point within reach (most pixels)
            const float a = static_cast<float>(std::clamp(half + 0.5 - std::sqrt(d2[i]), 0.0, 1.0));
            if (a <= 0) continue;
            float* px = &img.rgba[4 * c.map.index(i, j)];
            const float below = px[3] * (1 - a), alpha = a + below;
            px[0] = (er * a + px[0] * below) / alpha;
            px[1] = (eg * a + px[1] * below) / alpha;
            px[2] = (eb * a + px[2] * below) / alpha;
            px[3] = alpha;
        }
    });
    throw_if_canceled(o);
}

}  // namespace nurbsrt
