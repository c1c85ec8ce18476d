#include "baselines/lean.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include "baselines/linear_pyramid.h"
#include "error.h"

namespace ndfbake {

namespace {

// The base lobe as a slope distribution (see lean.h): P22's degrees of freedom ν (∞: Gaussian),
// its per-axis scale σ_b² (S_b = σ_b² I) and the factor K that turns D = P22/cos⁴ into
// brdf.eval's normalization.
struct SlopeLobe {
    double nu;
    double scale;
    double factor;
};

SlopeLobe slope_lobe(const BaseBrdf& brdf)
{
    const double p = brdf.parameter();
    switch (brdf.kind()) {
    case BrdfKind::ggx: return {2.0, 0.5 * (p * p) * (p * p), 1.0};  // α = roughness²
    case BrdfKind::beckmann: return {std::numeric_limits<double>::infinity(), 0.5 * p * p, 1.0};
    case BrdfKind::blinn_phong: return {p + 2.0, 1.0 / (p + 2.0), (p + 1.0) / (p + 2.0)};
    case BrdfKind::lambert: break;
    }
    throw Error(Status::internal, "LEAN has no slope lobe for " + brdf.to_string());
}

// (1 + q/ν)^−(ν+2)/2, and its limit exp(−q/2) as ν → ∞.
double slope_shape(double q, double nu)
{
    if (std::isinf(nu)) return std::exp(-0.5 * q);
    return std::exp(-0.5 * (nu + 2.0) * std::log1p(q / nu));
}

class LeanPyramid final : public LinearNdfPyramid {
public:
    LeanPyramid(const NormalMap& map, WrapMode wrap)
        : LinearNdfPyramid(map, wrap, kLeanFloats, [](const Vec3& n, float* out) {
              const Slope t = lean_slope(n);
              out[0] = float(t.x);
              out[1] = float(t.y);
              out[2] = float(t.x * t.x);
              out[3] = float(t.y * t.y);
              out[4] = float(t.x * t.y);
          })
    {
    }

    std::string name() const override { return "lean"; }

    void effective_brdf(int level, int x, int y, const BaseBrdf& brdf, std::span<const Vec3> directions,
                        std::span<float> out) const override
    {
        check_output(directions, out);
        const std::span<const float> m = texel(level, x, y);
        const double tx = m[0], ty = m[1];
        if (brdf.kind() == BrdfKind::lambert) {
            // LEAN is specular-only: diffuse shades with the normal of the mean slope.
            const Vec3 normal = normalize_or(Vec3{float(tx), float(ty), 1.0f}, {0.0f, 0.0f, 1.0f});
            for (size_t d = 0; d < directions.size(); ++d) out[d] = brdf.eval(dot(directions[d], normal));
            return;
        }
        // Σ = M − t̄t̄ᵀ (survey eq. 19's covariance), kept positive semi-definite against rounding.
        const double sxx = std::max(0.0, double(m[2]) - tx * tx);
        const double syy = std::max(0.0, double(m[3]) - ty * ty);
        const double bound = std::sqrt(sxx * syy);
        const double sxy = std::clamp(double(m[4]) - tx * ty, -bound, bound);
        // S = Σ + S_b(t̄): LEAN's "add the base lobe's variance", taken at the mean slope (lean.h).
        const SlopeLobe base = slope_lobe(brdf);
        const double tilt2 = 1.0 + tx * tx + ty * ty;  // 1 + |t̄|² = 1/cos²β̄
        const double spread = base.scale * tilt2;
        const double a = sxx + spread * (1.0 + tx * tx), b = sxy + spread * tx * ty, c = syy + spread * (1.0 + ty * ty);
        const double det = a * c - b * b;  // ≥ det S_b > 0
        const double peak = base.factor / (std::sqrt(tilt2) * 2.0 * std::numbers::pi * std::sqrt(det));  // K cos β̄ / (2π √det S)
        for (size_t i = 0; i < directions.size(); ++i) {
            const Vec3 h = directions[i];
            if (!(h.z > 0.0f)) {
                out[i] = 0.0f;  // both base lobes vanish below the horizon
                continue;
            }
            const double hz = h.z;
            const double dx = h.x / hz - tx, dy = h.y / hz - ty;
            const double q = (c * dx * dx - 2.0 * b * dx * dy + a * dy * dy) / det;  // dᵀS⁻¹d
            // f(h) = K cos β̄ · P22(t_h − t̄; ν, S) / h_z⁴ (bivariate Student-t over slopes, lean.h).
            const double p22 = peak * slope_shape(q, base.nu);
            const double hz2 = hz * hz;
            out[i] = float(p22 / (hz2 * hz2));
        }
    }
};

}  // namespace

Slope lean_slope(const Vec3& n)
{
    const double tangential = std::hypot(double(n.x), double(n.y));
    if (tangential == 0.0) return {};
    if (double(n.z) * kLeanMaxSlope <= tangential) {
        const double scale = kLeanMaxSlope / tangential;
        return {n.x * scale, n.y * scale};
    }
    return {n.x / double(n.z), n.y / double(n.z)};
}

std::unique_ptr<NdfPyramid> make_lean_pyramid(const NormalMap& map, WrapMode wrap)
{
    return std::make_unique<LeanPyramid>(map, wrap);
}

}  // namespace ndfbake
