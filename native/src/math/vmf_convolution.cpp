#include "math/vmf_convolution.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "math/vmf.h"

namespace ndfbake {

namespace {

// The vMF density beyond θ where κ(1 − cos θ) = 40 is below e^{−40} of its peak.
constexpr double kVmfTailExponent = 40.0;
// Quadrature steps per width of the narrower of the two lobes.
constexpr double kStepsPerWidth = 8.0;

}  // namespace

double convolve_with_vmf(const std::function<double(double)>& f, double f_width, double kappa, double beta)
{
    constexpr double pi = std::numbers::pi;
    const double vmf_width = 1.0 / std::sqrt(kappa);
    const double step = std::min({f_width, vmf_width, 0.05}) / kStepsPerWidth;
    const double cos_max = 1.0 - kVmfTailExponent / kappa;
    const double theta_max = cos_max <= -1.0 ? pi : std::acos(cos_max);
    const int theta_steps = std::max(64, int(std::ceil(theta_max / step)));
    // p(θ) dθ = κ e^{κ(cos θ − 1)} sin θ dθ / (1 − e^{−2κ}): the vMF's polar density about μ.
    const double norm = kappa / -std::expm1(-2.0 * kappa);
    const double sin_beta = std::sin(beta), cos_beta = std::cos(beta);
    double sum = 0.0, mass = 0.0;
    const double dtheta = theta_max / theta_steps;
    for (int i = 0; i < theta_steps; ++i) {
        const double theta = (i + 0.5) * dtheta;
        const double weight = norm * std::exp(kappa * (std::cos(theta) - 1.0)) * std::sin(theta) * dtheta;
        if (weight == 0.0) continue;
        // Azimuth: the ring of n at angle θ sweeps ω·n over cos(θ ± β); resolve f along it.
        const double ring = std::sin(theta) * sin_beta;
        const int phi_steps = std::clamp(int(std::ceil(2.0 * pi * ring / step)), 16, 4096);
        double ring_sum = 0.0;
        for (int k = 0; k < phi_steps; ++k) {
            const double phi = (k + 0.5) * pi / phi_steps;  // symmetric in φ: integrate over [0, π]
            ring_sum += f(std::cos(theta) * cos_beta + ring * std::cos(phi));
        }
        sum += weight * ring_sum / phi_steps;
        mass += weight;
    }
    return mass > 0.0 ? sum / mass : 0.0;
}

ConvolutionTable tabulate_convolution(const BaseBrdf& brdf, double kappa)
{
    const double f_width = brdf.angular_width();
    const auto f = [&](double c) { return double(brdf.eval(float(c))); };
    // β over [0, π] in sin β dβ, with quadratic spacing: dense near β = 0 where the lobes peak.
    const double lobe_width = std::sqrt(f_width * f_width + 2.0 / kappa);
    const double beta_max = std::min(std::numbers::pi, 12.0 * lobe_width + 0.1);
    constexpr int kSteps = 200;
    ConvolutionTable table;
    for (int i = 0; i < kSteps; ++i) {
        const double t0 = double(i) / kSteps, t1 = double(i + 1) / kSteps;
        const double b0 = beta_max * t0 * t0, b1 = beta_max * t1 * t1, beta = 0.5 * (b0 + b1);
        table.cos_beta.push_back(std::cos(beta));
        table.measure.push_back(std::sin(beta) * (b1 - b0));
        table.value.push_back(convolve_with_vmf(f, f_width, kappa, beta));
    }
    return table;
}

double rule_error(const ConvolutionTable& table, const std::function<double(double)>& rule)
{
    double diff2 = 0.0, ref2 = 0.0;
    for (size_t i = 0; i < table.value.size(); ++i) {
        const double d = rule(table.cos_beta[i]) - table.value[i];
        diff2 += d * d * table.measure[i];
        ref2 += table.value[i] * table.value[i] * table.measure[i];
    }
    return ref2 > 0.0 ? std::sqrt(diff2 / ref2) : 0.0;
}

double convolution_rule_error(const BaseBrdf& brdf, double kappa)
{
    const ConvolvedLobe lobe = brdf.convolved(float(kappa));
    return rule_error(tabulate_convolution(brdf, kappa), [&](double c) { return double(lobe.eval(float(c))); });
}

}  // namespace ndfbake
