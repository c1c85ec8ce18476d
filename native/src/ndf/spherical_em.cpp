#include "ndf/spherical_em.h"

#include "math/fast_exp.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace ndfbake {

namespace {

// A lobe whose total responsibility is under half a sample explains nothing (it is "dead").
constexpr double kDeadLobeSampleWeight = 0.5;

struct LobeTerms {
    float log_alpha;           // −∞ for a dead lobe
    float log_norm_shifted;
};

std::vector<LobeTerms> lobe_terms(std::span<const VmfLobe> lobes)
{
    std::vector<LobeTerms> terms(lobes.size());
    for (size_t j = 0; j < lobes.size(); ++j) {
        terms[j].log_alpha = lobes[j].alpha > 0.0f ? std::log(lobes[j].alpha)
                                                   : -std::numeric_limits<float>::infinity();
        terms[j].log_norm_shifted = float(log_vmf_normalizer_shifted(lobes[j].kappa));
    }
    return terms;
}

// Returns log Σ_j α_j γ_j(n) and fills z[j] ∝ (α_j γ_j(n))^sharpness, normalized: the E-step's
// responsibilities, from one exponential per lobe (shifted by the largest term: log-sum-exp).
float responsibilities(std::span<const VmfLobe> lobes, std::span<const LobeTerms> terms, const Vec3& n, float* z,
                       float sharpness = 1.0f)
{
    float max_log = -std::numeric_limits<float>::infinity();
    for (size_t j = 0; j < lobes.size(); ++j) {
        z[j] = terms[j].log_alpha + log_vmf_density(lobes[j], n, terms[j].log_norm_shifted);
        max_log = std::max(max_log, z[j]);
    }
    if (!std::isfinite(max_log)) {  // every lobe is dead: nobody is responsible
        std::fill(z, z + lobes.size(), 0.0f);
        return max_log;
    }
    float sum = 0.0f, sharp_sum = 0.0f;
    for (size_t j = 0; j < lobes.size(); ++j) {
        const float shifted = z[j] - max_log;
        sum += std::exp(shifted);
        z[j] = sharpness == 1.0f ? std::exp(shifted) : std::exp(sharpness * shifted);
        sharp_sum += z[j];
    }
    const float inv_sum = 1.0f / sharp_sum;
    for (size_t j = 0; j < lobes.size(); ++j) z[j] *= inv_sum;
    return max_log + std::log(sum);
}

// Samples in structure-of-arrays form, so that the E-step runs over many samples per lobe at once.
struct SampleBlocks {
    std::vector<float> x, y, z, w;
    explicit SampleBlocks(std::span<const WeightedNormal> samples)
    {
        // Exact sizes: a top-level footprint is the whole map, and growth by doubling would hold
        // up to twice its memory (bake/memory_budget.cpp counts 16 bytes per sample).
        x.reserve(samples.size());
        y.reserve(samples.size());
        z.reserve(samples.size());
        w.reserve(samples.size());
        for (const WeightedNormal& s : samples) {
            x.push_back(s.n.x);
            y.push_back(s.n.y);
            z.push_back(s.n.z);
            w.push_back(s.weight);
        }
    }
    size_t size() const { return x.size(); }
};

// Samples per E-step block: a lobe's terms for a block fit in L1 alongside the samples.
constexpr size_t kEStepBlock = 64;

// One E-step over all samples: accumulates Σ w z_ij and Σ w z_ij n_i per lobe, the log-likelihood
// and the worst-explained sample. Summaries sharpen their responsibilities by their weight.
void e_step(const SampleBlocks& s, std::span<const VmfLobe> lobes, std::span<const LobeTerms> terms, bool summaries,
            std::vector<double>& lobe_weight, std::vector<Vec3d>& lobe_sum, double& log_likelihood, float& worst_log,
            size_t& worst_sample)
{
    const size_t J = lobes.size();
    alignas(64) float log_p[kMaxLobes][kEStepBlock];
    alignas(64) float e[kMaxLobes][kEStepBlock];
    alignas(64) float peak[kEStepBlock], sum[kEStepBlock], inv[kEStepBlock];
    for (size_t begin = 0; begin < s.size(); begin += kEStepBlock) {
        const size_t n = std::min(kEStepBlock, s.size() - begin);
        const float *x = &s.x[begin], *y = &s.y[begin], *z = &s.z[begin], *w = &s.w[begin];
        for (size_t i = 0; i < n; ++i) peak[i] = -std::numeric_limits<float>::infinity();
        for (size_t j = 0; j < J; ++j) {
            const float k = lobes[j].kappa, mx = lobes[j].mu.x, my = lobes[j].mu.y, mz = lobes[j].mu.z;
            const float base = terms[j].log_alpha + terms[j].log_norm_shifted - k;
#pragma omp simd
            for (size_t i = 0; i < n; ++i) {
                log_p[j][i] = base + k * (mx * x[i] + my * y[i] + mz * z[i]);
                peak[i] = std::max(peak[i], log_p[j][i]);
            }
        }
        for (size_t i = 0; i < n; ++i) sum[i] = 0.0f;
        for (size_t j = 0; j < J; ++j) {
#pragma omp simd
            for (size_t i = 0; i < n; ++i) {
                e[j][i] = fast_exp_nonpositive(log_p[j][i] - peak[i]);
                sum[i] += e[j][i];
            }
        }
        for (size_t i = 0; i < n; ++i) {
            if (!std::isfinite(peak[i])) {  // every lobe dead: the sample joins no lobe
                inv[i] = 0.0f;
                continue;
            }
            const float lse = peak[i] + std::log(sum[i]);
            log_likelihood += double(w[i]) * lse;
            if (lse < worst_log) {
                worst_log = lse;
                worst_sample = begin + i;
            }
            inv[i] = w[i] / sum[i];
        }
        if (summaries) {
            // (α_j γ_j)^w normalized: recompute the terms sharpened, per sample.
            for (size_t i = 0; i < n; ++i) {
                if (inv[i] == 0.0f) continue;
                float sharp_sum = 0.0f;
                for (size_t j = 0; j < J; ++j) sharp_sum += (e[j][i] = fast_exp_nonpositive(w[i] * (log_p[j][i] - peak[i])));
                inv[i] = w[i] / sharp_sum;
            }
        }
        for (size_t j = 0; j < J; ++j) {
            float weight = 0.0f, sx = 0.0f, sy = 0.0f, sz = 0.0f;
#pragma omp simd reduction(+ : weight, sx, sy, sz)
            for (size_t i = 0; i < n; ++i) {
                const float r = e[j][i] * inv[i];
                weight += r;
                sx += r * x[i];
                sy += r * y[i];
                sz += r * z[i];
            }
            lobe_weight[j] += weight;
            lobe_sum[j].x += sx;
            lobe_sum[j].y += sy;
            lobe_sum[j].z += sz;
        }
    }
}

}  // namespace

