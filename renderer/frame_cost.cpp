#include "renderer/frame_cost.h"

#include <algorithm>
#include <cstdint>

#include "renderer/frame/frame.h"
#include "renderer/solve/prepared_data.h"
#include "renderer/map/preliminary_map.h"
#include "renderer/render.h"
#include "renderer/passes/shadow_rays.h"

namespace nurbsrt {
namespace {

// Bytes per pixel of the frame's buffers, all alive at once at the peak
// (shading, while the solve buffers still exist).
constexpr size_t kImageBytesPerPixel =
    4 * sizeof(float) + sizeof(float) + 3 * sizeof(float) + sizeof(uint32_t) + 2 * sizeof(float) + sizeof(uint8_t);
constexpr size_t kSolveBytesPerPixel = sizeof(PixelHit) + 3 * sizeof(uint8_t);
// The rescue and nearer-sheet passes' lists, at worst one entry per pixel.
constexpr size_t kRescueBytesPerPixel = 2 * sizeof(size_t) + sizeof(PixelHit) + 2 * sizeof(uint8_t);
constexpr size_t kMapBytesPerPixel = sizeof(uint32_t) + 2 * sizeof(float);
// The GL framebuffer (R32UI id, R32F u and v, 32-bit depth), per pixel of one
// band of the map (kMapBandPixels at most), counted twice: the readback now
// goes straight into the map's arrays (kMapBytesPerPixel), and the second copy,
// once the read buffer, is kept as the margin the render gate was tuned with.
constexpr size_t kFramebufferBytesPerPixel = 2 * (sizeof(uint32_t) + 2 * sizeof(float) + sizeof(float));
// The encoder's 8-bit RGBA copy and the encoded file (at most as large again).
constexpr size_t kEncodeBytesPerPixel = 2 * 4;
// Clip-space position of a map vertex, on the CPU and in the GL buffer.
constexpr size_t kBytesPerMapVertex = 2 * 4 * sizeof(float);
// A GL context's fixed cost (llvmpipe state, shader binaries) and the thread stacks.
constexpr size_t kFixedBytes = size_t(32) << 20;

// Work, in core-seconds of the reference machine (2-core Xeon), fitted to the
// CPU time (not wall time: the machine is shared) of cached frames of a
// rational low-degree part (0.52 us per pixel at 320x240, encoding included)
// and of a degree-9 face on 200 x 200 poles (1.75 us per pixel at 1600x1200):
// a pixel's fixed cost (map readback, a solve's set-up, shading, encoding) and
// the cost per basis-function product of its solve (Newton's few iterations
// each evaluate (p+1)(q+1) products with derivatives).
constexpr double kSecondsPerPixel = 0.4e-6;
constexpr double kSecondsPerBasisProduct = 0.0134e-6;
constexpr double kSecondsPerTriangle = 0.2e-6;
constexpr double kBicubicEvalCost = 16.0;
// The extra work of anti-aliasing 4 sub-pixel rays per edge pixel, and of the
// key light's shadows, as shares of the plain frame's: upper ends of `nurbsrt
// bench --only look` (512 x 512, one thread, three real models: anti-aliasing
// 4 with feature lines took 0.37-0.99 of the plain frame more, shadows
// 0.29-0.57 more). Anti-aliasing scales with its ray count; the samples are
// shaded with shadows too, so the two multiply.
constexpr double kAntialiasWorkAt4 = 1.0;
constexpr double kShadowWork = 0.6;
// Anti-aliasing's edge flag, and the shadow AOV, per pixel.
constexpr size_t kAntialiasBytesPerPixel = sizeof(uint8_t);
constexpr size_t kShadowBytesPerPixel = sizeof(uint8_t);

}  // namespace

FrameCost estimate_frame_cost(const PreparedScene& prepared, int width, int height, FrameCostOptions options) {
    const Scene& scene = prepared.scene();
    const MapMesh& map = prepared.map_mesh();
    const double pixels = double(width) * double(height);

    // Per-face evaluation cost, weighted by the face's share of map vertices.
    std::vector<double> weight(scene.faces.size() + 1, 0.0);
    for (uint32_t f : map.face)
        if (f < weight.size()) weight[f] += 1.0;
    double weighted = 0, total_weight = 0, projected_bytes = 0;
    for (const Face& f : scene.faces) {
        const NurbsSurface& s = f.surface;
        const double eval = double(s.degree_u + 1) * double(s.degree_v + 1);
        const double w = f.index < weight.size() ? weight[f.index] + 1.0 : 1.0;
        weighted += w * eval;
        total_weight += w;
        // proposed projects a face's patches where it has them, else its control points.
        const SurfacePatches& patches = prepared.faces()[f.index - 1].patches;
        projected_bytes += patches.usable() ? double(patches.coef.size()) * sizeof(Vec4)
                                            : double(s.cp.size()) * sizeof(Vec4) +
                                                  double(s.knots_u.size() + s.knots_v.size()) * sizeof(double);
    }
    const double eval_cost = total_weight > 0 ? weighted / total_weight : kBicubicEvalCost;

    FrameCost c;
    const double per_pixel =
        kImageBytesPerPixel + kSolveBytesPerPixel + kRescueBytesPerPixel + kMapBytesPerPixel + kEncodeBytesPerPixel;
    const auto band_pixels = [](double px) { return std::min(px, double(kMapBandPixels)); };
    // Every term above is already a worst case (all candidate lists full), so no slack factor:
    // measured peaks were 0.4-0.65 of this at 1024x768 and more.
    const double bytes = pixels * per_pixel + band_pixels(pixels) * kFramebufferBytesPerPixel + projected_bytes +
                         double(map.xyz.size()) * kBytesPerMapVertex;
    double extra_bytes = 0;
    double work_factor = 1;
    if (options.antialias > 0) {
        extra_bytes += pixels * kAntialiasBytesPerPixel;
        work_factor *= 1 + kAntialiasWorkAt4 * options.antialias / 4.0;
    }
    if (options.shadows) {
        // The light's own map (as the view's: map, framebuffer, clip positions,
        // the surfaces projected for it) and the shadow AOV.
        const double light = double(light_map_size(width, height));
        extra_bytes += light * light * kMapBytesPerPixel + band_pixels(light * light) * kFramebufferBytesPerPixel +
                       projected_bytes + double(map.xyz.size()) * kBytesPerMapVertex + pixels * kShadowBytesPerPixel;
        work_factor *= 1 + kShadowWork;
    }
    c.memory_bytes = kFixedBytes + static_cast<size_t>(bytes + extra_bytes);
    c.core_seconds = work_factor * (pixels * (kSecondsPerPixel + kSecondsPerBasisProduct * eval_cost) +
                                    double(map.triangles()) * kSecondsPerTriangle);
    return c;
}

}  // namespace nurbsrt
