// SurfacePatches: a surface's polynomial patches in power form (see surface_patches.h).
#include "renderer/solve/surface_patches.h"

#include "renderer/solve/degree_dispatch.h"

namespace nurbsrt {

namespace {

// Coefficients per face above which no patches are made: 8 MB (a face of
// 100 x 160 bicubic spans, well above the densest real faces, such as a helical
// coil's); the cap keeps a hostile file's single face from multiplying its
// control points' memory by (p+1)(q+1).
constexpr size_t kMaxPatchCoefficients = size_t(1) << 18;

struct PatchEvaluation {
    template <int kP, int kQ>
    static SurfaceDerivs run(const SurfacePatches& t, const SurfaceSpans& spans, double u, double v) {
        const int p = kP >= 0 ? kP : t.degree_u, q = kQ >= 0 ? kQ : t.degree_v;
        double x, y;
        const size_t k = spans.u.locate(u, x), l = spans.v.locate(v, y);
        const Vec4* c = t.coef.data() + (k * t.spans_v + l) * static_cast<size_t>((p + 1) * (q + 1));
        // Row a of the patch, sum_b C_ab y^b, and its y derivative, by Horner.
        auto row = [&](int a, Vec4& r, Vec4& dr) {
            const Vec4* ca = c + a * (q + 1);
            r = ca[q];
            dr = Vec4{};
            for (int b = q - 1; b >= 0; --b) {
                dr = y * dr + r;
                r = y * r + ca[b];
            }
        };
        // Then Horner in x over the rows, with the x derivative alongside.
        Vec4 S, Sv, Su{};
        row(p, S, Sv);
        for (int a = p - 1; a >= 0; --a) {
            Vec4 r, dr;
            row(a, r, dr);
            Su = x * Su + S;
            S = x * S + r;
            Sv = x * Sv + dr;
        }
        return {S, spans.u.inv_half(k) * Su, spans.v.inv_half(l) * Sv};
    }
};

}  // namespace

size_t patch_coefficients(const NurbsSurface& s, const SurfaceSpans& spans) {
    if (!spans.usable()) return 0;
    const size_t nk = spans.u.spans(), nl = spans.v.spans();
    const size_t size = static_cast<size_t>((s.degree_u + 1) * (s.degree_v + 1));
    return nk * nl > kMaxPatchCoefficients / size ? 0 : nk * nl * size;
}

SurfacePatches make_surface_patches(const NurbsSurface& s, const SurfaceSpans& spans) {
    SurfacePatches t;
    const size_t n = patch_coefficients(s, spans);
    if (!n) return t;
    const int p = s.degree_u, q = s.degree_v;
    const size_t nk = spans.u.spans(), nl = spans.v.spans(), size = static_cast<size_t>((p + 1) * (q + 1));
    t.degree_u = p;
    t.degree_v = q;
    t.spans_v = nl;
    t.coef.resize(n);
    std::vector<Vec4> rows(static_cast<size_t>(p + 1) * (q + 1));  // T_ib = sum_j c_v[j][b] P_ij
    for (size_t k = 0; k < nk; ++k) {
        const double* cu = spans.u.coefficients(k);
        const int i0 = spans.u.knot_index(k) - p;
        for (size_t l = 0; l < nl; ++l) {
            const double* cv = spans.v.coefficients(l);
            const int j0 = spans.v.knot_index(l) - q;
            for (int i = 0; i <= p; ++i)
                for (int b = 0; b <= q; ++b) {
                    Vec4 sum{};
                    for (int j = 0; j <= q; ++j)
                        sum += cv[j * (q + 1) + b] * s.cp[static_cast<size_t>(i0 + i) * s.num_v + (j0 + j)];
                    rows[static_cast<size_t>(i * (q + 1) + b)] = sum;
                }
            Vec4* c = t.coef.data() + (k * nl + l) * size;
            for (int a = 0; a <= p; ++a)
                for (int b = 0; b <= q; ++b) {
                    Vec4 sum{};
                    for (int i = 0; i <= p; ++i)
                        sum += cu[i * (p + 1) + a] * rows[static_cast<size_t>(i * (q + 1) + b)];
                    c[a * (q + 1) + b] = sum;
                }
        }
    }
    return t;
}

// The kernel of every Newton step (a quarter of a frame's instructions) is also
// compiled for x86-64-v3 (AVX2 and FMA) and chosen when the library loads (GCC
// function multiversioning, "default" elsewhere), with the degree dispatch and
// its unrolled loops inlined (flatten): a Vec4 takes one 256-bit register, and
// each Horner step y * r + c is one fused multiply-add, which shortens the
// chains of dependent operations that bound this loop (AVX2 without FMA did
// not). A fused multiply-add rounds once, so results may differ from the
// default build's in the last bit (docs/BENCHMARKS.md).
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
#define NURBSRT_EVALUATION_CLONES __attribute__((target_clones("arch=x86-64-v3", "default"), flatten))
#else
#define NURBSRT_EVALUATION_CLONES
#endif

NURBSRT_EVALUATION_CLONES
SurfaceDerivs evaluate_d1(const SurfacePatches& patches, const SurfaceSpans& spans, double u, double v) {
    return degree_dispatch::with_degrees<PatchEvaluation>(patches.degree_u, patches.degree_v, patches, spans, u, v);
}

SurfacePatches project_patches(const Camera& camera, const SurfacePatches& patches) {
    SurfacePatches out;
    out.degree_u = patches.degree_u;
    out.degree_v = patches.degree_v;
    out.spans_v = patches.spans_v;
    out.coef.resize(patches.coef.size());
    for (size_t k = 0; k < patches.coef.size(); ++k) out.coef[k] = camera.project_h(patches.coef[k]);
    return out;
}

}  // namespace nurbsrt
