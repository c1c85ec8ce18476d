// Small deterministic random numbers for the synthetic patterns. The generators are written out here
// rather than taken from <random>: std:: distributions differ between standard libraries, and a
// synthetic map must come out bit-identical for a given seed on every platform.
#pragma once

#include <cstdint>

namespace ndfbake {

// SplitMix64's finalizer (Steele et al. 2014): a bijective 64-bit mix, good enough to hash lattice
// coordinates into independent-looking values.
constexpr uint64_t mix64(uint64_t z)
{
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return z ^ (z >> 31);
}

// Maps 64 random bits to [0, 1) using the top 53, so every double is exact.
constexpr double bits_to_unit(uint64_t bits) { return double(bits >> 11) * 0x1.0p-53; }

class SplitMix64 {
public:
    explicit constexpr SplitMix64(uint64_t seed) : state_(seed) {}

    constexpr uint64_t next()
    {
        state_ += kIncrement;
        return mix64(state_);
    }
    constexpr double uniform() { return bits_to_unit(next()); }
    constexpr double uniform(double lo, double hi) { return lo + (hi - lo) * uniform(); }

private:
    static constexpr uint64_t kIncrement = 0x9e3779b97f4a7c15ull;  // 2^64 / golden ratio
    uint64_t state_;
};

}  // namespace ndfbake
