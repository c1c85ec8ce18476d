// exp(x) for x ≤ 0 in a form the compiler vectorizes: EM's responsibilities need millions of them
// per level, and only to single precision.
#pragma once

#include <bit>
#include <cstdint>

namespace ndfbake {

// Below this 2^x would leave float's normal range; e^-87 is 1.6e-38, zero for every sum it joins.
inline constexpr float kFastExpMin = -87.0f;

// e^x = 2^i · 2^f with t = x·log₂e = i + f, f ∈ [0, 1); 2^f by a degree-5 polynomial (relative
// error under 2e-7, below float's own rounding of the result). Valid for x ≤ 0; x < kFastExpMin
// (including −∞) gives e^kFastExpMin.
inline float fast_exp_nonpositive(float x)
{
    const float t = (x > kFastExpMin ? x : kFastExpMin) * 1.44269504f;
    int32_t i = int32_t(t);
    i -= (t < float(i)) ? 1 : 0;  // floor for negative t
    const float f = t - float(i);
    const float p = 1.0f + f * (0.693147182f + f * (0.240226507f + f * (0.0555041086f +
                                f * (0.00961812911f + f * 0.00133335581f))));
    return p * std::bit_cast<float>(uint32_t(i + 127) << 23);
}

}  // namespace ndfbake
