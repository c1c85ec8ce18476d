#include "baselines/spherical_harmonics.h"

#include <array>
#include <cmath>
#include <numbers>

namespace ndfbake {

namespace {

// Gauss–Legendre nodes per panel: exact for polynomials of degree 31 on each panel, far above the
// Legendre degrees we integrate against once the panels have cut the peak down to size.
constexpr int kGaussNodes = 16;
// Panels [1 − 2^−k, 1 − 2^−(k+1)] for k < this, then [1 − 2^−k, 1]: the last one is narrower than
// float's spacing below 1 (2^−24), so no lobe brdf.eval can express is narrower than a panel.
constexpr int kHalvingPanels = 26;

struct GaussRule {
    std::array<double, kGaussNodes> node{}, weight{};
};

// Nodes and weights on [−1, 1]: Newton on P_n from the Chebyshev-like initial guesses.
const GaussRule& gauss_legendre()
{
    static const GaussRule rule = [] {
        GaussRule r;
        constexpr int n = kGaussNodes;
        for (int i = 0; i < n; ++i) {
            double x = std::cos(std::numbers::pi * (i + 0.75) / (n + 0.5));
            double derivative = 1.0;
            for (int iteration = 0; iteration < 100; ++iteration) {
                double p0 = 1.0, p1 = x;
                for (int k = 2; k <= n; ++k) {
                    const double p2 = ((2.0 * k - 1.0) * x * p1 - (k - 1.0) * p0) / k;
                    p0 = p1;
                    p1 = p2;
                }
                derivative = n * (x * p1 - p0) / (x * x - 1.0);
                const double step = p1 / derivative;
                x -= step;
                if (std::abs(step) < 1e-16) break;
            }
            r.node[size_t(i)] = x;
            r.weight[size_t(i)] = 2.0 / ((1.0 - x * x) * derivative * derivative);
        }
        return r;
    }();
    return rule;
}

}  // namespace

void real_sh(const Vec3& direction, int order, double* out)
{
    double x = direction.x, y = direction.y, z = direction.z;
    const double len = std::sqrt(x * x + y * y + z * z);
    if (len > 0.0 && std::isfinite(len)) {
        x /= len;
        y /= len;
        z /= len;
    } else {
        x = 0.0;
        y = 0.0;
        z = 1.0;
    }
    // q[m] holds K_lm P_l^m(z) / sin^m θ for the current l; the sin^m θ factor rides on
    // (x + iy)^m = sin^m θ (cos mφ + i sin mφ).
    double c_m = 1.0, s_m = 0.0;       // Re, Im of (x + iy)^m
    double diagonal = 0.5 / std::sqrt(std::numbers::pi);  // K_00 = √(1/4π)
    for (int m = 0; m <= order; ++m) {
        if (m > 0) {
            diagonal *= std::sqrt((2.0 * m + 1.0) / (2.0 * m));  // the l = m term from l = m − 1
            const double c = x * c_m - y * s_m;
            s_m = x * s_m + y * c_m;
            c_m = c;
        }
        const double cos_factor = m == 0 ? 1.0 : std::numbers::sqrt2 * c_m;
        const double sin_factor = std::numbers::sqrt2 * s_m;
        double previous = 0.0, current = diagonal;
        for (int l = m; l <= order; ++l) {
            if (l == m + 1) {
                previous = current;
                current = std::sqrt(2.0 * m + 3.0) * z * previous;
            } else if (l > m + 1) {
                const double ll = double(l) * l, mm = double(m) * m, l1 = double(l - 1) * (l - 1);
                const double a = std::sqrt((4.0 * ll - 1.0) / (ll - mm));
                const double b = std::sqrt((l1 - mm) / (4.0 * l1 - 1.0));
                const double next = a * (z * current - b * previous);
                previous = current;
                current = next;
            }
            out[sh_index(l, m)] = current * cos_factor;
            if (m > 0) out[sh_index(l, -m)] = current * sin_factor;
        }
    }
}

std::vector<double> zonal_brdf_coefficients(const BaseBrdf& brdf, int order)
{
    std::vector<double> rho(size_t(order) + 1, 0.0);
    const GaussRule& rule = gauss_legendre();
    std::vector<double> legendre(size_t(order) + 1);
    auto panel = [&](double lo, double hi) {
        const double half = 0.5 * (hi - lo), mid = 0.5 * (hi + lo);
        for (int i = 0; i < kGaussNodes; ++i) {
            const double c = mid + half * rule.node[size_t(i)];
            const double f = brdf.eval(float(c));
            if (f == 0.0) continue;
            // P_l(c) by Bonnet's recurrence.
            double p_prev = 1.0, p = c;
            legendre[0] = 1.0;
            if (order >= 1) legendre[1] = c;
            for (int l = 1; l < order; ++l) {
                const double p_next = ((2.0 * l + 1.0) * c * p - l * p_prev) / (l + 1.0);
                p_prev = p;
                p = p_next;
                legendre[size_t(l) + 1] = p;
            }
            const double w = half * rule.weight[size_t(i)] * f;
            for (int l = 0; l <= order; ++l) rho[size_t(l)] += w * legendre[size_t(l)];
        }
    };
    panel(-1.0, 0.0);
    double lo = 0.0;
    for (int k = 1; k <= kHalvingPanels; ++k) {
        const double hi = 1.0 - std::ldexp(1.0, -k);
        panel(lo, hi);
        lo = hi;
    }
    panel(lo, 1.0);
    for (double& r : rho) r *= 2.0 * std::numbers::pi;  // ρ̂_l = 2π ∫ f P_l dc
    return rho;
}

}  // namespace ndfbake
