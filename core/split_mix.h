// SplitMix64 (Steele, Lea & Flood 2014): a fixed, portable pseudo-random
// sequence for samples that must be the same on every machine and library
// (the std distributions are implementation-defined).
#pragma once

#include <cstdint>

namespace nurbsrt {

struct SplitMix64 {
    uint64_t state;
    uint64_t next() {
        uint64_t z = (state += 0x9E3779B97F4A7C15ull);
        z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
        z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
        return z ^ (z >> 31);
    }
    // In [0, n) (n > 0), by the remainder: bias below 2^-40 for the n used here.
    int below(int n) { return static_cast<int>(next() % static_cast<uint64_t>(n)); }
};

}  // namespace nurbsrt
