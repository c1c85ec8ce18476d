// Lobes refined against the effective BRDF (ndf/brdf_refinement.h): the derivatives it steps by
// against finite differences, its bulk evaluation against the scalar one, and its fits against
// the exact effective BRDF (eq. 4) on the full direction set it never saw whole.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <limits>

#include "math/brdf.h"
#include "math/sphere.h"
#include "ndf/brdf_refinement.h"
#include "ndf/effective_brdf.h"
#include "ndf/spherical_em.h"
#include "pyramid/lobe_pyramid.h"
#include "synth/patterns.h"

namespace ndfbake {
namespace {

const BaseBrdf kBrdfs[] = {BaseBrdf::blinn_phong(128.0f), BaseBrdf::ggx(0.3f), BaseBrdf::beckmann(0.2f),
                           BaseBrdf::lambert()};

TEST(ConvolvedLobeSlope, MatchesCentralDifferencesForEveryBrdf)
{
    for (const BaseBrdf& brdf : kBrdfs)
        for (float kappa : {2.0f, 50.0f, 3000.0f}) {
            const ConvolvedLobe lobe = brdf.convolved(kappa);
            for (double c : {0.15, 0.5, 0.9, 0.99, 0.999}) {
                // Steps well inside the lobe's width (sharp lobes change fast) and, for Lambert's
                // 48-band series, inside its highest band's wiggle near c = 1.
                const double width = brdf.angular_width();
                const double h = brdf.kind() == BrdfKind::lambert ? 1e-4 : 1e-3 * width * width;
                const double numeric = (double(lobe.eval(float(c + h))) - lobe.eval(float(c - h))) / (2.0 * h);
                const double analytic = lobe.slope(float(c));
                const double scale = std::max(std::abs(numeric), 1e-3 * lobe.eval(1.0f));
                EXPECT_NEAR(analytic, numeric, 0.02 * scale) << brdf.to_string() << " kappa " << kappa << " c " << c;
            }
        }
}

TEST(ConvolvedLobeSlope, BulkEvaluationEqualsTheScalarOneEverywhere)
{
    std::vector<float> c = {-1.0f, -0.3f, 0.0f, std::numeric_limits<float>::min(), 1e-20f, 1e-3f,
                            0.2f, 0.7f, 0.95f, 0.9999f, 1.0f};
    std::vector<float> value(c.size()), slope(c.size()), base(c.size());
    for (const BaseBrdf& brdf : kBrdfs) {
        brdf.eval_many(c, base);
        for (float kappa : {kKappaMin, 10.0f, kKappaMax}) {
            const ConvolvedLobe lobe = brdf.convolved(kappa);
            lobe.eval_many(c, value, slope);
            for (size_t i = 0; i < c.size(); ++i) {
                const float v = lobe.eval(c[i]), s = lobe.slope(c[i]);
                EXPECT_NEAR(value[i], v, 1e-5f * std::max(1.0f, std::abs(v))) << brdf.to_string() << " c " << c[i];
                EXPECT_NEAR(slope[i], s, 1e-4f * std::max(1.0f, std::abs(s))) << brdf.to_string() << " c " << c[i];
                ASSERT_TRUE(std::isfinite(value[i]) && std::isfinite(slope[i]));
            }
        }
        for (size_t i = 0; i < c.size(); ++i) {
            const float f = brdf.eval(c[i]);
            EXPECT_NEAR(base[i], f, 1e-5f * std::max(1.0f, f)) << brdf.to_string() << " c " << c[i];
        }
        // A denormal cosine (fast_log_positive's domain ends at the normals): finite and near.
        const std::vector<float> denormal = {1e-40f};
        std::vector<float> v(1), s(1);
        brdf.convolved(kKappaMin).eval_many(denormal, v, s);
        EXPECT_TRUE(std::isfinite(v[0]) && std::isfinite(s[0])) << brdf.to_string();
        EXPECT_NEAR(v[0], brdf.convolved(kKappaMin).eval(1e-40f), 0.01f) << brdf.to_string();
    }
}

void expect_valid(const std::vector<VmfLobe>& lobes)
{
    ASSERT_FALSE(lobes.empty());
    float total = 0.0f;
    for (const VmfLobe& l : lobes) {
        EXPECT_TRUE(l.alpha >= kNegligibleLobeWeight && l.alpha <= 1.0f) << l.alpha;
        EXPECT_NEAR(length(l.mu), 1.0f, 1e-5f);
        EXPECT_GE(l.kappa, kKappaMin);
        EXPECT_LE(l.kappa, kKappaMax);
        total += l.alpha;
    }
    EXPECT_NEAR(total, 1.0f, 1e-5f);
}

// Every measured texel of a level: EM's lobes against refined ones, on the error measure's own
// full direction set and every fine normal.
TEST(BrdfRefinement, LowersTheExactErrorOfEmFitsOnEveryTexel)
{
    for (const BaseBrdf& brdf : {BaseBrdf::blinn_phong(128.0f), BaseBrdf::ggx(0.3f), BaseBrdf::lambert()}) {
        const std::vector<Vec3> directions = fibonacci_hemisphere(error_direction_count(brdf));
        const LobeRefiner refiner(brdf);
        double pattern_em = 0.0, pattern_refined = 0.0;
        for (Pattern pattern : {Pattern::fbm, Pattern::weave, Pattern::bumps}) {
            const NormalMap map = synthesize(pattern, 64, 64);
            PyramidSettings settings;
            settings.align = false;
            const LobePyramid pyramid = build_lobe_pyramid(map, settings, {});
            double em_total = 0.0, refined_total = 0.0;
            int texels = 0;
            for (int level : {2, 4}) {
                for (int t = 0; t < 8; ++t) {
                    const LevelSize size = pyramid.size(level);
                    const int x = (t * 5) % size.width, y = (t * 3) % size.height;
                    std::vector<WeightedNormal> normals;
                    gather_footprint(map, level, x, y, WrapMode::wrap, normals);
                    const TexelErrorMeter meter(normals, brdf, directions);
                    std::vector<VmfLobe> lobes = pyramid.texel_lobes(level, x, y);
                    const float em = meter.error(lobes);
                    refiner.refine(normals, lobes);
                    expect_valid(lobes);
                    const float refined = meter.error(lobes);
                    // The objective leaves out directions where both sides are under 1% of their peak.
                    EXPECT_LE(refined, em * 1.01f + 1e-4f) << brdf.to_string() << " " << pattern_name(pattern);
                    em_total += em;
                    refined_total += refined;
                    ++texels;
                }
            }
            std::printf("%-12s %-7s: EM %.4f, refined %.4f\n", brdf.to_string().c_str(), pattern_name(pattern),
                        em_total / texels, refined_total / texels);
            EXPECT_LT(refined_total, 0.95 * em_total) << brdf.to_string() << " " << pattern_name(pattern);
            pattern_em += em_total;
            pattern_refined += refined_total;
        }
        // Sharp lobes leave EM a fifth or more of the error to gain back (measured 0.15-0.3).
        EXPECT_LT(pattern_refined, 0.85 * pattern_em) << brdf.to_string();
    }
}

// Where the base BRDF is far sharper than the spread of a texel's normals, the refinement may not
// trade the error between its directions for the error on them: measured on a dense set of
// directions (spacing a fifth of the BRDF's width) that the refinement never sees.
TEST(BrdfRefinement, NeverWorsensTheErrorUnderVerySharpBrdfs)
{
    for (const BaseBrdf& brdf : {BaseBrdf::ggx(0.15f), BaseBrdf::ggx(0.2f), BaseBrdf::blinn_phong(1000.0f)}) {
        const LobeRefiner refiner(brdf);
        const NormalMap map = synthesize(Pattern::fbm, 64, 64);
        PyramidSettings settings;
        settings.align = false;
        const LobePyramid pyramid = build_lobe_pyramid(map, settings, {});
        double em_total = 0.0, refined_total = 0.0;
        int changed = 0;
        for (int t = 0; t < 6; ++t) {
            const int x = (t * 5) % 16, y = (t * 3) % 16;
            std::vector<WeightedNormal> normals;
            gather_footprint(map, 2, x, y, WrapMode::wrap, normals);
            const Vec3 axis = mean_normal(normals).direction;
            const double spacing = 0.2 * brdf.angular_width(), radius = 0.6;
            const std::vector<Vec3> dense =
                fibonacci_cap(axis, radius, int(cap_solid_angle(radius) / (spacing * spacing)), 0.25);
            const TexelErrorMeter meter(normals, brdf, dense);
            std::vector<VmfLobe> lobes = pyramid.texel_lobes(2, x, y);
            const float em = meter.error(lobes);
            refiner.refine(normals, lobes);
            expect_valid(lobes);
            const float refined = meter.error(lobes);
            EXPECT_LE(refined, em * 1.01f + 1e-4f) << brdf.to_string() << " texel " << t;
            changed += refined != em ? 1 : 0;
            em_total += em;
            refined_total += refined;
        }
        std::printf("%-18s dense directions: EM %.4f, refined %.4f (%d of 6 texels changed)\n",
                    brdf.to_string().c_str(), em_total / 6, refined_total / 6, changed);
        EXPECT_GT(changed, 0) << brdf.to_string() << ": the refinement left every texel alone";
    }
}

// One lobe has no weight to move (its softmax column is zero) but its μ and κ still move.
TEST(BrdfRefinement, ASingleLobeFromAPoorStartImproves)
{
    for (const BaseBrdf& brdf : {BaseBrdf::blinn_phong(128.0f), BaseBrdf::ggx(0.3f)}) {
        const LobeRefiner refiner(brdf);
        const NormalMap map = synthesize(Pattern::bumps, 64, 64);
        std::vector<WeightedNormal> normals;
        gather_footprint(map, 3, 2, 5, WrapMode::wrap, normals);
        const std::vector<Vec3> directions = fibonacci_hemisphere(error_direction_count(brdf));
        const TexelErrorMeter meter(normals, brdf, directions);
        std::vector<VmfLobe> lobes{{1.0f, normalize_or({0.2f, 0.1f, 0.97f}, {0, 0, 1}), 1.5f}};
        const float before = meter.error(lobes);
        refiner.refine(normals, lobes);
        expect_valid(lobes);
        EXPECT_LT(meter.error(lobes), 0.8f * before) << brdf.to_string();
    }
}

TEST(BrdfRefinement, HardCasesStayFiniteAndInBounds)
{
    const BaseBrdf brdf = BaseBrdf::blinn_phong(128.0f);
    const std::vector<Vec3> directions = fibonacci_hemisphere(error_direction_count(brdf));
    const LobeRefiner refiner(brdf);
    auto samples = [](std::initializer_list<Vec3> normals) {
        std::vector<WeightedNormal> s;
        for (const Vec3& n : normals) s.push_back({normalize_or(n, {0, 0, 1}), 1.0f});
        return s;
    };

    // All normals equal: the saturated lobe is already exact and stays put.
    const auto equal = samples({{0.3f, -0.2f, 0.93f}, {0.3f, -0.2f, 0.93f}, {0.3f, -0.2f, 0.93f}});
    std::vector<VmfLobe> one{single_vmf_lobe(equal)};
    refiner.refine(equal, one);
    expect_valid(one);
    EXPECT_LT(TexelErrorMeter(equal, brdf, directions).error(one), 0.01f);

    // Antipodal normals, normals on the horizon, a single normal: lobes from EM, then refined.
    for (const auto& normals : {samples({{0, 0, 1}, {0, 0, -1}}),
                                samples({{1, 0, 0}, {0, 1, 0}, {-1, 0, 0}, {0, -1, 0}, {0.7071f, 0.7071f, 0}}),
                                samples({{0.1f, 0.2f, 0.97f}})}) {
        for (int count = 1; count <= kMaxLobes; ++count) {
            std::vector<VmfLobe> lobes = farthest_point_seeds({}, normals, count);
            fit_vmf_mixture(normals, lobes, EmSettings{});
            std::erase_if(lobes, [](const VmfLobe& l) { return !(l.alpha > 0.0f); });
            refiner.refine(normals, lobes);
            expect_valid(lobes);
            EXPECT_TRUE(std::isfinite(TexelErrorMeter(normals, brdf, directions).error(lobes)));
        }
    }

    // Lobes of κ at both bounds: the finite differences step inward, κ stays within them.
    const auto spread = samples({{0.2f, 0, 0.98f}, {-0.2f, 0, 0.98f}, {0, 0.3f, 0.95f}, {0, -0.1f, 0.99f}, {0, 0, 1}});
    std::vector<VmfLobe> extremes{{0.5f, {0, 0, 1}, kKappaMax}, {0.5f, {0.2f, 0, 0.98f}, kKappaMin}};
    extremes[1].mu = normalize_or(extremes[1].mu, {0, 0, 1});
    refiner.refine(spread, extremes);
    expect_valid(extremes);
}

}  // namespace
}  // namespace ndfbake
