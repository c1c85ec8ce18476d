// vMF and BRDF math against closed forms, numerical integration and their limits (κ → 0, κ → ∞).
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <numbers>
#include <vector>

#include "error.h"
#include "math/brdf.h"
#include "math/fast_exp.h"
#include "math/sphere.h"
#include "math/vmf.h"

namespace ndfbake {
namespace {

// ∫_{S²} g(ω·z) dω = 2π ∫_{-1}^{1} g(c) dc, by the midpoint rule.
template <typename F>
double integrate_zonal(F g, int steps = 200000)
{
    double sum = 0.0;
    for (int i = 0; i < steps; ++i) sum += g(-1.0 + (i + 0.5) * 2.0 / steps);
    return 2.0 * std::numbers::pi * sum * 2.0 / steps;
}

TEST(VmfMath, MeanResultantLengthMatchesCothFormAndLimits)
{
    for (double k : {0.05, 0.5, 2.0, 10.0, 100.0})
        EXPECT_NEAR(mean_resultant_length(k), 1.0 / std::tanh(k) - 1.0 / k, 1e-12) << k;
    EXPECT_NEAR(mean_resultant_length(1e-6), 1e-6 / 3.0, 1e-15);  // κ → 0: A ≈ κ/3, no cancellation
    EXPECT_NEAR(mean_resultant_length(1e6), 1.0 - 1e-6, 1e-12);   // κ → ∞
}

TEST(VmfMath, KappaFromResultantIsGuardedAtBothEnds)
{
    EXPECT_EQ(kappa_from_resultant(0.0), kKappaMin);      // normals cancel: uniform lobe
    EXPECT_EQ(kappa_from_resultant(-1.0), kKappaMin);
    EXPECT_EQ(kappa_from_resultant(std::nan("")), kKappaMin);
    EXPECT_EQ(kappa_from_resultant(1.0), kKappaMax);      // identical normals
    EXPECT_EQ(kappa_from_resultant(1.0 - 1e-12), kKappaMax);
    // In between it is Banerjee's approximation, close to the true A⁻¹ (within 5% for R ≥ 0.3).
    for (double k : {1.0, 3.0, 10.0, 100.0, 1000.0}) {
        const double estimate = kappa_from_resultant(mean_resultant_length(k));
        EXPECT_NEAR(estimate / k, 1.0, 0.06) << k;
    }
}

TEST(VmfMath, ResultantFromKappaInvertsBanerjeeExactly)
{
    for (float k : {kKappaMin, 0.01f, 0.7f, 5.0f, 64.0f, 2000.0f, kKappaMax}) {
        const double r = resultant_from_kappa(k);
        EXPECT_GT(r, 0.0);
        EXPECT_LT(r, 1.0);
        EXPECT_NEAR(kappa_from_resultant(r) / k, 1.0, 1e-5) << k;
    }
}

TEST(VmfMath, DroppingLightLobesRemovesDeadAndNegligibleOnesAndRenormalizes)
{
    const float nan = std::numeric_limits<float>::quiet_NaN();
    std::vector<VmfLobe> lobes{{0.3f, {0, 0, 1}, 10.0f}, {0.0f, {1, 0, 0}, 10.0f}, {nan, {0, 1, 0}, 10.0f},
                               {5e-5f, {0, 0, 1}, 20.0f}, {0.1f, {0, 1, 0}, 30.0f}};
    std::vector<VmfLobe> dead_only = lobes;
    drop_light_lobes(dead_only, 0.0f);
    ASSERT_EQ(dead_only.size(), 3u);  // α = 0 and NaN go, the tiny positive weight stays
    drop_light_lobes(lobes, 1e-4f);
    ASSERT_EQ(lobes.size(), 2u);
    EXPECT_FLOAT_EQ(lobes[0].alpha, 0.75f);
    EXPECT_FLOAT_EQ(lobes[1].alpha, 0.25f);
    EXPECT_EQ(lobes[1].kappa, 30.0f);
}

TEST(VmfMath, DensityIsNormalizedAcrossTheWholeKappaRange)
{
    for (float k : {kKappaMin, 0.5f, 8.0f, 300.0f, kKappaMax}) {
        const VmfLobe lobe{1.0f, {0, 0, 1}, k};
        const double shifted = log_vmf_normalizer_shifted(k);
        ASSERT_TRUE(std::isfinite(shifted)) << k;
        // Sample finely near c = 1 where sharp lobes live.
        const double integral = integrate_zonal([&](double c) {
            return std::exp(double(log_vmf_density(lobe, {0.0f, float(std::sqrt(std::max(0.0, 1 - c * c))), float(c)}, float(shifted))));
        }, 2000000);
        EXPECT_NEAR(integral, 1.0, k > 1000 ? 0.02 : 1e-3) << k;
    }
}

TEST(VmfMath, LegendreCoefficientsMatchA1AndTheLargeKappaLimit)
{
    std::vector<double> a(9);
    for (double k : {0.01, 1.0, 20.0}) {
        vmf_legendre_coefficients(k, 8, a.data());
        EXPECT_DOUBLE_EQ(a[0], 1.0);
        EXPECT_NEAR(a[1], mean_resultant_length(k), 1e-10) << k;
        for (int l = 1; l <= 8; ++l) EXPECT_LT(a[size_t(l)], a[size_t(l - 1)]);
    }
    vmf_legendre_coefficients(5000.0, 8, a.data());
    for (int l = 0; l <= 8; ++l) EXPECT_NEAR(a[size_t(l)], std::exp(-l * (l + 1) / 10000.0), 1e-4) << l;
}

TEST(VmfMath, LegendreCoefficientsAreContinuousIntoTheAsymptoticFormAndOneAtInfinity)
{
    // From kKappaMax on the coefficients are exp(−l(l+1)/(2κ)); just below, the continued fraction.
    std::vector<double> below(49), at(49), infinite(49);
    vmf_legendre_coefficients(std::nextafter(double(kKappaMax), 0.0), 48, below.data());
    vmf_legendre_coefficients(double(kKappaMax), 48, at.data());
    vmf_legendre_coefficients(std::numeric_limits<double>::infinity(), 48, infinite.data());
    for (size_t l = 0; l <= 48; ++l) {
        EXPECT_NEAR(below[l], at[l], 1e-5) << l;
        EXPECT_EQ(infinite[l], 1.0) << l;
    }
    EXPECT_LT(at[48], 0.9);  // 48 bands at the cap still feel its 0.6° spread
}

TEST(BaseBrdf, LobesAreNormalizedAsTheirDefinitionsSay)
{
    // Normalized Blinn-Phong integrates to 1 against the cosine over the hemisphere of n.
    const BaseBrdf bp = BaseBrdf::blinn_phong(64.0f);
    EXPECT_NEAR(integrate_zonal([&](double c) { return bp.eval(float(c)) * std::max(c, 0.0); }), 1.0, 0.02);
    // The GGX distribution D is normalized so that ∫ D(c) c dω = 1.
    const BaseBrdf ggx = BaseBrdf::ggx(0.5f);
    EXPECT_NEAR(integrate_zonal([&](double c) { return ggx.eval(float(c)) * std::max(c, 0.0); }), 1.0, 1e-3);
    EXPECT_NEAR(integrate_zonal([&](double c) { return BaseBrdf::lambert().eval(float(c)); }), 1.0, 1e-3);
}

// Relative L2 distance of two zonal functions over the hemisphere about their axis.
template <typename F, typename G>
double relative_hemisphere_distance(F f, G g)
{
    double diff2 = 0.0, ref2 = 0.0;
    for (const Vec3& w : fibonacci_hemisphere(4096)) {
        const double d = double(f(w.z)) - double(g(w.z));
        diff2 += d * d;
        ref2 += double(g(w.z)) * double(g(w.z));
    }
    return std::sqrt(diff2 / ref2);
}

TEST(BaseBrdf, ConvolvingWithALobeAtTheCapLeavesEveryBrdfAsItIs)
{
    // A lobe at kKappaMax is one direction (a level-0 texel): its effective BRDF is the base BRDF,
    // however glossy. Widened by the full 1/κ = 1e-4, as they were, these were off by 8.95
    // (GGX 0.05), 0.26 (GGX 0.1), 0.012 (GGX 0.3), 0.21 (Blinn-Phong 1e4) and 0.053 (Beckmann
    // 0.05) here.
    for (const BaseBrdf& brdf : {BaseBrdf::ggx(0.05f), BaseBrdf::ggx(0.1f), BaseBrdf::ggx(0.3f),
                                 BaseBrdf::blinn_phong(32.0f), BaseBrdf::blinn_phong(1e4f),
                                 BaseBrdf::beckmann(0.05f), BaseBrdf::lambert()}) {
        // Lambert's convolution is its 48-band series, 0.1% off the kink at the horizon (brdf.h).
        const double series = brdf.kind() == BrdfKind::lambert ? 2e-3 : 0.0;
        const ConvolvedLobe at_cap = brdf.convolved(kKappaMax);
        EXPECT_LT(relative_hemisphere_distance([&](float c) { return at_cap.eval(c); },
                                               [&](float c) { return brdf.eval(c); }), 1e-6 + series)
            << brdf.to_string();
    }
}

TEST(BaseBrdf, ALobeJustBelowTheCapKeepsItsWholeSpread)
{
    // Below the cap a lobe is a real spread: GGX α'² = α² + 1.5/κ with all of 1/κ.
    for (float kappa : {1000.0f, std::nextafter(kKappaMax, 0.0f)}) {
        const float roughness = 0.3f, alpha = roughness * roughness;
        EXPECT_NEAR(BaseBrdf::ggx(roughness).convolved(kappa).lobe_parameter(),
                    std::sqrt(alpha * alpha + kGgxVmfWidening / kappa), 1e-7)
            << kappa;
    }
}

TEST(BaseBrdf, LambertConvolvedWithAUniformLobeIsConstant)
{
    // κ → 0: the NDF is uniform on the sphere, and E[max(ω·n, 0)]/π = 1/(4π) for every ω.
    const ConvolvedLobe flat = BaseBrdf::lambert().convolved(kKappaMin);
    for (float c : {-1.0f, -0.3f, 0.0f, 0.5f, 1.0f}) EXPECT_NEAR(flat.eval(c), 1.0 / (4.0 * std::numbers::pi), 1e-3);
}

TEST(BaseBrdf, BlinnPhongRuleIsHansEquation20)
{
    const BaseBrdf bp = BaseBrdf::blinn_phong(100.0f);
    const float kappa = 50.0f, s_prime = kappa * 100.0f / (kappa + 100.0f);
    for (float c : {0.2f, 0.9f, 0.99f, 1.0f})
        EXPECT_NEAR(bp.convolved(kappa).eval(c) / BaseBrdf::blinn_phong(s_prime).eval(c), 1.0, 1e-5) << c;
}

TEST(BaseBrdf, ParsesAndRejectsSpecs)
{
    EXPECT_EQ(BaseBrdf::parse("ggx:0.25").to_string(), "ggx:0.25");
    EXPECT_EQ(BaseBrdf::parse("blinn-phong:64").kind(), BrdfKind::blinn_phong);
    EXPECT_EQ(BaseBrdf::parse("lambert").kind(), BrdfKind::lambert);
    for (const char* bad : {"ggx", "ggx:", "ggx:2", "ggx:-1", "phong:3", "blinn-phong:0.5", "ggx:nan", ""})
        EXPECT_ANY_THROW(BaseBrdf::parse(bad)) << bad;
    // A value that is not a number is an unknown spec, not a number out of range.
    for (const char* bad : {"beckmann:abc", "blinn-phong:32x"}) {
        try {
            BaseBrdf::parse(bad);
            ADD_FAILURE() << bad;
        } catch (const Error& e) {
            EXPECT_NE(std::string(e.what()).find("unknown BRDF"), std::string::npos) << e.what();
        }
    }
}

// EM's responsibilities and the refinement's lobes use these in place of libm: their stated
// errors, against double precision, over every argument they are used for.
TEST(FastExp, ExpAndLogMeetTheirStatedErrors)
{
    double exp_error = 0.0;
    for (double x = kFastExpMin + 1e-4; x <= 0.0; x += 1e-4) {
        const float xf = float(x);
        const double truth = std::exp(double(xf));
        exp_error = std::max(exp_error, std::abs(fast_exp_nonpositive(xf) - truth) / truth);
    }
    EXPECT_LT(exp_error, 5e-7);
    EXPECT_EQ(fast_exp_nonpositive(0.0f), 1.0f);
    EXPECT_EQ(fast_exp_nonpositive(kFastExpMin - 1.0f), 0.0f);
    EXPECT_EQ(fast_exp_nonpositive(-std::numeric_limits<float>::infinity()), 0.0f);
    EXPECT_EQ(fast_exp_nonpositive(std::numeric_limits<float>::quiet_NaN()), 0.0f);

    double log_error = 0.0;
    for (double x = std::numeric_limits<float>::min(); x < 1e38; x *= 1.0003) {
        const float xf = float(x);
        const double truth = std::log(double(xf));
        log_error = std::max(log_error, std::abs(fast_log_positive(xf) - truth) / std::max(1.0, std::abs(truth)));
    }
    EXPECT_LT(log_error, 2e-7);
}

}  // namespace
}  // namespace ndfbake
