// Baseline NDF representations (naive, Toksvig, single vMF, LEAN, Xu partitions, SH): footprints,
// storage, hand-computed texels and accuracy against the exact effective BRDF (Han 2007 eq. 4),
// never against stored numbers from a run.
#include <gtest/gtest.h>

#include <functional>

#include <cmath>
#include <map>
#include <numbers>

#include "baselines/footprint_means.h"
#include "baselines/lean.h"
#include "baselines/linear_pyramid.h"
#include "baselines/registry.h"
#include "baselines/spherical_harmonics.h"
#include "baselines/xu_partitions.h"
#include "error.h"
#include "math/sphere.h"
#include "ndf/effective_brdf.h"
#include "synth/patterns.h"

namespace ndfbake {
namespace {

constexpr double kPi = std::numbers::pi;

NormalMap make_map(int width, int height, const std::vector<Vec3>& normals)
{
    NormalMap map;
    map.width = width;
    map.height = height;
    for (const Vec3& n : normals) map.normals.push_back(normalize_or(n, {0, 0, 1}));
    return map;
}

// Two columns of facets tilted ±θ about Y: n = (±sin θ, 0, cos θ).
NormalMap two_facets(double theta)
{
    const float s = float(std::sin(theta)), c = float(std::cos(theta));
    return make_map(2, 1, {{s, 0, c}, {-s, 0, c}});
}

const LinearNdfPyramid& linear(const NdfPyramid& pyramid)
{
    return dynamic_cast<const LinearNdfPyramid&>(pyramid);
}

std::vector<float> evaluate(const NdfPyramid& pyramid, int level, int x, int y, const BaseBrdf& brdf,
                            const std::vector<Vec3>& directions)
{
    std::vector<float> out(directions.size());
    pyramid.effective_brdf(level, x, y, brdf, directions, out);
    return out;
}

float eval_at(const NdfPyramid& pyramid, int level, const BaseBrdf& brdf, const Vec3& direction)
{
    return evaluate(pyramid, level, 0, 0, brdf, {normalize_or(direction, {0, 0, 1})})[0];
}

std::vector<float> reference(const NormalMap& map, int level, int x, int y, WrapMode wrap, const BaseBrdf& brdf,
                             const std::vector<Vec3>& directions)
{
    std::vector<WeightedNormal> samples;
    gather_footprint(map, level, x, y, wrap, samples);
    std::vector<float> out(directions.size());
    reference_effective_brdf(samples, brdf, directions, out);
    return out;
}

float texel_error(const NdfPyramid& pyramid, const NormalMap& map, int level, int x, int y, WrapMode wrap,
                  const BaseBrdf& brdf)
{
    const auto directions = fibonacci_hemisphere(error_direction_count(brdf));
    return relative_l2_error(evaluate(pyramid, level, x, y, brdf, directions),
                             reference(map, level, x, y, wrap, brdf, directions));
}

double level_error(const NdfPyramid& pyramid, const NormalMap& map, int level, WrapMode wrap, const BaseBrdf& brdf)
{
    const LevelSize size = pyramid.size(level);
    double sum = 0.0;
    for (int y = 0; y < size.height; ++y)
        for (int x = 0; x < size.width; ++x) sum += texel_error(pyramid, map, level, x, y, wrap, brdf);
    return sum / (double(size.width) * size.height);
}

// ---------------------------------------------------------------------------------------------
// Footprints

// Per fine texel index: the weight gather_footprint gives it under texel (x, y) of `level`.
std::map<int, double> gathered_weights(const NormalMap& tagged, int level, int x, int y, WrapMode wrap)
{
    std::vector<WeightedNormal> samples;
    gather_footprint(tagged, level, x, y, wrap, samples);
    std::map<int, double> weights;
    for (const WeightedNormal& s : samples) weights[int(s.n.x)] += s.weight;
    return weights;
}

NormalMap tagged_map(int w, int h)
{
    NormalMap map;
    map.width = w;
    map.height = h;
    for (int i = 0; i < w * h; ++i) map.normals.push_back({float(i), 0, 1});  // x tags the texel
    return map;
}

const std::vector<std::pair<int, int>> kOddSizes = {{3, 5}, {1, 7}, {13, 2}, {16, 16}, {5, 1}, {6, 11}};

TEST(BaselineFootprints, AxisFootprintsAreGatherFootprints)
{
    for (auto [w, h] : kOddSizes) {
        const NormalMap tagged = tagged_map(w, h);
        for (WrapMode wrap : {WrapMode::clamp, WrapMode::wrap})
            for (int level = 0; level < level_count(w, h); ++level) {
                const AxisFootprints columns = axis_footprints(w, level, wrap), rows = axis_footprints(h, level, wrap);
                const LevelSize size = level_size(w, h, level);
                ASSERT_EQ(columns.targets(), size.width);
                ASSERT_EQ(rows.targets(), size.height);
                for (int y = 0; y < size.height; ++y)
                    for (int x = 0; x < size.width; ++x) {
                        std::map<int, double> separable;
                        for (int r = rows.begin[size_t(y)]; r < rows.begin[size_t(y) + 1]; ++r)
                            for (int c = columns.begin[size_t(x)]; c < columns.begin[size_t(x) + 1]; ++c)
                                separable[rows.taps[size_t(r)].index * w + columns.taps[size_t(c)].index] +=
                                    double(rows.taps[size_t(r)].multiplicity) * columns.taps[size_t(c)].multiplicity;
                        EXPECT_EQ(separable, gathered_weights(tagged, level, x, y, wrap))
                            << w << "x" << h << " level " << level << " texel " << x << "," << y;
                    }
            }
    }
}

TEST(BaselineFootprints, ChildFootprintsComposeToTheFineFootprints)
{
    int nested_wrap_levels = 0, summed_wrap_levels = 0;
    for (int extent : {1, 2, 3, 5, 6, 7, 12, 13, 16}) {
        for (WrapMode wrap : {WrapMode::clamp, WrapMode::wrap})
            for (int level = 1; level < level_count(extent, 1); ++level) {
                const auto children = child_footprints(extent, level, wrap);
                if (wrap == WrapMode::clamp) {
                    ASSERT_TRUE(children.has_value()) << extent << " level " << level;
                }
                if (!children) {
                    ++summed_wrap_levels;
                    continue;
                }
                if (wrap == WrapMode::wrap) ++nested_wrap_levels;
                const AxisFootprints fine_parent = axis_footprints(extent, level, wrap);
                const AxisFootprints fine_child = axis_footprints(extent, level - 1, wrap);
                for (int i = 0; i < fine_parent.targets(); ++i) {
                    std::map<int, int> direct, composed;
                    for (int t = fine_parent.begin[size_t(i)]; t < fine_parent.begin[size_t(i) + 1]; ++t)
                        direct[fine_parent.taps[size_t(t)].index] += fine_parent.taps[size_t(t)].multiplicity;
                    double weight = 0.0;
                    for (int t = children->begin[size_t(i)]; t < children->begin[size_t(i) + 1]; ++t) {
                        const AxisTap child = children->taps[size_t(t)];
                        EXPECT_EQ(child.multiplicity, fine_child.weight[size_t(child.index)]);
                        weight += child.multiplicity;
                        for (int u = fine_child.begin[size_t(child.index)]; u < fine_child.begin[size_t(child.index) + 1]; ++u)
                            composed[fine_child.taps[size_t(u)].index] += fine_child.taps[size_t(u)].multiplicity;
                    }
                    EXPECT_EQ(direct, composed) << extent << " level " << level << " texel " << i;
                    EXPECT_EQ(weight, fine_parent.weight[size_t(i)]);
                }
            }
    }
    // Both build paths are exercised: power-of-two extents nest, odd ones wrap onto shifted windows.
    EXPECT_GT(nested_wrap_levels, 0);
    EXPECT_GT(summed_wrap_levels, 0);
}

// Stored texels are the footprint means of φ computed here from gather_footprint's normals: the
// mean normal, and LEAN's slope moments t = (n_x, n_y)/n_z, on odd sizes in both modes (so both the
// nested and the fine-level build paths are checked).
TEST(BaselineStorage, TexelsAreFootprintMeansOfTheFeatures)
{
    for (auto [w, h] : kOddSizes) {
        const NormalMap map = synthesize(Pattern::fbm, w, h, 3);
        for (WrapMode wrap : {WrapMode::clamp, WrapMode::wrap}) {
            const auto naive = build_baseline("naive", map, wrap);
            const auto lean = build_baseline("lean", map, wrap);
            for (int level = 0; level < level_count(w, h); ++level) {
                const LevelSize size = level_size(w, h, level);
                for (int y = 0; y < size.height; ++y)
                    for (int x = 0; x < size.width; ++x) {
                        std::vector<WeightedNormal> samples;
                        gather_footprint(map, level, x, y, wrap, samples);
                        double total = 0.0, mean[3] = {}, moments[5] = {};
                        for (const WeightedNormal& s : samples) {
                            const double tx = s.n.x / s.n.z, ty = s.n.y / s.n.z;
                            const double phi[5] = {tx, ty, tx * tx, ty * ty, tx * ty};
                            for (int k = 0; k < 3; ++k) mean[k] += s.weight * s.n[k];
                            for (int k = 0; k < 5; ++k) moments[k] += s.weight * phi[k];
                            total += s.weight;
                        }
                        const auto stored_mean = linear(*naive).texel(level, x, y);
                        const auto stored_moments = linear(*lean).texel(level, x, y);
                        for (int k = 0; k < 3; ++k) EXPECT_NEAR(stored_mean[size_t(k)], mean[k] / total, 2e-6);
                        for (int k = 0; k < 5; ++k)
                            EXPECT_NEAR(stored_moments[size_t(k)], moments[k] / total, 2e-6 * (1.0 + std::abs(moments[k] / total)));
                    }
            }
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Single-lobe baselines on the two-facet texel, by hand

// Facets at ±30° about Y: the mean normal is (0, 0, cos 30°), so R = cos 30° = √3/2 = 0.8660254.
constexpr double kFacetTilt = kPi / 6.0;
const double kFacetR = std::sqrt(3.0) / 2.0;

TEST(SingleLobeBaselines, NaiveShadesTheRenormalizedMean)
{
    const auto pyramid = build_baseline("naive", two_facets(kFacetTilt), WrapMode::clamp);
    const auto mean = linear(*pyramid).texel(1, 0, 0);
    EXPECT_NEAR(mean[0], 0.0, 1e-7);
    EXPECT_NEAR(mean[2], kFacetR, 1e-6);
    // f(ω·ẑ): normalized Blinn-Phong 32 at ω = ẑ is 33/(2π) = 5.2521131, at 20° off 33/(2π)·cos³²20°.
    const BaseBrdf bp = BaseBrdf::blinn_phong(32.0f);
    EXPECT_NEAR(eval_at(*pyramid, 1, bp, {0, 0, 1}), 5.2521131, 1e-5);
    EXPECT_NEAR(eval_at(*pyramid, 1, bp, {float(std::sin(0.349066)), 0, float(std::cos(0.349066))}),
                5.2521131 * std::pow(std::cos(0.349066), 32.0), 1e-5);
}

TEST(SingleLobeBaselines, ToksvigMatchesHisExponentAndTheBeckmannWidening)
{
    const auto pyramid = build_baseline("toksvig", two_facets(kFacetTilt), WrapMode::clamp);
    // Toksvig: s' = sR/(R + s(1 − R)) = 32·0.8660254/(0.8660254 + 32·0.1339746) = 5.377774, and
    // f(ω) = (s'+1)/(2π) (ω·ẑ)^s'.
    const double s_prime = 32.0 * kFacetR / (kFacetR + 32.0 * (1.0 - kFacetR));
    EXPECT_NEAR(s_prime, 5.377774, 1e-6);
    const BaseBrdf bp = BaseBrdf::blinn_phong(32.0f);
    EXPECT_NEAR(eval_at(*pyramid, 1, bp, {0, 0, 1}), (s_prime + 1.0) / (2.0 * kPi), 1e-4);
    const double off = 0.5;  // radians from the mean normal
    EXPECT_NEAR(eval_at(*pyramid, 1, bp, {float(std::sin(off)), 0, float(std::cos(off))}),
                (s_prime + 1.0) / (2.0 * kPi) * std::pow(std::cos(off), s_prime), 1e-4);
    // Beckmann m = 0.25 (eq. 21): m'² = m² + 2σ², σ² = (1 − R)/R = 0.1547005, so m'² = 0.371901
    // (m' = 0.609837), and the amplitude keeping the sphere integral I(m) = 1 + (√π/2) m erfcx(1/m):
    // I(0.25) = 1.030353, I(m') = 1.162199, A = 0.886555; D(ẑ) = A/(π m'²) = 0.758802.
    const double m2 = 0.0625 + 2.0 * (1.0 - kFacetR) / kFacetR;
    EXPECT_NEAR(m2, 0.371901, 1e-6);
    EXPECT_NEAR(BaseBrdf::beckmann_sphere_integral(0.25) / BaseBrdf::beckmann_sphere_integral(std::sqrt(m2)),
                0.886555, 1e-6);
    EXPECT_NEAR(eval_at(*pyramid, 1, BaseBrdf::beckmann(0.25f), {0, 0, 1}), 0.886555 / (kPi * m2), 1e-4);
}

TEST(SingleLobeBaselines, SingleVmfUsesBanerjeesKappa)
{
    const auto pyramid = build_baseline("single-vmf", two_facets(kFacetTilt), WrapMode::clamp);
    // κ = (3R − R³)/(1 − R²) = (2.5980762 − 0.6495191)/0.25 = 7.7942286; s' = κs/(κ + s) = 6.2676254.
    const double kappa = (3.0 * kFacetR - kFacetR * kFacetR * kFacetR) / (1.0 - kFacetR * kFacetR);
    EXPECT_NEAR(kappa, 7.7942286, 1e-6);
    const double s_prime = kappa * 32.0 / (kappa + 32.0);
    EXPECT_NEAR(eval_at(*pyramid, 1, BaseBrdf::blinn_phong(32.0f), {0, 0, 1}), (s_prime + 1.0) / (2.0 * kPi), 1e-4);
}

// ---------------------------------------------------------------------------------------------
// LEAN

TEST(Lean, MomentsAndCovarianceOfTwoFacetsByHand)
{
    // ±30° about Y: slopes t = (±tan 30°, 0) = (±1/√3, 0), so E[t] = 0, E[t_x²] = 1/3, the rest 0,
    // and Σ = M − t̄t̄ᵀ = diag(1/3, 0).
    const auto pyramid = build_baseline("lean", two_facets(kFacetTilt), WrapMode::clamp);
    const auto m = linear(*pyramid).texel(1, 0, 0);
    const double expected[5] = {0.0, 0.0, 1.0 / 3.0, 0.0, 0.0};
    for (int k = 0; k < 5; ++k) EXPECT_NEAR(m[size_t(k)], expected[k], 1e-6) << k;

    // Blinn-Phong 32: S = Σ + I/(s+2) = diag(1/3 + 1/34, 1/34) = diag(0.3627451, 0.0294118), det S =
    // 0.0106690; at t_h = t̄ = 0 (ω = ẑ): f = (33/34) / (2π √det S) = 0.9705882/0.6489948 = 1.495526.
    const BaseBrdf bp = BaseBrdf::blinn_phong(32.0f);
    EXPECT_NEAR(eval_at(*pyramid, 1, bp, {0, 0, 1}), 1.495526, 2e-5);
    // At slope (0, 0.1), ω = (0, 0.1, 1)/√1.01: dᵀS⁻¹d = 0.01·34 = 0.34, ν = 34:
    // f = 1.495526 · (1 + 0.34/34)^−18 / ω_z⁴ = 1.495526 · 0.8360173 · 1.0201 = 1.275416.
    EXPECT_NEAR(eval_at(*pyramid, 1, bp, {0, 0.1f, 1}), 1.275416, 2e-5);
    // Lambert shades with the normal of the mean slope, ẑ here: 1/π.
    EXPECT_NEAR(eval_at(*pyramid, 1, BaseBrdf::lambert(), {0, 0, 1}), 1.0 / kPi, 1e-6);
}

TEST(Lean, MomentsOfAnOffsetPairByHand)
{
    // Slopes (0.7, 0) and (0.3, 0): E[t_x] = 0.5, E[t_x²] = (0.49 + 0.09)/2 = 0.29, Σ_xx = 0.04.
    const auto pyramid = build_baseline("lean", make_map(1, 2, {{0.7f, 0, 1}, {0.3f, 0, 1}}), WrapMode::clamp);
    const auto m = linear(*pyramid).texel(1, 0, 0);
    const double expected[5] = {0.5, 0.0, 0.29, 0.0, 0.0};
    for (int k = 0; k < 5; ++k) EXPECT_NEAR(m[size_t(k)], expected[k], 1e-6) << k;
    EXPECT_NEAR(m[2] - m[0] * m[0], 0.04, 1e-6);
}

TEST(Lean, IdenticalNormalsReproduceTheBaseBrdf)
{
    const NormalMap flat = make_map(2, 2, std::vector<Vec3>(4, Vec3{0, 0, 1}));
    const auto pyramid = build_baseline("lean", flat, WrapMode::clamp);
    for (const BaseBrdf& brdf : {BaseBrdf::blinn_phong(8.0f), BaseBrdf::blinn_phong(32.0f), BaseBrdf::blinn_phong(256.0f),
                                 BaseBrdf::ggx(0.2f), BaseBrdf::ggx(0.5f), BaseBrdf::ggx(1.0f), BaseBrdf::beckmann(0.1f),
                                 BaseBrdf::beckmann(0.4f), BaseBrdf::lambert()})
        for (int level : {0, 1}) EXPECT_LT(texel_error(*pyramid, flat, level, 0, 0, WrapMode::clamp, brdf), 1e-2f) << brdf.to_string();

    // Tilted by 30° towards (0.6, 0.8): the lobe peaks at the normal with exactly brdf.eval(1).
    const Vec3 n{0.3f, 0.4f, float(std::cos(kPi / 6.0))};
    const auto tilted = build_baseline("lean", make_map(2, 2, std::vector<Vec3>(4, n)), WrapMode::clamp);
    for (const BaseBrdf& brdf : {BaseBrdf::blinn_phong(32.0f), BaseBrdf::ggx(0.5f), BaseBrdf::beckmann(0.3f)})
        for (int level : {0, 1})
            EXPECT_NEAR(evaluate(*tilted, level, 0, 0, brdf, {n})[0] / brdf.eval(1.0f), 1.0, 1e-4) << brdf.to_string();
}

TEST(Lean, AnisotropicLobeBeatsToksvigOnBrushedMetal)
{
    // Brushed streaks tilt normals about X only: an anisotropic NDF that one isotropic lobe smears.
    const NormalMap map = synthesize(Pattern::brushed, 32, 32);
    const auto lean = build_baseline("lean", map, WrapMode::wrap);
    const auto toksvig = build_baseline("toksvig", map, WrapMode::wrap);
    const BaseBrdf brdf = BaseBrdf::blinn_phong(32.0f);
    for (int level = 3; level < lean->level_count(); ++level)
        EXPECT_LT(level_error(*lean, map, level, WrapMode::wrap, brdf), level_error(*toksvig, map, level, WrapMode::wrap, brdf))
            << "level " << level;
}

TEST(Lean, HorizonNormalsAreClampedToTheMaximumSlope)
{
    const Slope t = lean_slope({0.6f, 0.8f, 0.0f});
    EXPECT_NEAR(std::hypot(t.x, t.y), kLeanMaxSlope, 1e-3);
    EXPECT_NEAR(t.x / t.y, 0.75, 1e-6);  // azimuth kept
    const Slope below = lean_slope(normalize_or({1.0f, 0.0f, -0.2f}, {}));
    EXPECT_NEAR(below.x, kLeanMaxSlope, 1e-3);
    const Slope inside = lean_slope(normalize_or({0.5f, -0.25f, 1.0f}, {}));
    EXPECT_NEAR(inside.x, 0.5, 1e-6);
    EXPECT_NEAR(inside.y, -0.25, 1e-6);
}

// ---------------------------------------------------------------------------------------------
// Spherical harmonics

TEST(SphericalHarmonics, LowOrdersMatchTheirClosedForms)
{
    for (const Vec3& v : {Vec3{0.3f, -0.5f, 0.8f}, Vec3{-0.9f, 0.1f, -0.2f}, Vec3{0, 0, 1}}) {
        const Vec3 d = normalize_or(v, {});
        double y[9];
        real_sh(d, 2, y);
        const double x = d.x, yy = d.y, z = d.z;
        EXPECT_NEAR(y[sh_index(0, 0)], 0.2820948, 1e-6);
        EXPECT_NEAR(y[sh_index(1, -1)], 0.4886025 * yy, 1e-6);
        EXPECT_NEAR(y[sh_index(1, 0)], 0.4886025 * z, 1e-6);
        EXPECT_NEAR(y[sh_index(1, 1)], 0.4886025 * x, 1e-6);
        EXPECT_NEAR(y[sh_index(2, -2)], 1.0925484 * x * yy, 1e-6);
        EXPECT_NEAR(y[sh_index(2, -1)], 1.0925484 * yy * z, 1e-6);
        EXPECT_NEAR(y[sh_index(2, 0)], 0.3153916 * (3 * z * z - 1), 1e-6);
        EXPECT_NEAR(y[sh_index(2, 1)], 1.0925484 * x * z, 1e-6);
        EXPECT_NEAR(y[sh_index(2, 2)], 0.5462742 * (x * x - yy * yy), 1e-6);
    }
}

TEST(SphericalHarmonics, AdditionTheoremHoldsUpToTheHighestOrder)
{
    // Σ_m Y_lm(a) Y_lm(b) = (2l+1)/(4π) P_l(a·b): orthonormal, correctly normalized bands.
    const Vec3 pairs[][2] = {{{0.3f, -0.5f, 0.8f}, {-0.2f, 0.9f, 0.4f}}, {{0, 0, 1}, {1, 0, 0}}, {{0.6f, 0.8f, 0}, {0.6f, 0.8f, 0}}};
    std::vector<double> ya(sh_count(kMaxShOrder)), yb(sh_count(kMaxShOrder));
    for (const auto& pair : pairs) {
        const Vec3 a = normalize_or(pair[0], {}), b = normalize_or(pair[1], {});
        real_sh(a, kMaxShOrder, ya.data());
        real_sh(b, kMaxShOrder, yb.data());
        for (int l = 0; l <= kMaxShOrder; ++l) {
            double sum = 0.0;
            for (int m = -l; m <= l; ++m) sum += ya[size_t(sh_index(l, m))] * yb[size_t(sh_index(l, m))];
            EXPECT_NEAR(sum, (2 * l + 1) / (4 * kPi) * std::legendre(unsigned(l), double(dot(a, b))), 1e-5) << "l " << l;
        }
    }
}

TEST(SphericalHarmonics, ZonalCoefficientsMatchHandIntegrals)
{
    // Lambert, ρ̂_l = 2 ∫₀¹ c P_l(c) dc: 1, 2/3, 1/4, 0, −1/24, 0, 1/64, 0, −1/128 (Ramamoorthi &
    // Hanrahan's Â_l divided by π).
    const double lambert[9] = {1.0, 2.0 / 3.0, 0.25, 0.0, -1.0 / 24.0, 0.0, 1.0 / 64.0, 0.0, -1.0 / 128.0};
    const auto rho = zonal_brdf_coefficients(BaseBrdf::lambert(), 8);
    for (int l = 0; l <= 8; ++l) EXPECT_NEAR(rho[size_t(l)], lambert[l], 1e-7) << l;
    // Normalized Blinn-Phong, ρ̂_l = (s+1) ∫₀¹ c^s P_l: 1, (s+1)/(s+2), (s+1)/2·(3/(s+3) − 1/(s+1)) = s/(s+3).
    for (float s : {8.0f, 32.0f, 256.0f}) {
        const auto bp = zonal_brdf_coefficients(BaseBrdf::blinn_phong(s), 2);
        EXPECT_NEAR(bp[0], 1.0, 1e-6);
        EXPECT_NEAR(bp[1], (s + 1.0) / (s + 2.0), 1e-6);
        EXPECT_NEAR(bp[2], s / (s + 3.0), 1e-6);
    }
    // GGX is normalized over projected area, ∫ D cos θ dω = 1, so ρ̂_1 = 1; at roughness 1 (α = 1)
    // D = 1/π and ρ̂_l = 2 ∫₀¹ P_l: 2, 1, 0, −1/4.
    for (float roughness : {0.3f, 0.5f, 1.0f}) EXPECT_NEAR(zonal_brdf_coefficients(BaseBrdf::ggx(roughness), 1)[1], 1.0, 1e-5);
    const auto flat = zonal_brdf_coefficients(BaseBrdf::ggx(1.0f), 3);
    EXPECT_NEAR(flat[0], 2.0, 1e-6);
    EXPECT_NEAR(flat[2], 0.0, 1e-6);
    EXPECT_NEAR(flat[3], -0.25, 1e-6);
}

// The order-2 truncation of Lambert about one normal, Σ_{l≤2} (2l+1)/(4π) ρ̂_l P_l(c), by hand:
// (1/4π)(1 + 2c + (5/8)(3c² − 1)) = (3/32 + c/2 + 15c²/32)/π.
double lambert_order2(double c) { return (3.0 / 32.0 + c / 2.0 + 15.0 * c * c / 32.0) / kPi; }

TEST(ShNdf, OneNormalUnderLambertAtOrderTwoMissesBySixteenth)
{
    // Directions uniform over the upper hemisphere make c = ω·ẑ uniform on [0, 1]. The residual
    // (3/32 − c/2 + 15c²/32)/π has ∫₀¹ residual² = 1/(768π²) against ∫₀¹ (c/π)² = 1/(3π²), so the
    // relative L2 error is √(3/768) = 1/16 exactly: SH-2 is not within 3% of a point-lit texel.
    const NormalMap map = make_map(1, 1, {{0, 0, 1}});
    const auto pyramid = build_baseline("sh-2", map, WrapMode::clamp);
    const auto directions = fibonacci_hemisphere(kMaxErrorDirections);
    const float error = relative_l2_error(evaluate(*pyramid, 0, 0, 0, BaseBrdf::lambert(), directions),
                                          reference(map, 0, 0, 0, WrapMode::clamp, BaseBrdf::lambert(), directions));
    EXPECT_NEAR(error, 1.0 / 16.0, 5e-4);
}

TEST(ShNdf, OrderTwoIsTheTruncatedCosineAveragedOverEveryTexel)
{
    // Eq. 11 at order 2 under Lambert is, for any NDF, the mean of the hand-derived truncated
    // cosine over the texel's normals: this checks basis, ρ̂_l, Λ_l and the pyramid's averaging
    // together. Against the exact effective BRDF no texel may do worse than its worst single normal.
    const BaseBrdf lambert = BaseBrdf::lambert();
    const auto directions = fibonacci_hemisphere(error_direction_count(lambert));
    double worst = 0.0;
    for (Pattern pattern : {Pattern::fbm, Pattern::bumps, Pattern::weave, Pattern::vgroove}) {
        const NormalMap map = synthesize(pattern, 32, 32);
        // The SH-2 error of each fine normal alone, from the closed form.
        std::vector<double> single(map.normals.size());
        for (size_t i = 0; i < map.normals.size(); ++i) {
            std::vector<float> truncated(directions.size()), exact(directions.size());
            for (size_t d = 0; d < directions.size(); ++d) {
                const float c = dot(directions[d], map.normals[i]);
                truncated[d] = float(lambert_order2(c));
                exact[d] = lambert.eval(c);
            }
            single[i] = relative_l2_error(truncated, exact);
        }
        const NormalMap tags = tagged_map(map.width, map.height);
        const auto pyramid = build_baseline("sh-2", map, WrapMode::wrap);
        for (int level = 0; level < pyramid->level_count(); ++level) {
            const LevelSize size = pyramid->size(level);
            for (int y = 0; y < size.height; ++y)
                for (int x = 0; x < size.width; ++x) {
                    const auto fit = evaluate(*pyramid, level, x, y, lambert, directions);
                    std::vector<WeightedNormal> samples;
                    gather_footprint(map, level, x, y, WrapMode::wrap, samples);
                    double bound = 0.0;
                    for (const auto& [index, weight] : gathered_weights(tags, level, x, y, WrapMode::wrap))
                        bound = std::max(bound, single[size_t(index)]);
                    double total = 0.0;
                    std::vector<double> mean(directions.size(), 0.0);
                    for (const WeightedNormal& s : samples) {
                        total += s.weight;
                        for (size_t d = 0; d < directions.size(); ++d) mean[d] += s.weight * lambert_order2(dot(directions[d], s.n));
                    }
                    for (size_t d = 0; d < directions.size(); ++d) ASSERT_NEAR(fit[d], mean[d] / total, 2e-6);
                    const float error = relative_l2_error(fit, reference(map, level, x, y, WrapMode::wrap, lambert, directions));
                    EXPECT_LE(error, bound + 1e-4) << pattern_name(pattern) << " level " << level;
                    worst = std::max(worst, double(error));
                }
        }
    }
    // Every fine normal of these maps is within 50° of ẑ, where one normal alone misses by under 7%.
    EXPECT_LT(worst, 0.07);
}

TEST(ShNdf, OrderTwoShadesLambertWithinThreePercentUnderEnvironmentLight)
{
    // Han §5.2 (after Ramamoorthi & Hanrahan): nine coefficients carry Lambertian shading within a
    // few percent under environment lighting, which is smooth. The shading of a texel is
    // ∫ L(ω) ρ_eff(ω) dω over the sphere; compare SH-2's with the exact one of every texel, under a
    // sky, a sky with a broad sun, and a sun near the horizon.
    std::vector<Vec3> sphere;
    for (const Vec3& d : fibonacci_hemisphere(4096)) {
        sphere.push_back(d);
        sphere.push_back({d.x, d.y, -d.z});
    }
    const Vec3 sun = normalize_or({0.6f, 0.3f, 0.75f}, {0, 0, 1}), low_sun = normalize_or({-0.9f, 0.2f, 0.15f}, {0, 0, 1});
    const std::vector<std::function<float(const Vec3&)>> environments = {
        [](const Vec3& w) { return 1.0f + 0.8f * w.z; },
        [&](const Vec3& w) { return 0.6f + 0.4f * w.z + 4.0f * std::exp(3.0f * (dot(w, sun) - 1.0f)); },
        [&](const Vec3& w) { return 0.3f + 6.0f * std::exp(4.0f * (dot(w, low_sun) - 1.0f)); },
    };
    const BaseBrdf lambert = BaseBrdf::lambert();
    double worst = 0.0;
    for (Pattern pattern : {Pattern::fbm, Pattern::bumps, Pattern::weave, Pattern::vgroove}) {
        const NormalMap map = synthesize(pattern, 32, 32);
        const auto pyramid = build_baseline("sh-2", map, WrapMode::wrap);
        for (int level = 0; level < pyramid->level_count(); ++level) {
            const LevelSize size = pyramid->size(level);
            for (int y = 0; y < size.height; ++y)
                for (int x = 0; x < size.width; ++x) {
                    const auto fit = evaluate(*pyramid, level, x, y, lambert, sphere);
                    const auto exact = reference(map, level, x, y, WrapMode::wrap, lambert, sphere);
                    for (const auto& light : environments) {
                        double shade_fit = 0.0, shade_exact = 0.0;
                        for (size_t d = 0; d < sphere.size(); ++d) {
                            shade_fit += light(sphere[d]) * fit[d];
                            shade_exact += light(sphere[d]) * exact[d];
                        }
                        worst = std::max(worst, std::abs(shade_fit - shade_exact) / shade_exact);
                    }
                }
        }
    }
    std::printf("SH-2 Lambert shading under environment light: worst relative error %.4f\n", worst);
    EXPECT_LT(worst, 0.03);
}

TEST(ShNdf, ErrorFallsWithOrderOnMultiLobeTexels)
{
    const BaseBrdf brdf = BaseBrdf::blinn_phong(32.0f);
    struct Case {
        Pattern pattern;
        int level;
    };
    for (const Case c : {Case{Pattern::vgroove, 2}, Case{Pattern::weave, 3}, Case{Pattern::weave, 5}}) {
        const NormalMap map = synthesize(c.pattern, 32, 32);
        double previous = 1e9;
        for (int order = 2; order <= 8; ++order) {
            const auto pyramid = build_baseline("sh-" + std::to_string(order), map, WrapMode::wrap);
            const double error = texel_error(*pyramid, map, c.level, 0, 0, WrapMode::wrap, brdf);
            EXPECT_LT(error, previous) << pattern_name(c.pattern) << " order " << order;
            previous = error;
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Xu et al. 2017 partitions

TEST(XuPartitions, CellsAreTheSectorsAndBandsDocumented)
{
    EXPECT_EQ(xu_cell(XuPartition::sectors, {1, 0.2f, 0.5f}), 0);    // +X
    EXPECT_EQ(xu_cell(XuPartition::sectors, {0.2f, 1, 0.5f}), 1);    // +Y
    EXPECT_EQ(xu_cell(XuPartition::sectors, {-1, -0.2f, 0.5f}), 2);  // −X
    EXPECT_EQ(xu_cell(XuPartition::sectors, {0.2f, -1, 0.5f}), 3);   // −Y
    EXPECT_EQ(xu_cell(XuPartition::sectors_bands, normalize_or({0.5f, 0, 1}, {})), 0);   // 26.6°: cap
    EXPECT_EQ(xu_cell(XuPartition::sectors_bands, normalize_or({1.2f, 0, 1}, {})), 1);   // 50.2°: ring
    EXPECT_EQ(xu_cell(XuPartition::sectors_bands, normalize_or({0, -1.2f, 1}, {})), 7);  // −Y ring
    EXPECT_EQ(xu_cell(XuPartition::whole, {0, -1, 0}), 0);
}

TEST(XuPartitions, LevelsArePlainAveragesOfTheirChildren)
{
    const NormalMap map = synthesize(Pattern::weave, 16, 16);
    for (const char* name : {"xu-1x1", "xu-1x4", "xu-2x4"}) {
        const auto pyramid = build_baseline(name, map, WrapMode::clamp);
        const LinearNdfPyramid& storage = linear(*pyramid);
        for (int level = 1; level < storage.level_count(); ++level) {
            const LevelSize size = storage.size(level);
            for (int y = 0; y < size.height; ++y)
                for (int x = 0; x < size.width; ++x) {
                    const auto parent = storage.texel(level, x, y);
                    double alpha = 0.0;
                    for (size_t k = 0; k < parent.size(); ++k) {
                        double children = 0.0;
                        for (int dy = 0; dy < 2; ++dy)
                            for (int dx = 0; dx < 2; ++dx) children += storage.texel(level - 1, 2 * x + dx, 2 * y + dy)[k];
                        EXPECT_NEAR(parent[k], children / 4.0, 1e-6) << name << " level " << level;
                        if (k % kXuFloatsPerCell == 0) alpha += parent[k];
                    }
                    EXPECT_NEAR(alpha, 1.0, 1e-6);  // the cells' weights w⁽ʲ⁾ of eq. 15 sum to one
                }
        }
    }
}

TEST(XuPartitions, SectorsSeparateTheVGrooveFacets)
{
    // The groove's facets lean towards +X and −X: each sector cell holds identical normals, so the
    // mixture is exact where every single lobe is badly wrong.
    const NormalMap map = synthesize(Pattern::vgroove, 16, 16);
    const BaseBrdf brdf = BaseBrdf::blinn_phong(32.0f);
    const auto one = build_baseline("xu-1x1", map, WrapMode::wrap);
    for (const char* name : {"xu-1x4", "xu-2x4", "xu-adaptive"}) {
        const auto pyramid = build_baseline(name, map, WrapMode::wrap);
        for (int level = 1; level < pyramid->level_count(); ++level) {
            EXPECT_LT(level_error(*pyramid, map, level, WrapMode::wrap, brdf), 1e-2) << name << " level " << level;
            EXPECT_GT(level_error(*one, map, level, WrapMode::wrap, brdf), 0.5) << "level " << level;
        }
    }
}

TEST(XuPartitions, TwoByFourIsAtLeastAsGoodAsOneLobeOnTheWeave)
{
    const NormalMap map = synthesize(Pattern::weave, 64, 64);
    const auto one = build_baseline("xu-1x1", map, WrapMode::wrap);
    const auto eight = build_baseline("xu-2x4", map, WrapMode::wrap);
    for (const BaseBrdf& brdf : {BaseBrdf::blinn_phong(32.0f), BaseBrdf::ggx(0.5f)})
        for (int level = 3; level < one->level_count(); ++level)
            EXPECT_LE(level_error(*eight, map, level, WrapMode::wrap, brdf), level_error(*one, map, level, WrapMode::wrap, brdf))
                << brdf.to_string() << " level " << level;
}

TEST(XuPartitions, AdaptiveStoresOnlyTheCellsItShades)
{
    // All normals equal: |r| = 1 ≥ ε0 everywhere, one cell (4 floats) per texel.
    const auto flat = build_baseline("xu-adaptive", make_map(4, 4, std::vector<Vec3>(16, Vec3{0.2f, 0.1f, 1})), WrapMode::clamp);
    EXPECT_DOUBLE_EQ(dynamic_cast<const XuAdaptivePyramid&>(*flat).mean_floats_per_texel(), 4.0);
    EXPECT_EQ(flat->floats_per_texel(), 4);
    // V-groove 16×16: level 0 texels hold one normal (one cell each, 256 × 4 floats); every coarser
    // texel sees both facets equally, |r| = cos 30° = 0.866 < ε0 = 0.95, and splits into the ±X
    // sectors, whose |r| = 1 ≥ ε1 keeps them whole: 2 cells = 8 floats on 64 + 16 + 4 + 1 texels.
    // Mean: (1024 + 85·8) / 341 = 1704/341.
    const auto groove = build_baseline("xu-adaptive", synthesize(Pattern::vgroove, 16, 16), WrapMode::clamp);
    const auto& adaptive = dynamic_cast<const XuAdaptivePyramid&>(*groove);
    EXPECT_NEAR(adaptive.mean_floats_per_texel(), 1704.0 / 341.0, 1e-12);
    EXPECT_EQ(adaptive.floats_per_texel(), 5);
    EXPECT_EQ(adaptive.texel(2, 1, 1).size(), 8u);
    EXPECT_EQ(adaptive.texel(0, 3, 3).size(), 4u);
}

// ---------------------------------------------------------------------------------------------
// Every baseline

int documented_floats(const std::string& name)
{
    if (name == "naive" || name == "toksvig" || name == "single-vmf") return 3;
    if (name == "lean") return 5;
    if (name == "xu-1x1") return 4;
    if (name == "xu-1x4") return 16;
    if (name == "xu-2x4") return 32;
    const int order = std::stoi(name.substr(3));
    return (order + 1) * (order + 1);
}

TEST(Baselines, RegistryListsEveryNameAndRejectsUnknownOnes)
{
    const std::vector<std::string> expected = {"naive", "toksvig", "single-vmf", "lean", "xu-1x1", "xu-1x4", "xu-2x4",
                                               "xu-adaptive", "sh-2", "sh-3", "sh-4", "sh-5", "sh-6", "sh-7", "sh-8"};
    EXPECT_EQ(baseline_names(), expected);
    const NormalMap map = make_map(2, 2, std::vector<Vec3>(4, Vec3{0, 0, 1}));
    for (const char* bad : {"", "vmf", "sh-", "sh-x", "sh-2x", "sh-17", "sh--1", "LEAN", "xu-3x3"}) {
        try {
            build_baseline(bad, map, WrapMode::wrap);
            ADD_FAILURE() << "accepted '" << bad << "'";
        } catch (const Error& e) {
            EXPECT_EQ(e.status(), Status::invalid_argument);
        }
    }
    EXPECT_EQ(build_baseline("sh-12", map, WrapMode::wrap)->floats_per_texel(), 169);
    try {
        build_baseline("naive", NormalMap{}, WrapMode::wrap);
        ADD_FAILURE() << "accepted an empty map";
    } catch (const Error& e) {
        EXPECT_EQ(e.status(), Status::invalid_argument);
    }
}

TEST(Baselines, HardMapsGiveDocumentedSizesStorageAndFiniteShading)
{
    const float c45 = std::sqrt(0.5f);
    std::vector<NormalMap> maps = {
        make_map(1, 1, {{0.3f, -0.2f, 0.93f}}),
        make_map(1, 7, {{0, 0, 1}, {1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {c45, c45, 0}, {0, 0, 1}}),
        synthesize(Pattern::weave, 3, 5),
        make_map(4, 3, std::vector<Vec3>(12, Vec3{0.3f, -0.2f, 0.93f})),
        make_map(2, 2, {{1, 0, 0}, {0, 1, 0}, {-1, 0, 0}, {0, -1, 0}}),  // all on the horizon
    };
    maps[2].normals[0] = {1, 0, 0};
    maps[2].normals[1] = {0, 0, -1};  // a decoder reflects these; the baselines must survive them anyway
    const BaseBrdf brdfs[] = {BaseBrdf::lambert(), BaseBrdf::blinn_phong(32.0f), BaseBrdf::ggx(0.3f), BaseBrdf::beckmann(0.2f)};
    const auto directions = fibonacci_hemisphere(256);
    for (const NormalMap& map : maps)
        for (WrapMode wrap : {WrapMode::clamp, WrapMode::wrap})
            for (const std::string& name : baseline_names()) {
                const auto pyramid = build_baseline(name, map, wrap);
                EXPECT_EQ(pyramid->name(), name);
                ASSERT_EQ(pyramid->level_count(), level_count(map.width, map.height)) << name;
                if (name == "xu-adaptive") {
                    const double mean = dynamic_cast<const XuAdaptivePyramid&>(*pyramid).mean_floats_per_texel();
                    EXPECT_GE(mean, 4.0);
                    EXPECT_LE(mean, 32.0);
                    EXPECT_EQ(pyramid->floats_per_texel(), int(std::ceil(mean)));
                } else {
                    EXPECT_EQ(pyramid->floats_per_texel(), documented_floats(name)) << name;
                }
                for (int level = 0; level < pyramid->level_count(); ++level) {
                    const LevelSize size = pyramid->size(level);
                    EXPECT_EQ(size, level_size(map.width, map.height, level)) << name;
                    for (int y = 0; y < size.height; ++y)
                        for (int x = 0; x < size.width; ++x)
                            for (const BaseBrdf& brdf : brdfs)
                                for (float v : evaluate(*pyramid, level, x, y, brdf, directions))
                                    ASSERT_TRUE(std::isfinite(v)) << name << " " << brdf.to_string() << " level " << level;
                }
            }
}

TEST(Baselines, TexelOutOfRangeThrows)
{
    const auto pyramid = build_baseline("lean", make_map(2, 2, std::vector<Vec3>(4, Vec3{0, 0, 1})), WrapMode::wrap);
    std::vector<float> out(1);
    const std::vector<Vec3> directions = {{0, 0, 1}};
    EXPECT_THROW(pyramid->effective_brdf(1, 1, 0, BaseBrdf::lambert(), directions, out), Error);
    EXPECT_THROW(pyramid->effective_brdf(2, 0, 0, BaseBrdf::lambert(), directions, out), Error);
    std::vector<float> short_out;
    EXPECT_THROW(pyramid->effective_brdf(0, 0, 0, BaseBrdf::lambert(), directions, short_out), Error);
}

}  // namespace
}  // namespace ndfbake
