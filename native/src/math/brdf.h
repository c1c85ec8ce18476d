// Base BRDFs of the form f(ω·n) (Han et al. 2007, eq. 3) and their convolution with a vMF lobe.
#pragma once

#include <array>
#include <span>
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
    // d eval / dc: how the lobe changes as its axis turns (the refinement's Jacobian needs it).
    float slope(float cos_theta) const;
    // eval() (and, where `slope` is not empty, slope()) at many cosines at once, vectorized in
    // single precision (fast_exp.h; measured relative error under 1e-5, slopes of the sharpest
    // lobes included): the refinement evaluates millions
    // per texel. Spans of equal length.
    void eval_many(std::span<const float> cos_theta, std::span<float> value, std::span<float> slope) const;
    // What a shader needs to draw the lobe: s' (Blinn-Phong) or α' (GGX), and its weight.
    float lobe_parameter() const { return parameter_; }
    float lobe_amplitude() const { return amplitude_; }

private:
    friend class BaseBrdf;
    int kind_ = 0;
    float parameter_ = 0.0f;  // s' for Blinn-Phong, α' for GGX
    float amplitude_ = 1.0f;  // GGX, Beckmann: the widened lobe's weight, see BaseBrdf::convolved
    std::array<float, kLambertBands + 1> lambert_bands_{};
};

enum class BrdfKind { lambert, blinn_phong, ggx, beckmann };

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
    // Beckmann (Torrance-Sparrow) distribution of RMS slope m: exp(−tan²θ/m²) / (π m² cos⁴θ).
    static BaseBrdf beckmann(float slope);

    // Parses "lambert", "blinn-phong:S", "ggx:R" or "beckmann:M"; throws Error(invalid_argument)
    // otherwise.
    static BaseBrdf parse(const std::string& text);
    std::string to_string() const;

    BrdfKind kind() const { return kind_; }
    float parameter() const { return parameter_; }  // s (Blinn-Phong), roughness (GGX), m (Beckmann)

    // f(c), c = ω·n.
    float eval(float cos_theta) const;
    // f at many cosines at once, as ConvolvedLobe::eval_many.
    void eval_many(std::span<const float> cos_theta, std::span<float> value) const;
    // f convolved with a normalized vMF of concentration κ about μ, as a function of c = ω·μ,
    // with κ = ∞ at the cap (convolution_kappa, vmf.h: a single direction leaves f as it is):
    // - Blinn-Phong: s' = κs/(κ + s) (eq. 20).
    // - GGX: amplitude · D(c; α') with α'² = α² + kGgxVmfWidening/κ (α' ≤ 1) and amplitude =
    //   ∫D_α dω / ∫D_α' dω, which keeps the lobe's integral over the sphere (convolution with a
    //   normalized lobe does). Measured against numerical convolution (tests/native/test_convolution):
    //   relative L2 error at most 0.39 for κ ≥ 5 and every α in [0.02, 1] (0.31 for α ≤ 0.7; at
    //   α = 1 no wider lobe exists); up to 0.88 below, where the NDF is nearly uniform and no
    //   hemispherical GGX lobe has its shape; 0.05 at κ = 1e5, past the cap, left unwidened.
    // - Beckmann: amplitude · D(c; m') with m'² = m² + 2/κ (eq. 21: σ'² = σ² + 1/(2κ) with m² = 4σ²;
    //   5% error at κ = 50), m' ≤ 1 and amplitude = ∫D_m dω / ∫D_m' dω, as for GGX.
    // - Lambert: its Legendre series, every band scaled by the vMF's A_l(κ).
    // Shaders must apply the same rule: lobe_parameter() and lobe_amplitude() give it.
    ConvolvedLobe convolved(float kappa) const;

    // ∫_{S²} D(ω·n) dω of the GGX distribution of slope scale α (not roughness):
    // 1 + α² artanh(k)/k with k = √(1 − α²), and 2 at α = 1.
    static double ggx_sphere_integral(double alpha);
    // The same for the Beckmann distribution of RMS slope m: 1 + (√π/2) m e^(1/m²) erfc(1/m).
    static double beckmann_sphere_integral(double m);

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
// GGX widening by a vMF lobe: α'² = α² + kGgxVmfWidening/κ. Chosen by measurement (test_convolution)
// to minimize the worst relative L2 error for κ ≥ 5 over α ∈ [0.02, 0.7]: 1.0 gives 0.45, 1.25 gives
// 0.32, 1.5 gives 0.31, 2.0 (the Beckmann slope-variance derivation, and Filament's rule) gives
// 0.38, and 0.5 (Neubelt & Pettineo's 1/(2κ)) 0.98.
inline constexpr float kGgxVmfWidening = 1.5f;
// A widened lobe narrowed toward grazing views, for shading (not fitting): the roughness a lobe is
// drawn with is α_c² = max(α'² / (1 + kGrazingNarrowing·α'²·tan²θ), α²), θ between the view and the
// lobe's normal, because a microfacet lobe weights its facets by their projected area toward the
// view and a normal map's fine normals are not (docs/grazing-fit.md: fitted offline against the
// normal map's own response in Cycles' model; docs/rendering.md, "Grazing views", for the renders).
// The add-on's Cycles lobes use it (lobe_nodes, nodes.GRAZING_NARROWING), and ndfbake.glsl.
inline constexpr float kGrazingNarrowing = 4.0f;

// Beckmann RMS slope limits, as for GGX's α.
inline constexpr float kMinBeckmannSlope = 1e-4f;
inline constexpr float kMaxBeckmannSlope = 1.0f;

// GGX roughness limits: Blender clamps roughness to [0, 1]; below 0.01 (α = 1e-4) the lobe is a
// mirror that no finite direction set can sample.
inline constexpr float kMinGgxRoughness = 0.01f;
inline constexpr float kMaxGgxRoughness = 1.0f;

}  // namespace ndfbake
