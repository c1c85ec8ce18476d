#include "math/brdf.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <limits>
#include <numbers>

#include "error.h"
#include "math/fast_exp.h"
#include "math/vmf.h"

namespace ndfbake {

namespace {

constexpr float kInvPi = float(std::numbers::inv_pi);

// GGX's d = c²(α² − 1) + 1, written α²c² + (1 − c)(1 + c): the same number, but at small α the
// written form's α² − 1 rounds to −1 in float and d to 0 at c = 1 (D infinite below roughness
// 0.013, 20% off at 0.02); this one stays exact near the peak, where D = 1/(πα²).
inline float ggx_denominator(float c, float a2) { return a2 * c * c + (1.0f - c) * (1.0f + c); }

// Legendre coefficients a_l of max(c, 0) = Σ a_l P_l(c):
// a_l = (2l+1)/2 ∫₀¹ c P_l(c) dc; ∫₀¹ c P_l = 1/2, 1/3 (l = 0, 1), 0 for odd l ≥ 3, and
// (−1)^{l/2+1} (l−2)! / (2^l (l/2−1)! (l/2+1)!) for even l ≥ 2.
const std::array<double, kLambertBands + 1>& clamped_cosine_legendre()
{
    static const std::array<double, kLambertBands + 1> coefficients = [] {
        std::array<double, kLambertBands + 1> a{};
        a[0] = 0.5 * 0.5;
        a[1] = 1.5 / 3.0;
        for (int l = 2; l <= kLambertBands; l += 2) {
            // lgamma keeps the factorials finite for large l.
            const double log_mag = std::lgamma(l - 1.0) - l * std::log(2.0) - std::lgamma(l / 2.0) -
                                   std::lgamma(l / 2.0 + 2.0);
            const double sign = ((l / 2 + 1) % 2 == 0) ? 1.0 : -1.0;
            a[size_t(l)] = (2.0 * l + 1.0) / 2.0 * sign * std::exp(log_mag);
        }
        return a;
    }();
    return coefficients;
}

float normalized_blinn_phong(float c, float s)
{
    if (c <= 0.0f) return 0.0f;
    return (s + 1.0f) * (0.5f * kInvPi) * std::exp(s * std::log(c));
}

float ggx_distribution(float c, float alpha)
{
    if (c <= 0.0f) return 0.0f;
    const float a2 = alpha * alpha;
    const float d = ggx_denominator(c, a2);
    return a2 * kInvPi / (d * d);
}

float beckmann_distribution(float c, float m)
{
    if (c <= 0.0f) return 0.0f;
    const float c2 = c * c, m2 = m * m;
    const float tan2 = (1.0f - c2) / c2;
    // Near the horizon the exponential underflows to 0 while c^4 does too: 0/0. D -> 0 there.
    const float falloff = std::exp(-tan2 / m2);
    if (falloff == 0.0f) return 0.0f;
    return falloff * kInvPi / (m2 * c2 * c2);
}

// fast_log_positive needs a normal float: eval_many raises smaller positive cosines to this
// (c^s changes by (FLT_MIN/c)^s, 0 in float for s ≥ 1 and under 1% for the s ≥ 1e-3 of a
// Blinn-Phong lobe convolved with a vMF of κ ≥ kKappaMin).
constexpr float kMinEvalManyCosine = std::numeric_limits<float>::min();

// (s + 1)/(2π) c^s and its derivative s · f / c, vectorized.
void blinn_phong_many(std::span<const float> c, float s, std::span<float> value, std::span<float> slope)
{
    const float scale = (s + 1.0f) * (0.5f * kInvPi);
    const size_t n = c.size();
    const float* x = c.data();
    float* v = value.data();
#pragma omp simd
    for (size_t i = 0; i < n; ++i) {
        const float c_lit = x[i] > kMinEvalManyCosine ? x[i] : kMinEvalManyCosine;
        v[i] = x[i] > 0.0f ? scale * fast_exp_nonpositive(s * fast_log_positive(c_lit)) : 0.0f;
    }
    if (slope.empty()) return;
    float* d = slope.data();
#pragma omp simd
    for (size_t i = 0; i < n; ++i) d[i] = x[i] > 0.0f ? s * v[i] / (x[i] > kMinEvalManyCosine ? x[i] : kMinEvalManyCosine) : 0.0f;
}

// amplitude · α²/(π d²), d = c²(α² − 1) + 1, and its derivative −4c(α² − 1) D / d, vectorized.
void ggx_many(std::span<const float> c, float alpha, float amplitude, std::span<float> value, std::span<float> slope)
{
    const float a2 = alpha * alpha, scale = amplitude * a2 * kInvPi;
    const size_t n = c.size();
    const float* x = c.data();
    float* v = value.data();
    float* ds = slope.empty() ? nullptr : slope.data();
#pragma omp simd
    for (size_t i = 0; i < n; ++i) {
        const float cc = x[i] > 0.0f ? x[i] : 0.0f;
        const float d = ggx_denominator(cc, a2);
        v[i] = x[i] > 0.0f ? scale / (d * d) : 0.0f;
    }
    if (!ds) return;
#pragma omp simd
    for (size_t i = 0; i < n; ++i) {
        const float cc = x[i] > 0.0f ? x[i] : 0.0f;
        const float d = ggx_denominator(cc, a2);
        ds[i] = -4.0f * cc * (a2 - 1.0f) * v[i] / d;
    }
}

// amplitude · exp(−tan²θ/m²)/(π m² c⁴) and its derivative D (2/(m² c³) − 4/c), vectorized.
void beckmann_many(std::span<const float> c, float m, float amplitude, std::span<float> value,
                   std::span<float> slope)
{
    const float m2 = m * m, scale = amplitude * kInvPi;
    const size_t n = c.size();
    const float* x = c.data();
    float* v = value.data();
#pragma omp simd
    for (size_t i = 0; i < n; ++i) {
        // Near the horizon e^(−tan²/m²) underflows to 0 while c⁴ does: D → 0 there, not 0/0.
        const bool lit = x[i] > kMinEvalManyCosine;
        const float cc = lit ? x[i] : 1.0f, c2 = cc * cc;
        const float falloff = lit ? fast_exp_nonpositive(-(1.0f - c2) / (c2 * m2)) : 0.0f;
        v[i] = falloff > 0.0f ? falloff * scale / (m2 * c2 * c2) : 0.0f;
    }
    if (slope.empty()) return;
    float* d = slope.data();
#pragma omp simd
    for (size_t i = 0; i < n; ++i) {
        const float cc = v[i] > 0.0f ? x[i] : 1.0f;
        d[i] = v[i] > 0.0f ? v[i] * (2.0f / (m2 * cc * cc * cc) - 4.0f / cc) : 0.0f;
    }
}

}  // namespace

BaseBrdf BaseBrdf::lambert() { return BaseBrdf(BrdfKind::lambert, 0.0f); }

BaseBrdf BaseBrdf::blinn_phong(float exponent)
{
    if (!(exponent >= kMinBlinnPhongExponent && exponent <= kMaxBlinnPhongExponent))
        throw Error(Status::invalid_argument, "Blinn-Phong exponent must be in [1, 10000], got " +
                                                  std::to_string(exponent));
    return BaseBrdf(BrdfKind::blinn_phong, exponent);
}

BaseBrdf BaseBrdf::ggx(float roughness)
{
    if (!(roughness >= kMinGgxRoughness && roughness <= kMaxGgxRoughness))
        throw Error(Status::invalid_argument,
                    "GGX roughness must be in [0.01, 1], got " + std::to_string(roughness));
    return BaseBrdf(BrdfKind::ggx, roughness);
}

BaseBrdf BaseBrdf::beckmann(float slope)
{
    if (!(slope >= kMinBeckmannSlope && slope <= kMaxBeckmannSlope))
        throw Error(Status::invalid_argument, "Beckmann slope must be in [0.0001, 1], got " + std::to_string(slope));
    return BaseBrdf(BrdfKind::beckmann, slope);
}

BaseBrdf BaseBrdf::parse(const std::string& text)
{
    if (text == "lambert") return lambert();
    const auto colon = text.find(':');
    const std::string name = text.substr(0, colon);
    if (colon != std::string::npos && (name == "blinn-phong" || name == "ggx" || name == "beckmann")) {
        const std::string value = text.substr(colon + 1);
        char* end = nullptr;
        const float parameter = std::strtof(value.c_str(), &end);
        if (!value.empty() && end && *end == '\0') {
            if (name == "ggx") return ggx(parameter);
            if (name == "beckmann") return beckmann(parameter);
            return blinn_phong(parameter);
        }
    }
    throw Error(Status::invalid_argument, "unknown BRDF '" + text +
                                              "': expected lambert, blinn-phong:EXPONENT, ggx:ROUGHNESS or beckmann:SLOPE");
}

std::string BaseBrdf::to_string() const
{
    char buffer[64];
    switch (kind_) {
    case BrdfKind::lambert: return "lambert";
    case BrdfKind::blinn_phong: std::snprintf(buffer, sizeof buffer, "blinn-phong:%g", parameter_); break;
    case BrdfKind::ggx: std::snprintf(buffer, sizeof buffer, "ggx:%g", parameter_); break;
    case BrdfKind::beckmann: std::snprintf(buffer, sizeof buffer, "beckmann:%g", parameter_); break;
    }
    return buffer;
}

float BaseBrdf::eval(float c) const
{
    switch (kind_) {
    case BrdfKind::lambert: return std::max(c, 0.0f) * kInvPi;
    case BrdfKind::blinn_phong: return normalized_blinn_phong(c, parameter_);
    case BrdfKind::ggx: return ggx_distribution(c, parameter_ * parameter_);
    case BrdfKind::beckmann: return beckmann_distribution(c, parameter_);
    }
    return 0.0f;
}

ConvolvedLobe BaseBrdf::convolved(float kappa) const
{
    ConvolvedLobe lobe;
    lobe.kind_ = int(kind_);
    kappa = convolution_kappa(kappa);  // +∞ for a single direction
    switch (kind_) {
    case BrdfKind::lambert: {
        const auto& a = clamped_cosine_legendre();
        std::array<double, kLambertBands + 1> attenuation{};
        vmf_legendre_coefficients(double(kappa), kLambertBands, attenuation.data());
        for (int l = 0; l <= kLambertBands; ++l)
            lobe.lambert_bands_[size_t(l)] = float(a[size_t(l)] * attenuation[size_t(l)]);
        break;
    }
    case BrdfKind::blinn_phong:
        lobe.parameter_ = parameter_ / (1.0f + parameter_ / kappa);  // eq. 20, κs/(κ + s), finite at κ = ∞
        break;
    case BrdfKind::ggx: {
        const float alpha = parameter_ * parameter_;
        // A lobe wider than α = 1 is beyond what Blender's roughness can express; the
        // amplitude then carries the spread the width cannot.
        lobe.parameter_ = std::min(1.0f, std::sqrt(alpha * alpha + kGgxVmfWidening / kappa));
        lobe.amplitude_ = float(ggx_sphere_integral(alpha) / ggx_sphere_integral(lobe.parameter_));
        break;
    }
    case BrdfKind::beckmann:
        // Eq. 21, capped like GGX's: past m = 1 a Beckmann lobe piles up at the horizon instead
        // of widening (relative error 354 at κ = 1e-3 uncapped); the amplitude keeps the integral.
        lobe.parameter_ = std::min(kMaxBeckmannSlope, std::sqrt(parameter_ * parameter_ + 2.0f / kappa));
        lobe.amplitude_ = float(beckmann_sphere_integral(parameter_) / beckmann_sphere_integral(lobe.parameter_));
        break;
    }
    return lobe;
}

float ConvolvedLobe::eval(float c) const
{
    switch (BrdfKind(kind_)) {
    case BrdfKind::lambert: {
        // Σ a_l A_l P_l(c) with the three-term Legendre recurrence.
        float p_prev = 1.0f, p = c;
        float sum = lambert_bands_[0] + lambert_bands_[1] * c;
        for (int l = 1; l < kLambertBands; l += 1) {
            const float p_next = (float(2 * l + 1) * c * p - float(l) * p_prev) / float(l + 1);
            p_prev = p;
            p = p_next;
            sum += lambert_bands_[size_t(l + 1)] * p;
        }
        return std::max(0.0f, sum * kInvPi);
    }
    case BrdfKind::blinn_phong: return normalized_blinn_phong(c, parameter_);
    case BrdfKind::ggx: return amplitude_ * ggx_distribution(c, parameter_);
    case BrdfKind::beckmann: return amplitude_ * beckmann_distribution(c, parameter_);
    }
    return 0.0f;
}

float ConvolvedLobe::slope(float c) const
{
    switch (BrdfKind(kind_)) {
    case BrdfKind::lambert: {
        // Σ a_l A_l P'_l(c), with P'_{l+1} = (l + 1) P_l + c P'_l.
        float p_prev = 1.0f, p = c, dp = 1.0f;
        float sum = lambert_bands_[1];
        for (int l = 1; l < kLambertBands; l += 1) {
            const float dp_next = float(l + 1) * p + c * dp;
            const float p_next = (float(2 * l + 1) * c * p - float(l) * p_prev) / float(l + 1);
            p_prev = p;
            p = p_next;
            dp = dp_next;
            sum += lambert_bands_[size_t(l + 1)] * dp;
        }
        return eval(c) > 0.0f ? sum * kInvPi : 0.0f;
    }
    case BrdfKind::blinn_phong:  // d/dc (s+1)/(2π) c^s = s · f / c
        return c > 0.0f ? parameter_ * normalized_blinn_phong(c, parameter_) / c : 0.0f;
    case BrdfKind::ggx: {  // D = α²/(π d²), d = c²(α² − 1) + 1: D' = −4c(α² − 1) D / d
        if (c <= 0.0f) return 0.0f;
        const float a2 = parameter_ * parameter_;
        const float d = ggx_denominator(c, a2);
        return -4.0f * c * (a2 - 1.0f) * amplitude_ * ggx_distribution(c, parameter_) / d;
    }
    case BrdfKind::beckmann: {  // D = exp(−tan²/m²)/(π m² c⁴): D' = D (2/(m² c³) − 4/c)
        if (c <= 0.0f) return 0.0f;
        const float m2 = parameter_ * parameter_, d = amplitude_ * beckmann_distribution(c, parameter_);
        return d > 0.0f ? d * (2.0f / (m2 * c * c * c) - 4.0f / c) : 0.0f;  // 0 · ∞ where D underflows
    }
    }
    return 0.0f;
}

void ConvolvedLobe::eval_many(std::span<const float> c, std::span<float> value, std::span<float> slope) const
{
    switch (BrdfKind(kind_)) {
    case BrdfKind::blinn_phong: return blinn_phong_many(c, parameter_, value, slope);
    case BrdfKind::ggx: return ggx_many(c, parameter_, amplitude_, value, slope);
    case BrdfKind::beckmann: return beckmann_many(c, parameter_, amplitude_, value, slope);
    case BrdfKind::lambert:  // a recurrence per cosine: no faster in bulk
        for (size_t i = 0; i < c.size(); ++i) {
            value[i] = eval(c[i]);
            if (!slope.empty()) slope[i] = this->slope(c[i]);
        }
        return;
    }
}

void BaseBrdf::eval_many(std::span<const float> c, std::span<float> value) const
{
    switch (kind_) {
    case BrdfKind::blinn_phong: return blinn_phong_many(c, parameter_, value, {});
    case BrdfKind::ggx: return ggx_many(c, parameter_ * parameter_, 1.0f, value, {});
    case BrdfKind::beckmann: return beckmann_many(c, parameter_, 1.0f, value, {});
    case BrdfKind::lambert:
        for (size_t i = 0; i < c.size(); ++i) value[i] = eval(c[i]);
        return;
    }
}

double BaseBrdf::beckmann_sphere_integral(double m)
{
    // With u = tan²θ: ∫ D dω = s ∫₀^∞ e^(−su) √(1 + u) du, s = 1/m², = 1 + (√π/2) m erfcx(1/m)
    // where erfcx(x) = e^(x²) erfc(x); past x = 25 its asymptotic series (e^(x²) overflows later
    // than erfc underflows, but both leave double's range near x = 26).
    const double x = 1.0 / m;
    const double erfcx = x < 25.0 ? std::exp(x * x) * std::erfc(x)
                                  : (1.0 - 0.5 / (x * x) + 0.75 / (x * x * x * x)) / (x * std::sqrt(std::numbers::pi));
    return 1.0 + 0.5 * std::sqrt(std::numbers::pi) * m * erfcx;
}

double BaseBrdf::ggx_sphere_integral(double alpha)
{
    // 2π ∫₀¹ D(c) dc = 1 + α² artanh(k)/k; the series artanh(k)/k = 1 + k²/3 + … near α = 1.
    const double k2 = std::max(0.0, 1.0 - alpha * alpha);
    const double k = std::sqrt(k2);
    const double ratio = k < 1e-4 ? 1.0 + k2 / 3.0 : std::atanh(k) / k;
    return 1.0 + alpha * alpha * ratio;
}

float BaseBrdf::angular_width() const
{
    switch (kind_) {
    case BrdfKind::lambert: return 1.0f;
    case BrdfKind::blinn_phong: return 1.0f / std::sqrt(parameter_);  // c^s ≈ exp(−s θ²/2)
    case BrdfKind::ggx: return parameter_ * parameter_;                // α: the slope scale
    case BrdfKind::beckmann: return parameter_;                         // m: the RMS slope
    }
    return 1.0f;
}

}  // namespace ndfbake
