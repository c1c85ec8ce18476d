#include "ndf/brdf_refinement.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numbers>

#include "math/sphere.h"
#include "ndf/effective_brdf.h"
#include "ndf/spherical_em.h"

namespace ndfbake {

namespace {

// Parameters per lobe: the logit of α (a softmax keeps Σα = 1 and every α > 0), two steps in the
// tangent plane of μ, and log κ (κ spans seven decades).
constexpr int kLobeParameters = 4;
constexpr int kMaxParameters = kMaxLobes * kLobeParameters;
// The log κ step of the finite difference for ∂G/∂log κ: κ enters every BRDF's rule in closed
// form, but through a different one each (eq. 20, 21, the GGX rule, Lambert's bands).
constexpr float kLogKappaDifference = 0.01f;
// A step changes log κ by at most this (a factor e), so that one bad step cannot throw a lobe from
// sharp to uniform.
constexpr float kMaxLogKappaStep = 1.0f;
// Levenberg-Marquardt damping: the first λ, its bounds, and how it moves on success and failure.
constexpr double kInitialDamping = 1e-2, kMinDamping = 1e-12, kMaxDamping = 1e8;
constexpr double kDampingDown = 0.3, kDampingUp = 10.0;
// A texel whose relative error is under this after the first search is left there. Measured on
// the six synthetic patterns at Blinn-Phong 128: FitAccuracy's figures did not move, and the
// V-groove's refined build (its texels near-exact) went from 16 s to 2 s.
constexpr double kEscapeMinError = 0.02;
// The refined fit must beat the starting one on the check set by this fraction of its squared
// distance: the check set is a sample of the error too, and a tie is noise.
constexpr double kCheckMargin = 1e-3;
// See damped_solve.
constexpr double kMinRelativeDamping = 1e-9;
// A step that lowers the squared distance by less than this fraction ends the search.
constexpr double kRefineConvergence = 1e-3;

// The parameters a step changes, around the current lobes.
struct LobeStep {
    float logit = 0.0f, u = 0.0f, v = 0.0f, log_kappa = 0.0f;
};

std::vector<VmfLobe> stepped(std::span<const VmfLobe> lobes, std::span<const LobeStep> step)
{
    std::vector<VmfLobe> out(lobes.begin(), lobes.end());
    float max_logit = -std::numeric_limits<float>::infinity();
    std::array<float, kMaxLobes> logit{};
    for (size_t j = 0; j < out.size(); ++j) {
        logit[j] = std::log(out[j].alpha) + step[j].logit;
        max_logit = std::max(max_logit, logit[j]);
    }
    float total = 0.0f;
    for (size_t j = 0; j < out.size(); ++j) total += std::exp(logit[j] - max_logit);
    for (size_t j = 0; j < out.size(); ++j) {
        VmfLobe& lobe = out[j];
        lobe.alpha = std::exp(logit[j] - max_logit) / total;
        const OrthonormalFrame f = orthonormal_frame(lobe.mu);
        lobe.mu = normalize_or(lobe.mu + step[j].u * f.t + step[j].v * f.b, lobe.mu);
        const float dk = std::clamp(step[j].log_kappa, -kMaxLogKappaStep, kMaxLogKappaStep);
        lobe.kappa = std::clamp(lobe.kappa * std::exp(dk), kKappaMin, kKappaMax);
    }
    return out;
}

double squared_norm(std::span<const float> a)
{
    double sum = 0.0;
    for (float v : a) sum += double(v) * v;
    return sum;
}

double squared_distance(std::span<const float> a, std::span<const float> b)
{
    double sum = 0.0;
    for (size_t i = 0; i < a.size(); ++i) sum += (double(a[i]) - b[i]) * (double(a[i]) - b[i]);
    return sum;
}

// Solves (A + λ D) x = −g by Cholesky, D = diag A with every entry at least kMinRelativeDamping
// of its largest (a parameter the residual does not depend on, such as the weight of a single
// lobe or κ where GGX's α' is clamped at 1, has a zero column and would otherwise leave the matrix
// singular for every λ); false when the damped matrix is not positive definite.
bool damped_solve(const double* A, const double* g, int n, double lambda, double* x)
{
    double largest = 0.0;
    for (int i = 0; i < n; ++i) largest = std::max(largest, A[i * n + i]);
    std::array<double, kMaxParameters * kMaxParameters> L{};
    for (int i = 0; i < n; ++i)
        for (int j = 0; j <= i; ++j) {
            double sum = A[i * n + j] + (i == j ? lambda * std::max(A[i * n + i], kMinRelativeDamping * largest) : 0.0);
            for (int k = 0; k < j; ++k) sum -= L[size_t(i * n + k)] * L[size_t(j * n + k)];
            if (i == j) {
                if (!(sum > 0.0)) return false;
                L[size_t(i * n + i)] = std::sqrt(sum);
            } else {
                L[size_t(i * n + j)] = sum / L[size_t(j * n + j)];
            }
        }
    for (int i = 0; i < n; ++i) {  // L y = −g
        double sum = -g[i];
        for (int k = 0; k < i; ++k) sum -= L[size_t(i * n + k)] * x[k];
        x[i] = sum / L[size_t(i * n + i)];
    }
    for (int i = n - 1; i >= 0; --i) {  // Lᵀ x = y
        double sum = x[i];
        for (int k = i + 1; k < n; ++k) sum -= L[size_t(k * n + i)] * x[k];
        x[i] = sum / L[size_t(i * n + i)];
    }
    return true;
}

// Σ a_i b_i over independent partial sums: one vector accumulator would wait on its own additions
// (the normal equations are a few hundred of these per step).
float dot_product(std::span<const float> a, std::span<const float> b)
{
    constexpr size_t kPartialSums = 16;
    const size_t n = a.size();
    const float *pa = a.data(), *pb = b.data();
    std::array<float, kPartialSums> partial{};
    size_t i = 0;
    for (; i + kPartialSums <= n; i += kPartialSums)
        for (size_t l = 0; l < kPartialSums; ++l) partial[l] += pa[i + l] * pb[i + l];
    float sum = 0.0f;
    for (; i < n; ++i) sum += pa[i] * pb[i];
    for (float p : partial) sum += p;
    return sum;
}

// One texel's objective: the squared distance between the lobes' convolved mixture and the
// reference effective BRDF over the texel's directions.
struct Objective {
    const BaseBrdf& brdf;
    std::span<const Vec3> directions;
    std::span<const float> reference;
};

struct FitState {
    std::vector<VmfLobe> lobes;
    std::vector<float> fit;  // the mixture's effective BRDF on the objective's directions
    double cost = 0.0;
};

// Σ_j α_j G_j(d·μ_j) (eq. 20–21) on every direction, and its distance to the reference.
FitState evaluate(const Objective& objective, std::vector<VmfLobe> lobes)
{
    FitState state{std::move(lobes), std::vector<float>(objective.directions.size()), 0.0};
    mixture_effective_brdf(state.lobes, objective.brdf, objective.directions, state.fit);
    state.cost = squared_distance(state.fit, objective.reference);
    return state;
}

// Levenberg-Marquardt from `state`, for at most kRefineIterations rounds. The Jacobian of the
// residual r_d = Σ_j α_j G_j(d·μ_j) − reference_d is built a column (one parameter over every
// direction) at a time, so that the normal equations are dot products of columns.
void levenberg_marquardt(const Objective& objective, FitState& state)
{
    const size_t J = state.lobes.size(), D = objective.directions.size();
    const int P = int(J) * kLobeParameters;
    std::vector<float> columns(size_t(P) * D), residual(D), c(D), g(D), slope(D), wider(D), along(D);
    auto column = [&](int i) { return std::span<float>(&columns[size_t(i) * D], D); };
    std::array<double, kMaxParameters * kMaxParameters> A;
    std::array<double, kMaxParameters> gradient, x;
    std::vector<LobeStep> step(J);
    double lambda = kInitialDamping;

    for (int iteration = 0; iteration < kRefineIterations && lambda < kMaxDamping; ++iteration) {
        for (size_t d = 0; d < D; ++d) residual[d] = state.fit[d] - objective.reference[d];
        for (size_t j = 0; j < J; ++j) {
            const VmfLobe& lobe = state.lobes[j];
            dot_each(objective.directions, lobe.mu, c);
            objective.brdf.convolved(lobe.kappa).eval_many(c, g, slope);
            // One-sided difference inward from the κ bounds.
            const float dlog_kappa = lobe.kappa * std::exp(kLogKappaDifference) <= kKappaMax ? kLogKappaDifference
                                                                                            : -kLogKappaDifference;
            objective.brdf.convolved(lobe.kappa * std::exp(dlog_kappa)).eval_many(c, wider, {});
            const OrthonormalFrame frame = orthonormal_frame(lobe.mu);
            const std::span<float> logit = column(int(j) * kLobeParameters), u = column(int(j) * kLobeParameters + 1),
                                   v = column(int(j) * kLobeParameters + 2), log_kappa = column(int(j) * kLobeParameters + 3);
            const float a = lobe.alpha;
            for (size_t d = 0; d < D; ++d) {
                logit[d] = a * (g[d] - state.fit[d]);  // ∂/∂logit_j of a softmax weight
                log_kappa[d] = a * (wider[d] - g[d]) / dlog_kappa;
            }
            dot_each(objective.directions, frame.t, along);
            for (size_t d = 0; d < D; ++d) u[d] = a * slope[d] * along[d];
            dot_each(objective.directions, frame.b, along);
            for (size_t d = 0; d < D; ++d) v[d] = a * slope[d] * along[d];
        }
        for (int i = 0; i < P; ++i) {
            gradient[size_t(i)] = dot_product(column(i), residual);
            for (int k = 0; k <= i; ++k)
                A[size_t(i * P + k)] = A[size_t(k * P + i)] = dot_product(column(i), column(k));
        }

        // The damped step: shrink it (raise λ) until the distance falls.
        bool improved = false;
        while (!improved && lambda < kMaxDamping) {
            if (!damped_solve(A.data(), gradient.data(), P, lambda, x.data())) {
                lambda *= kDampingUp;
                continue;
            }
            for (size_t j = 0; j < J; ++j) {
                const double* p = &x[j * kLobeParameters];
                step[j] = {float(p[0]), float(p[1]), float(p[2]), float(p[3])};
            }
            FitState trial = evaluate(objective, stepped(state.lobes, step));
            if (trial.cost < state.cost) {
                const bool converged = state.cost - trial.cost < kRefineConvergence * state.cost;
                state = std::move(trial);
                if (converged) return;
                lambda = std::max(lambda * kDampingDown, kMinDamping);
                improved = true;
            } else {
                lambda *= kDampingUp;
            }
        }
    }
}

}  // namespace

LobeRefiner::LobeRefiner(const BaseBrdf& brdf) : brdf_(brdf) {}

void LobeRefiner::refine(std::span<const WeightedNormal> normals, std::vector<VmfLobe>& lobes) const
{
    const size_t J = lobes.size();
    if (J == 0 || J > size_t(kMaxLobes) || normals.empty()) return;

    // The caps of directions the texel's effective BRDF lives in, about its mean normal.
    const Vec3 axis = mean_normal(normals).direction;
    float cos_spread = 1.0f;
    for (const WeightedNormal& s : normals) cos_spread = std::min(cos_spread, dot(axis, normalize_or(s.n, axis)));
    for (const VmfLobe& l : lobes) cos_spread = std::min(cos_spread, dot(axis, l.mu));
    const double spread = std::acos(std::clamp(double(cos_spread), -1.0, 1.0));
    const double width = brdf_.angular_width();
    // A broad BRDF (Lambert, rough GGX) still gets at least the error measure's least density.
    const double spacing = std::min(kRefineSpacingWidths * width, std::sqrt(2.0 * std::numbers::pi / kMinErrorDirections));
    const auto direction_count = [&](double radius) { return std::ceil(cap_solid_angle(radius) / (spacing * spacing)); };
    const double objective_radius = spread + kCapMarginWidths * width;
    if (direction_count(objective_radius) > kMaxRefineDirections) return;
    const std::vector<Vec3> cap = fibonacci_cap(axis, objective_radius, int(direction_count(objective_radius)), 0.0);
    const size_t D = cap.size();
    if (D == 0) return;

    std::vector<float> reference(D);
    reference_effective_brdf(normals, brdf_, cap, reference);
    const Objective objective{brdf_, cap, reference};
    FitState best = evaluate(objective, lobes);
    levenberg_marquardt(objective, best);

    // One escape from the local minimum: the lightest lobe moves to where the fit falls
    // furthest below the reference, and the search runs again.
    const double reference_norm2 = squared_norm(reference);
    if (J > 1 && best.cost > kEscapeMinError * kEscapeMinError * reference_norm2) {
        size_t lightest = 0, hungriest = 0;
        for (size_t j = 1; j < J; ++j)
            if (best.lobes[j].alpha < best.lobes[lightest].alpha) lightest = j;
        for (size_t d = 1; d < D; ++d)
            if (reference[d] - best.fit[d] > reference[hungriest] - best.fit[hungriest]) hungriest = d;
        std::vector<VmfLobe> moved = best.lobes;
        moved[lightest].mu = cap[hungriest];
        FitState escape = evaluate(objective, std::move(moved));
        levenberg_marquardt(objective, escape);
        if (escape.cost < best.cost) best = std::move(escape);
    }

    drop_light_lobes(best.lobes, kNegligibleLobeWeight);

    // Kept only if clearly closer on the independent set too, over a cap as wide as the broadest
    // lobe, before or after, reaches.
    float min_kappa = kKappaMax;
    for (const VmfLobe& l : lobes) min_kappa = std::min(min_kappa, l.kappa);
    for (const VmfLobe& l : best.lobes) min_kappa = std::min(min_kappa, l.kappa);
    for (const VmfLobe& l : best.lobes) cos_spread = std::min(cos_spread, dot(axis, l.mu));
    const double check_radius = std::acos(std::clamp(double(cos_spread), -1.0, 1.0)) +
                                kCapMarginWidths * std::sqrt(width * width + 1.0 / min_kappa);
    if (direction_count(check_radius) > kMaxRefineDirections) return;
    const std::vector<Vec3> check = fibonacci_cap(axis, check_radius, int(direction_count(check_radius)), 0.5);
    if (check.empty()) return;
    std::vector<float> check_reference(check.size()), before(check.size()), after(check.size());
    reference_effective_brdf(normals, brdf_, check, check_reference);
    mixture_effective_brdf(lobes, brdf_, check, before);
    mixture_effective_brdf(best.lobes, brdf_, check, after);
    if (squared_distance(after, check_reference) < (1.0 - kCheckMargin) * squared_distance(before, check_reference))
        lobes = std::move(best.lobes);
}

}  // namespace ndfbake
