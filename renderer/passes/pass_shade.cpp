// Shading from the exact normal (the last Newton iteration's partials), and the AOVs.
#include <algorithm>
#include <cmath>
#include <limits>

#include "core/scene/nurbs.h"
#include "renderer/passes/passes.h"

namespace nurbsrt {

namespace {

// Weights of the rig (lighting.h). Key and fill lie about 75 degrees apart, so no
// normal faces both fully: a face turned between them gets ~0.7 of its colour
// from the two, plus the ambient term, and stays below saturation; the key's
// side is the brighter by 2:1, a usual key-to-fill ratio.
constexpr double kKey = 0.6, kFill = 0.3;
// Ambient light on faces turned to the camera's up and down; between them it
// follows the normal (a hemisphere light), so even unlit sides show their form.
constexpr double kAmbientSky = 0.18, kAmbientGround = 0.06;
// A white Blinn-Phong highlight of the key light (Blinn 1977): curvature reads
// from how it stretches along a fillet or a cylinder. Small and tight, so flat
// faces keep their colour.
constexpr double kSpecular = 0.12;
constexpr int kShininess = 40;

// x^N by repeated squaring: std::pow (a log and an exp) took a quarter of the
// shading pass; the product differs from it in the last bits only.
template <int N>
double power(double x) {
    if constexpr (N == 0) {
        return 1.0;
    } else {
        const double h = power<N / 2>(x);
        return N % 2 ? h * h * x : h * h;
    }
}

}  // namespace

Shader::Shader(const FrameContext& c, const KeyLightShadows* shadows)
    : scene_(c.scene),
      options_(c.options),
      ground_z_(c.options.ground_height.value_or(c.bbox.lo.z)),
      face_colors_(c.options.face_colors),
      caps_(c.scene, c.options, c.map),
      rig_(light_rig(c.camera)),
      shadows_(shadows) {}

Vec3 Shader::colour(const PixelHit& h, const Ray& ray, Vec3& n, bool* shadowed, CapHit* cap, size_t pixel) const {
    CapHit found;
    if (caps_.find(h, ray, pixel, found)) {
        if (cap) *cap = found;
        n = found.normal;
        // A cap point lies on no face: face 0 leaves out the shadow test's own-face shortcut.
        return lit(caps_.colour(found, ray), ray.origin + found.t * ray.dir, n, ray, 0, 0, 0, shadowed);
    }
    if (cap) cap->plane = -1;
    const Face& f = scene_.faces[h.face - 1];
    // The solve's normal (exact at the double-precision hit); the limits of
    // surface_normal only where its partials were degenerate.
    n = {h.nx, h.ny, h.nz};
    if (n.x == 0 && n.y == 0 && n.z == 0) n = surface_normal(f.surface, h.u, h.v, f.reversed);
    if (dot(n, ray.dir) > 0) n = -n;  // two-sided: light the side facing the viewer
    Color col = f.color;
    if (!f.has_color && f.body < scene_.bodies.size() && scene_.bodies[f.body].has_color)
        col = scene_.bodies[f.body].color;
    if (!face_colors_.empty() && face_colors_[h.face - 1]) col = *face_colors_[h.face - 1];
    return lit(col, ray.origin + h.t * ray.dir, n, ray, h.face, h.u, h.v, shadowed);
}

Vec3 Shader::lit(Color col, Vec3 p, Vec3 n, const Ray& ray, uint32_t face, double u, double v, bool* shadowed) const {
    const bool blocked = shadows_ && shadows_->blocked(p, n, face, u, v);
    if (shadowed) *shadowed = blocked;
    const double key = blocked ? 0.0 : std::max(0.0, dot(n, rig_.key));
    const double ambient = kAmbientGround + (kAmbientSky - kAmbientGround) * 0.5 * (1 + dot(n, rig_.sky));
    const double diffuse = ambient + kKey * key + kFill * std::max(0.0, dot(n, rig_.fill));
    double specular = 0;
    if (key > 0) {
        const Vec3 half = normalize(rig_.key - ray.dir);  // between the light and the viewer
        specular = kSpecular * power<kShininess>(std::max(0.0, dot(n, half)));
    }
    return {col.r * diffuse + specular, col.g * diffuse + specular, col.b * diffuse + specular};
}

bool Shader::background(const Ray& ray, float rgba[4], bool* shadowed) const {
    const RenderOptions& o = options_;
    rgba[0] = o.background.r;
    rgba[1] = o.background.g;
    rgba[2] = o.background.b;
    rgba[3] = o.background_alpha;
    if (shadowed) *shadowed = false;
    if (!o.ground || ray.dir.z == 0) return false;
    const double t = (ground_z_ - ray.origin.z) / ray.dir.z;
    if (!(t > 0) || !std::isfinite(t)) return false;
    bool blocked = false;
    const Vec3 p = ray.origin + t * ray.dir, up{0, 0, 1};
    if (o.background_alpha > 0) {  // a floor: lit like a face
        Vec3 n = dot(up, ray.dir) > 0 ? -1.0 * up : up;
        const Vec3 rgb = lit(kGroundColor, p, n, ray, 0, 0, 0, &blocked);
        rgba[0] = static_cast<float>(rgb.x);
        rgba[1] = static_cast<float>(rgb.y);
        rgba[2] = static_cast<float>(rgb.z);
        rgba[3] = 1.0f;
    } else {  // a shadow catcher: only its shadow shows
        blocked = shadows_ && dot(up, ray.dir) < 0 && shadows_->blocked(p, up, 0, 0, 0);
        if (blocked) rgba[0] = rgba[1] = rgba[2] = 0.0f, rgba[3] = kShadowCatcherAlpha;
    }
    if (shadowed) *shadowed = blocked;
    return true;
}

void shade_pass(const FrameContext& c, const Shader& shader, const FrameBuffers& b, RenderImage& img) {
    const size_t npx = c.pixels();
    const Camera& camera = c.camera;
    img.width = c.width;
    img.height = c.height;
    assign_cancelable(img.rgba, 4 * npx, 0.0f, c);
    assign_cancelable(img.z, npx, std::numeric_limits<float>::infinity(), c);
    assign_cancelable(img.normal, 3 * npx, 0.0f, c);
    assign_cancelable(img.face, npx, uint32_t(0), c);
    assign_cancelable(img.u, npx, 0.0f, c);
    assign_cancelable(img.v, npx, 0.0f, c);
    assign_cancelable(img.iterations, npx, uint8_t(0), c);
    if (shader.shadows()) assign_cancelable(img.shadow, npx, uint8_t(0), c);
    parallel_rows(c, true, [&](int j) {
        for (int i = 0; i < c.width; ++i) {
            const size_t k = c.map.index(i, j);
            const PixelHit& h = b.hits[k];
            float* px = &img.rgba[4 * k];
            img.iterations[k] = h.iterations;
            if (!h.face) {
                bool shadowed = false;
                if (shader.background(camera.pixel_ray(i, j), px, &shadowed) && shadowed) img.shadow[k] = 1;
                continue;
            }
            Vec3 n;
            bool shadowed = false;
            CapHit cap;
            const Vec3 rgb = shader.colour(h, camera.pixel_ray(i, j), n, &shadowed, &cap, k);
            if (shadowed) img.shadow[k] = 1;
            px[0] = static_cast<float>(rgb.x);
            px[1] = static_cast<float>(rgb.y);
            px[2] = static_cast<float>(rgb.z);
            px[3] = 1.0f;
            img.normal[3 * k] = static_cast<float>(n.x);
            img.normal[3 * k + 1] = static_cast<float>(n.y);
            img.normal[3 * k + 2] = static_cast<float>(n.z);
            if (cap.plane >= 0) {  // a cap: its depth and body (render.h kCapFace), no (u, v)
                img.z[k] = static_cast<float>(cap.t);
                img.face[k] = kCapFace + cap.body;
                continue;
            }
            img.z[k] = static_cast<float>(h.t);
            img.face[k] = h.face;
            img.u[k] = h.u;
            img.v[k] = h.v;
        }
    });
}

}  // namespace nurbsrt
