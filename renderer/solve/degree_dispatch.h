// Calls a surface evaluator with the degrees as template arguments where they
// are among the common ones, so that its basis and tensor-product loops unroll
// (span_basis.cpp, surface_patches.cpp); -1 stands for a degree read at run time.
#pragma once

namespace nurbsrt::degree_dispatch {

// Degrees up to this in both directions get a fully unrolled evaluation (CAD
// surfaces are mostly of degree 1-3: planes, cylinders, cones, bicubic
// free-form). So do, up to kMaxUnrolled: degree 1 in one direction (NURBS
// conversion of extrusions and ruled faces gives 1 x 5-11 and 5-11 x 1, often
// a large share of a part's pixels), and equal degrees (free-form faces
// approximated to 5 x 5 or 7 x 7). Otherwise the v degree alone (the contiguous
// inner loop of a tensor product) up to kMaxUnrolled.
constexpr int kMaxUnrolledBoth = 3;
constexpr int kMaxUnrolled = 11;

// Which degree `one` unrolls besides the one it searches (kD).
enum class Unrolled { u_linear, v_linear, square, v_only };

template <class F, int kP, int kQ, class... A>
auto both(int p, int q, const A&... a) {
    if constexpr (kQ > kMaxUnrolledBoth) {
        return both<F, kP + 1, 1>(p, q, a...);
    } else if constexpr (kP > kMaxUnrolledBoth) {
        return F::template run<-1, -1>(a...);  // not reached: the caller checked the degrees
    } else {
        if (p == kP && q == kQ) return F::template run<kP, kQ>(a...);
        return both<F, kP, kQ + 1>(p, q, a...);
    }
}

template <class F, Unrolled kMode, int kD, class... A>
auto one(int p, int q, const A&... a) {
    if constexpr (kD > kMaxUnrolled) {
        return F::template run<-1, -1>(a...);  // not reached: the caller checked the degree
    } else {
        constexpr int kP = kMode == Unrolled::u_linear ? 1 : kMode == Unrolled::v_only ? -1 : kD;
        constexpr int kQ = kMode == Unrolled::v_linear ? 1 : kD;
        if ((kMode == Unrolled::v_linear ? p : q) == kD) return F::template run<kP, kQ>(a...);
        return one<F, kMode, kD + 1>(p, q, a...);
    }
}

// F::run<kP, kQ>(a...) for degrees p (u) and q (v).
template <class F, class... A>
auto with_degrees(int p, int q, const A&... a) {
    if (p >= 1 && p <= kMaxUnrolledBoth && q >= 1 && q <= kMaxUnrolledBoth) return both<F, 1, 1>(p, q, a...);
    if (p == 1 && q >= 1 && q <= kMaxUnrolled) return one<F, Unrolled::u_linear, 1>(p, q, a...);
    if (q == 1 && p >= 1 && p <= kMaxUnrolled) return one<F, Unrolled::v_linear, 1>(p, q, a...);
    if (p == q && q > kMaxUnrolledBoth && q <= kMaxUnrolled)
        return one<F, Unrolled::square, kMaxUnrolledBoth + 1>(p, q, a...);
    if (q >= 1 && q <= kMaxUnrolled) return one<F, Unrolled::v_only, 1>(p, q, a...);
    return F::template run<-1, -1>(a...);
}

}  // namespace nurbsrt::degree_dispatch
