// The convolution rules a shader uses for one vMF lobe, against numerical convolution: GGX (our
// measured rule), Blinn-Phong (eq. 20) and Beckmann (eq. 21).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "math/brdf.h"
#include "math/vmf_convolution.h"

namespace ndfbake {
namespace {

double ggx(double c, double alpha)
{
    if (c <= 0.0) return 0.0;
    const double a2 = alpha * alpha, d = c * c * (a2 - 1.0) + 1.0;
    return a2 / (3.141592653589793 * d * d);
}

TEST(ConvolutionRules, GgxRuleMeetsItsStatedErrorAndBeatsPublishedRules)
{
    // κ spans [0.5, 1e5] and α = roughness² spans [0.02, 1], as the rule's comment promises.
    double worst_wide = 0.0, worst_sharp = 0.0;
    double ours_total = 0.0, filament_total = 0.0, unity_total = 0.0;
    for (double alpha : {0.02, 0.2, 1.0}) {
        for (double kappa : {0.5, 5.0, 100.0, 1e5}) {
            const BaseBrdf brdf = BaseBrdf::ggx(float(std::sqrt(alpha)));
            const ConvolutionTable truth = tabulate_convolution(brdf, kappa);
            const ConvolvedLobe lobe = brdf.convolved(float(kappa));
            const double ours = rule_error(truth, [&](double c) { return double(lobe.eval(float(c))); });
            // Published rules as they are used: a GGX lobe of the widened α, no amplitude.
            const auto widened = [&](double k) { return std::min(1.0, std::sqrt(alpha * alpha + k / kappa)); };
            const double filament = rule_error(truth, [&](double c) { return ggx(c, widened(2.0)); });
            const double unity = rule_error(truth, [&](double c) { return ggx(c, widened(0.5)); });
            std::printf("alpha %.2f kappa %-7g: ours %.3f  2/kappa %.3f  1/(2 kappa) %.3f\n", alpha, kappa, ours,
                        filament, unity);
            (kappa >= 5.0 ? worst_sharp : worst_wide) = std::max(kappa >= 5.0 ? worst_sharp : worst_wide, ours);
            ours_total += ours;
            filament_total += filament;
            unity_total += unity;
        }
    }
    std::printf("worst: %.3f for kappa >= 5, %.3f below\n", worst_sharp, worst_wide);
    EXPECT_LE(worst_sharp, 0.39);
    EXPECT_LE(worst_wide, 0.88);
    EXPECT_LT(ours_total, filament_total);
    EXPECT_LT(ours_total, unity_total);
}

// ∫ D dω over the upper hemisphere of a zonal D(c): 2π ∫₀¹ D(c) dc by the midpoint rule in double.
template <typename F>
double hemisphere_integral(F d)
{
    double sum = 0.0;
    const int steps = 2000000;
    for (int i = 0; i < steps; ++i) sum += d((i + 0.5) / steps);
    return 2.0 * 3.141592653589793 * sum / steps;
}

TEST(ConvolutionRules, GgxSphereIntegralIsClosedForm)
{
    for (double alpha : {0.01, 0.1, 0.5, 0.9, 0.99999, 1.0})
        EXPECT_NEAR(BaseBrdf::ggx_sphere_integral(alpha), hemisphere_integral([&](double c) { return ggx(c, alpha); }),
                    1e-3)
            << alpha;
}

TEST(ConvolutionRules, GgxStaysExactAtItsPeakForTheSmallestRoughness)
{
    // D(1) = 1/(πα²), α = roughness²: in float, c²(α² − 1) + 1 rounded to 0 below roughness 0.013.
    for (float roughness : {0.01f, 0.012f, 0.02f, 0.05f, 0.3f}) {  // 0.01: the smallest accepted
        const double alpha = double(roughness) * double(roughness);
        const double peak = 1.0 / (3.141592653589793 * alpha * alpha);
        const float value = BaseBrdf::ggx(roughness).eval(1.0f);
        EXPECT_NEAR(value / peak, 1.0, 1e-5) << roughness;
        // Just off the peak too (c in float resolution): the double formula at the same c.
        const float c = std::nextafter(1.0f, 0.0f);
        EXPECT_NEAR(BaseBrdf::ggx(roughness).eval(c) / ggx(double(c), alpha), 1.0, 1e-3) << roughness;
    }
}

TEST(ConvolutionRules, BeckmannSphereIntegralIsClosedForm)
{
    for (double m : {0.01, 0.05, 0.3, 0.7, 1.0}) {
        const auto beckmann = [&](double c) {  // exp(−tan²θ/m²)/(π m² c⁴)
            const double t2 = (1.0 - c * c) / (c * c);
            return std::exp(-t2 / (m * m)) / (3.141592653589793 * m * m * c * c * c * c);
        };
        EXPECT_NEAR(BaseBrdf::beckmann_sphere_integral(m), hemisphere_integral(beckmann), 1e-3) << m;
    }
}

TEST(ConvolutionRules, BeckmannRuleStaysBoundedForWideVmfLobes)
{
    // Below κ ≈ 5 eq. 21 asks for m' past 1, where a Beckmann lobe piles up at the horizon
    // (uncapped: relative error 354 at κ = 1e-3, 3.1 at 0.5). Capped at 1, with the amplitude
    // keeping the integral: at most 0.9 from κ = 2 on and 1.6 as κ → 0, where the truth is nearly
    // uniform over the sphere and no hemispherical Beckmann lobe has its shape (GGX: 1.0).
    for (float m : {0.1f, 0.3f, 1.0f})
        for (double kappa : {1e-3, 0.5, 2.0, 5.0}) {
            const double error = convolution_rule_error(BaseBrdf::beckmann(m), kappa);
            std::printf("beckmann:%g kappa %g: %.3f\n", m, kappa, error);
            EXPECT_LT(error, kappa >= 2.0 ? 0.9 : 1.65) << m << " kappa " << kappa;
        }
}

TEST(ConvolutionRules, BlinnPhongAndBeckmannRulesAreAccurateForSharpLobes)
{
    // Eq. 20 and eq. 21 assume κ large (sinh κ ≈ e^κ/2 and small angles, §7.2): within 3% for
    // Blinn-Phong and 6% for Beckmann from κ = 50 on, up to just below the κ cap (past it the
    // rules leave the BRDF as it is, which the truth at 1e5 nearly is).
    for (const BaseBrdf& brdf : {BaseBrdf::blinn_phong(32.0f), BaseBrdf::blinn_phong(512.0f), BaseBrdf::beckmann(0.3f)}) {
        for (double kappa : {50.0, 1000.0, 5000.0, 9999.0, 1e5}) {
            const double error = convolution_rule_error(brdf, kappa);
            std::printf("%s kappa %g: %.4f\n", brdf.to_string().c_str(), kappa, error);
            EXPECT_LT(error, brdf.kind() == BrdfKind::beckmann ? 0.06 : 0.03) << brdf.to_string() << " kappa " << kappa;
        }
    }
}

}  // namespace
}  // namespace ndfbake
