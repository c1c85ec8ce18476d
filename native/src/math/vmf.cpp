#include "math/vmf.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

namespace ndfbake {

namespace {
// Below this κ the series forms are exact to double precision and the closed forms cancel.
constexpr double kSmallKappa = 1e-2;
}  // namespace

double mean_resultant_length(double kappa)
{
    if (kappa < kSmallKappa) {
        // coth κ − 1/κ = κ/3 − κ³/45 + 2κ⁵/945 − …
        const double k2 = kappa * kappa;
        return kappa * (1.0 / 3.0 - k2 / 45.0);
    }
    return 1.0 / std::tanh(kappa) - 1.0 / kappa;
}

namespace {

// Solves g(R) = R(3 − R²) − k(1 − R²) = 0 on (0, 1): g(0) = −k < 0 < 2 = g(1), and g is
// increasing there, so bisection is safe; Newton from the bracket then converges quickly.
double solve_resultant(double k)
{
    double lo = 0.0, hi = 1.0;
    double r = std::clamp(mean_resultant_length(k), 1e-12, 1.0 - 1e-12);
    for (int i = 0; i < 100; ++i) {
        const double g = r * (3.0 - r * r) - k * (1.0 - r * r);
        if (g < 0.0) lo = r; else hi = r;
        const double dg = 3.0 - 3.0 * r * r + 2.0 * k * r;
        double next = r - g / dg;
        if (!(next > lo && next < hi)) next = 0.5 * (lo + hi);
        // Converged to rounding: a fixed absolute 1e-16 is below double's spacing near 1 and
        // would run every iteration.
        if (std::abs(next - r) <= 4.0 * std::numeric_limits<double>::epsilon() * next) return next;
        r = next;
    }
    return r;
}

// The resultant whose Banerjee κ is kKappaMax, solved once: every level-0 texel is a lobe of
// κ = kKappaMax, and every fine normal's resultant saturates.
double resultant_at_kappa_max()
{
    static const double r = solve_resultant(kKappaMax);
    return r;
}

// Past resultant_at_kappa_max() plus this margin (far above rounding) Banerjee's κ exceeds the
// cap: kappa_from_resultant returns it without the division.
constexpr double kSaturationMargin = 1e-12;

}  // namespace

float kappa_from_resultant(double r)
{
    if (!(r > 0.0)) return kKappaMin;  // also catches NaN
    if (r >= resultant_at_kappa_max() + kSaturationMargin) return kKappaMax;
    const double kappa = r * (3.0 - r * r) / (1.0 - r * r);
    return float(std::clamp(kappa, double(kKappaMin), double(kKappaMax)));
}

double resultant_from_kappa(float kappa)
{
    if (kappa >= kKappaMax) return resultant_at_kappa_max();
    return solve_resultant(std::max(double(kappa), double(kKappaMin)));
}

double lobe_resultant(float kappa)
{
    return kappa >= kKappaMax ? 1.0 : resultant_from_kappa(kappa);
}

double log_vmf_normalizer_shifted(double kappa)
{
    constexpr double log_4pi = 2.5310242469692907;  // log(4π)
    constexpr double log_2pi = 1.8378770664093453;  // log(2π)
    if (kappa < kSmallKappa) {
        // log(κ / sinh κ) = −κ²/6 + O(κ⁴)
        return -log_4pi - kappa * kappa / 6.0 + kappa;
    }
    // log C + κ = log κ − log 2π − log(1 − e^{−2κ}); past κ = 20 the last term is under 5e-18,
    // below double's rounding of the rest, and EM asks for this of every lobe every iteration.
    if (kappa > 20.0) return std::log(kappa) - log_2pi;
    return std::log(kappa) - log_2pi - std::log1p(-std::exp(-2.0 * kappa));
}

void vmf_legendre_coefficients(double kappa, int lmax, double* out)
{
    // Ratios ρ_l = I_{l+1/2}/I_{l−1/2} from the continued fraction ρ_l = 1/((2l+1)/κ + ρ_{l+1}),
    // run downwards from far above lmax (Miller): upward recurrence loses all digits for small κ.
    if (kappa >= double(kKappaMax)) {
        // The continued fraction would have to start beyond κ: the asymptotic form instead.
        for (int l = 0; l <= lmax; ++l) out[l] = std::exp(-0.5 * l * (l + 1) / kappa);
        return;
    }
    const double k = std::max(kappa, double(kKappaMin));
    // The fraction only settles where (2l+1)/κ ≳ 1, so start beyond κ: a start below it
    // oscillates between two wrong ratios instead of converging.
    const int start = lmax + 40 + int(k);
    double rho = 0.0;
    std::vector<double> ratios(size_t(lmax) + 1, 0.0);
    for (int l = start; l >= 1; --l) {
        rho = 1.0 / ((2.0 * l + 1.0) / k + rho);
        if (l <= lmax) ratios[size_t(l)] = rho;
    }
    out[0] = 1.0;
    for (int l = 1; l <= lmax; ++l) out[l] = out[l - 1] * ratios[size_t(l)];
}

void drop_light_lobes(std::vector<VmfLobe>& lobes, float min_alpha)
{
    std::erase_if(lobes, [&](const VmfLobe& l) { return !(l.alpha > 0.0f && l.alpha >= min_alpha); });
    float total = 0.0f;
    for (const VmfLobe& l : lobes) total += l.alpha;
    if (total > 0.0f)
        for (VmfLobe& l : lobes) l.alpha /= total;
}

}  // namespace ndfbake
