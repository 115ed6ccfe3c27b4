// Where a pixel's anti-aliasing samples lie: stratified positions in the
// pixel square, randomized per pixel (pass_antialias.cpp).
#pragma once

#include <cstdint>

namespace nurbsrt {

namespace sample_pattern_detail {

// The bits of s in reverse order.
inline uint32_t reverse_bits(uint32_t s) {
    s = (s << 16) | (s >> 16);
    s = ((s & 0x00ff00ffu) << 8) | ((s & 0xff00ff00u) >> 8);
    s = ((s & 0x0f0f0f0fu) << 4) | ((s & 0xf0f0f0f0u) >> 4);
    s = ((s & 0x33333333u) << 2) | ((s & 0xccccccccu) >> 2);
    return ((s & 0x55555555u) << 1) | ((s & 0xaaaaaaaau) >> 1);
}

// x mod 1 for x in [0, 2).
inline double wrap01(double x) { return x >= 1.0 ? x - 1.0 : x; }

}  // namespace sample_pattern_detail

// A per-pixel hash for the randomization of the sample pattern, so that
// neighbouring edge pixels do not share one pattern (which would turn the
// residual error into a visible regular texture along an edge). Deterministic:
// the image does not depend on threads or runs. (A 32-bit integer hash after
// Wellons' "hash prospector", lowbias32.)
inline uint32_t hash32(uint32_t x) {
    x ^= x >> 16;
    x *= 0x7feb352du;
    x ^= x >> 15;
    x *= 0x846ca68bu;
    x ^= x >> 16;
    return x;
}

// Sample s of n in the pixel square [0, 1)^2, randomized by the pixel's seed.
// The Hammersley points ((s + 0.5) / n, radical inverse of s): for n a power of
// two a (0, m, 2)-net in base 2 (every elementary box of area 1/n, e.g. each
// column 1/n wide and each row 1/n high, holds one point). Randomized by random
// digit scrambling (Matousek 1998: an XOR of the pixel's mask with the digits,
// which keeps the net) and a jitter within the point's column, which gave a
// smaller coverage error than rotating the points modulo 1 (Cranley & Patterson
// 1976), which other n keep.
inline void sample_position(int s, int n, uint32_t seed, double& x, double& y) {
    using sample_pattern_detail::reverse_bits, sample_pattern_detail::wrap01;
    const uint32_t us = static_cast<uint32_t>(s), un = static_cast<uint32_t>(n);
    if ((un & (un - 1)) == 0) {
        const uint32_t jitter = hash32(seed ^ (0x9e3779b9u * (us + 1))) & 0xffffu;
        x = ((us ^ (seed & (un - 1))) + jitter * 0x1p-16) / n;
        y = (reverse_bits(us) ^ (seed >> 1)) * 0x1p-32;
        return;
    }
    x = wrap01((s + 0.5) / n + (seed & 0xffffu) * 0x1p-16);
    y = wrap01(reverse_bits(us) * 0x1p-32 + (seed >> 16) * 0x1p-16);
}

}  // namespace nurbsrt
