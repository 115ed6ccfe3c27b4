// Shading from the exact normal (the last Newton iteration's partials), and the AOVs.
#include <algorithm>
#include <limits>

#include "renderer/nurbs.h"
#include "renderer/passes.h"

namespace nurbsrt {

namespace {

// A fixed two-light rig, so every view of a model reads alike: ambient, a key
// light from the upper left behind the viewer, and a headlight along the ray
// (lights faces seen edge-on to the key light). The weights sum to 1.05: a face
// facing both lights saturates slightly, the rest stays below 1.
constexpr double kAmbient = 0.15, kKey = 0.55, kHeadlight = 0.35;

}  // namespace

Shader::Shader(const FrameContext& c)
    : scene_(c.scene),
      key_(normalize(-1.0 * c.camera.forward() + 0.6 * c.camera.up() - 0.5 * c.camera.right())) {}

Vec3 Shader::colour(const PixelHit& h, Vec3 dir, Vec3& n) const {
    const Face& f = scene_.faces[h.face - 1];
    // The solve's normal (exact at the double-precision hit); the limits of
    // surface_normal only where its partials were degenerate.
    n = {h.nx, h.ny, h.nz};
    if (n.x == 0 && n.y == 0 && n.z == 0) n = surface_normal(f.surface, h.u, h.v, f.reversed);
    if (dot(n, dir) > 0) n = -n;  // two-sided: light the side facing the viewer
    Color col = f.color;
    if (!f.has_color && f.body < scene_.bodies.size() && scene_.bodies[f.body].has_color)
        col = scene_.bodies[f.body].color;
    const double lambert = kAmbient + kKey * std::max(0.0, dot(n, key_)) + kHeadlight * std::max(0.0, -dot(n, dir));
    return {col.r * lambert, col.g * lambert, col.b * lambert};
}

void shade_pass(const FrameContext& c, const FrameBuffers& b, RenderImage& img) {
    const size_t npx = c.pixels();
    const Camera& camera = c.camera;
    const RenderOptions& options = c.options;
    img.width = c.width;
    img.height = c.height;
    img.rgba.assign(4 * npx, 0.0f);
    img.z.assign(npx, std::numeric_limits<float>::infinity());
    img.normal.assign(3 * npx, 0.0f);
    img.face.assign(npx, 0);
    img.u.assign(npx, 0.0f);
    img.v.assign(npx, 0.0f);
    img.iterations.assign(npx, 0);
    const Shader shader(c);
    parallel_rows(c, true, [&](int j) {
        for (int i = 0; i < c.width; ++i) {
            const size_t k = c.map.index(i, j);
            const PixelHit& h = b.hits[k];
            float* px = &img.rgba[4 * k];
            img.iterations[k] = h.iterations;
            if (!h.face) {
                px[0] = options.background.r;
                px[1] = options.background.g;
                px[2] = options.background.b;
                px[3] = options.background_alpha;
                continue;
            }
            Vec3 n;
            const Vec3 rgb = shader.colour(h, camera.pixel_ray(i, j).dir, n);
            px[0] = static_cast<float>(rgb.x);
            px[1] = static_cast<float>(rgb.y);
            px[2] = static_cast<float>(rgb.z);
            px[3] = 1.0f;
            img.z[k] = static_cast<float>(h.t);
            img.normal[3 * k] = static_cast<float>(n.x);
            img.normal[3 * k + 1] = static_cast<float>(n.y);
            img.normal[3 * k + 2] = static_cast<float>(n.z);
            img.face[k] = h.face;
            img.u[k] = h.u;
            img.v[k] = h.v;
        }
    });
}

}  // namespace nurbsrt
