// Base BRDFs of the form f(ω·n) (Han et al. 2007, eq. 3) and their convolution with a vMF lobe.
#pragma once

#include <array>
#include <string>

namespace ndfbake {

// Highest Legendre band of the convolved Lambert lobe. The clamped cosine's bands fall off as
// l^-1.5; 48 bands leave < 0.5% relative L2 error at κ → ∞, all of it at the horizon kink.
inline constexpr int kLambertBands = 48;

class BaseBrdf;

// A base BRDF convolved with one normalized vMF lobe: a function of c = ω·μ, prepared once per
// lobe because the Lambert case needs a band-limited series.
class ConvolvedLobe {
public:
    float eval(float cos_theta) const;

private:
    friend class BaseBrdf;
    int kind_ = 0;
    float parameter_ = 0.0f;  // s' for Blinn-Phong, α' for GGX
    std::array<float, kLambertBands + 1> lambert_bands_{};
};

enum class BrdfKind { lambert, blinn_phong, ggx };

// A single-variable BRDF lobe f(ω·n): ω is the light direction for Lambert and the half vector
// for the specular lobes. Shadowing and Fresnel vary slowly and are left out: they multiply the
// effective BRDF of every representation alike.
class BaseBrdf {
public:
    static BaseBrdf lambert();
    // Normalized Blinn-Phong, (s + 1)/(2π) · (ω_h·n)^s.
    static BaseBrdf blinn_phong(float exponent);
    // GGX distribution as Blender's Principled BSDF uses it: α = roughness².
    static BaseBrdf ggx(float roughness);

    // Parses "lambert", "blinn-phong:S" or "ggx:R"; throws Error(invalid_argument) otherwise.
    static BaseBrdf parse(const std::string& text);
    std::string to_string() const;

    BrdfKind kind() const { return kind_; }
    float parameter() const { return parameter_; }  // s for Blinn-Phong, roughness for GGX

    // f(c), c = ω·n.
    float eval(float cos_theta) const;
    // f convolved with a normalized vMF of concentration κ about μ, as a function of c = ω·μ:
    // Blinn-Phong with s' = κs/(κ + s) (eq. 20); GGX with α'² = α² + 2/κ (eq. 21 with the
    // Beckmann slope variance m² = 4σ², GGX taken for Beckmann at equal α); Lambert by its
    // Legendre series, every band scaled by the vMF's A_l(κ).
    ConvolvedLobe convolved(float kappa) const;

    // Angular standard deviation of the lobe in radians: how finely directions must sample it.
    float angular_width() const;

private:
    BaseBrdf(BrdfKind kind, float parameter) : kind_(kind), parameter_(parameter) {}
    BrdfKind kind_;
    float parameter_;
};

// Blinn-Phong exponent limits: below 1 the lobe is wider than a cosine, above 1e4 it is a mirror
// for any normal map we can store.
inline constexpr float kMinBlinnPhongExponent = 1.0f;
inline constexpr float kMaxBlinnPhongExponent = 1e4f;
// GGX roughness limits: Blender clamps roughness to [0, 1]; below 0.01 (α = 1e-4) the lobe is a
// mirror that no finite direction set can sample.
inline constexpr float kMinGgxRoughness = 0.01f;
inline constexpr float kMaxGgxRoughness = 1.0f;

}  // namespace ndfbake
