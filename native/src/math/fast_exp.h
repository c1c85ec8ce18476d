// exp(x) for x ≤ 0 and log(x) for x ≥ 1 in forms the compiler vectorizes: EM's responsibilities
// and log-likelihoods need millions of them per level, and only to single precision.
#pragma once

#include <bit>
#include <cstdint>

namespace ndfbake {

// Below this e^x is flushed to 0: e^-80 is 1.8e-35, nothing beside a log-sum-exp's largest term
// (1), and a responsibility that small times a coordinate would be a denormal, which costs the
// FPU a hundred cycles per operation (measured: EM on 14 samples ran 1.8x slower with them).
inline constexpr float kFastExpMin = -80.0f;

// e^x = 2^i · 2^f with t = x·log₂e = i + f, f ∈ [0, 1); 2^f by a degree-5 polynomial (relative
// error under 2e-7, below float's own rounding of the result). Valid for x ≤ 0; x < kFastExpMin
// (including −∞ and NaN) gives 0.
inline float fast_exp_nonpositive(float x)
{
    const float t = (x > kFastExpMin ? x : kFastExpMin) * 1.44269504f;
    int32_t i = int32_t(t);
    i -= (t < float(i)) ? 1 : 0;  // floor for negative t
    const float f = t - float(i);
    const float p = 1.0f + f * (0.693147182f + f * (0.240226507f + f * (0.0555041086f +
                                f * (0.00961812911f + f * 0.00133335581f))));
    return x > kFastExpMin ? p * std::bit_cast<float>(uint32_t(i + 127) << 23) : 0.0f;
}

// log x = e·ln 2 + log m with x = m·2^e, m ∈ [√½, √2); log m = 2 atanh s with s = (m − 1)/(m + 1),
// |s| ≤ 0.172, by its series to s⁹ (error under 2e-8). For finite x ≥ 1: a log-sum-exp's sum,
// whose largest term is 1.
inline float fast_log_at_least_one(float x)
{
    const uint32_t bits = std::bit_cast<uint32_t>(x);
    int32_t e = int32_t(bits >> 23) - 127;
    float m = std::bit_cast<float>((bits & 0x007fffffu) | 0x3f800000u);  // x / 2^e ∈ [1, 2)
    const bool halve = m > 1.41421356f;
    m = halve ? 0.5f * m : m;
    e += halve ? 1 : 0;
    const float s = (m - 1.0f) / (m + 1.0f), s2 = s * s;
    const float series = s * (2.0f + s2 * (0.666666667f + s2 * (0.4f + s2 * (0.285714286f + s2 * 0.222222222f))));
    return float(e) * 0.693147181f + series;
}

}  // namespace ndfbake