VmfLobe single_vmf_lobe(std::span<const WeightedNormal> samples)
{
    const MeanNormal mean = mean_normal(samples);
    return {1.0f, mean.direction, kappa_from_resultant(mean.length)};
}

EmResult fit_vmf_mixture(std::span<const WeightedNormal> samples, std::vector<VmfLobe>& lobes,
                         const EmSettings& settings, std::span<const Vec3> alignment_pull)
{
    const size_t J = lobes.size();
    EmResult result;
    if (J == 0 || samples.empty()) return result;

    double total_weight = 0.0;
    for (const WeightedNormal& s : samples) total_weight += s.weight;
    const double min_weight = samples.size() > 0 ? total_weight / double(samples.size()) : 1.0;

    const SampleBlocks soa(samples);
    std::vector<double> lobe_weight(J);
    std::vector<Vec3d> lobe_sum(J);
    std::vector<bool> reseeded(J, false);
    double previous = -std::numeric_limits<double>::infinity();

    for (int iteration = 0; iteration < settings.max_iterations; ++iteration) {
        const std::vector<LobeTerms> terms = lobe_terms(lobes);
        std::fill(lobe_weight.begin(), lobe_weight.end(), 0.0);
        std::fill(lobe_sum.begin(), lobe_sum.end(), Vec3d{});
        double log_likelihood = 0.0;
        float worst_log = std::numeric_limits<float>::infinity();
        size_t worst_sample = 0;

        // E-step (Algorithm 1 line 5, with α_j), accumulating the M-step's sums on the fly.
        e_step(soa, lobes, terms, settings.summaries, lobe_weight, lobe_sum, log_likelihood, worst_log, worst_sample);
        result.iterations = iteration + 1;
        result.mean_log_likelihood = log_likelihood / total_weight;

        // M-step (lines 9–14).
        for (size_t j = 0; j < J; ++j) {
            VmfLobe& lobe = lobes[j];
            if (lobe_weight[j] < kDeadLobeSampleWeight * min_weight) {
                if (!reseeded[j] && lobe.alpha > 0.0f) {
                    reseeded[j] = true;
                    lobe.mu = normalize_or(samples[worst_sample].n, lobe.mu);
                    lobe.alpha = float(min_weight / total_weight);
                    previous = -std::numeric_limits<double>::infinity();  // the model changed
                } else {
                    lobe.alpha = 0.0f;
                }
                continue;
            }
            lobe.alpha = float(lobe_weight[j] / total_weight);
            const Vec3 r = (lobe_sum[j].to_float()) / float(lobe_weight[j]);
            lobe.kappa = kappa_from_resultant(length(r));
            const Vec3 pull = j < alignment_pull.size() ? alignment_pull[j] : Vec3{};
            lobe.mu = normalize_or(r + pull, lobe.mu);  // eq. 23; R → 0 keeps the old direction
        }

        // A re-seeded lobe took weight out of thin air: keep Σα = 1.
        float alpha_sum = 0.0f;
        for (const VmfLobe& lobe : lobes) alpha_sum += lobe.alpha;
        if (alpha_sum > 0.0f)
            for (VmfLobe& lobe : lobes) lobe.alpha /= alpha_sum;

        const double change = result.mean_log_likelihood - previous;
        previous = result.mean_log_likelihood;
        if (std::abs(change) < settings.convergence * (1.0 + std::abs(previous))) break;
    }
    return result;
}

void vmf_responsibilities(std::span<const WeightedNormal> samples, std::span<const VmfLobe> lobes,
                          std::vector<float>& out)
{
    const size_t J = lobes.size();
    out.assign(samples.size() * J, 0.0f);
    const std::vector<LobeTerms> terms = lobe_terms(lobes);
    for (size_t i = 0; i < samples.size(); ++i) responsibilities(lobes, terms, samples[i].n, &out[i * J]);
}

}  // namespace ndfbake
