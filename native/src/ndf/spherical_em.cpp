#include "ndf/spherical_em.h"

#include "error.h"
#include "math/fast_exp.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <memory>

namespace ndfbake {

namespace {

// A lobe whose total responsibility is under half a sample explains nothing (it is "dead").
constexpr double kDeadLobeSampleWeight = 0.5;

// log_weighted_normalizer per lobe, on the stack: EM recomputes them every iteration, for texels
// of a dozen samples too.
using LobeTermArray = std::array<float, kMaxLobes>;

void lobe_terms(std::span<const VmfLobe> lobes, LobeTermArray& terms)
{
    for (size_t j = 0; j < lobes.size(); ++j) terms[j] = log_weighted_normalizer(lobes[j]);
}

// Returns log Σ_j α_j γ_j(n) and fills z[j] ∝ α_j γ_j(n), normalized: the E-step's
// responsibilities, from one exponential per lobe (shifted by the largest term: log-sum-exp).
float responsibilities(std::span<const VmfLobe> lobes, const LobeTermArray& terms, const Vec3& n, float* z)
{
    float max_log = -std::numeric_limits<float>::infinity();
    for (size_t j = 0; j < lobes.size(); ++j) {
        z[j] = log_vmf_density(lobes[j], n, terms[j]);
        max_log = std::max(max_log, z[j]);
    }
    if (!std::isfinite(max_log)) {  // every lobe is dead: nobody is responsible
        std::fill(z, z + lobes.size(), 0.0f);
        return max_log;
    }
    float sum = 0.0f;
    for (size_t j = 0; j < lobes.size(); ++j) {
        z[j] = std::exp(z[j] - max_log);
        sum += z[j];
    }
    const float inv_sum = 1.0f / sum;
    for (size_t j = 0; j < lobes.size(); ++j) z[j] *= inv_sum;
    return max_log + std::log(sum);
}

// Samples in structure-of-arrays form, so that the E-step runs over many samples per lobe at once.
struct SampleBlocks {
    // One allocation of exactly four arrays: a top-level footprint is the whole map, and growth by
    // doubling would hold up to twice its memory (bake/memory_budget.cpp counts 16 bytes a sample).
    std::unique_ptr<float[]> storage;
    const float *x, *y, *z, *w;
    size_t count;
    explicit SampleBlocks(std::span<const WeightedNormal> samples)
        : storage(new float[4 * samples.size()]), count(samples.size())
    {
        float* out = storage.get();
        for (size_t i = 0; i < count; ++i) {
            out[i] = samples[i].n.x;
            out[count + i] = samples[i].n.y;
            out[2 * count + i] = samples[i].n.z;
            out[3 * count + i] = samples[i].weight;
        }
        x = out, y = out + count, z = out + 2 * count, w = out + 3 * count;
    }
    size_t size() const { return count; }
};

// Samples per E-step block: a lobe's terms for a block fit in L1 alongside the samples.
constexpr size_t kEStepBlock = 64;

// One E-step over all samples: accumulates Σ w z_ij and Σ w z_ij n_i per lobe, the log-likelihood
// and the worst-explained sample.
void e_step(const SampleBlocks& s, std::span<const VmfLobe> lobes, const LobeTermArray& terms,
            std::array<double, kMaxLobes>& lobe_weight, std::array<Vec3d, kMaxLobes>& lobe_sum, double& log_likelihood, float& worst_log,
            size_t& worst_sample)
{
    const size_t J = lobes.size();
    alignas(64) float log_p[kMaxLobes][kEStepBlock];
    alignas(64) float e[kMaxLobes][kEStepBlock];
    alignas(64) float peak[kEStepBlock], sum[kEStepBlock], inv[kEStepBlock], lse[kEStepBlock];
    for (size_t begin = 0; begin < s.size(); begin += kEStepBlock) {
        const size_t n = std::min(kEStepBlock, s.size() - begin);
        const float *x = &s.x[begin], *y = &s.y[begin], *z = &s.z[begin], *w = &s.w[begin];
        for (size_t i = 0; i < n; ++i) peak[i] = -std::numeric_limits<float>::infinity();
        for (size_t j = 0; j < J; ++j) {
            const float k = lobes[j].kappa, mx = lobes[j].mu.x, my = lobes[j].mu.y, mz = lobes[j].mu.z;
            const float base = terms[j] - k;
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
        // A sample that every lobe is dead for (peak −∞) joins no lobe and adds no likelihood.
        // The block's likelihood is summed in float (64 terms) and handed to the double total.
#pragma omp simd
        for (size_t i = 0; i < n; ++i) {
            lse[i] = peak[i] + fast_log_positive(sum[i]);  // sum ≥ 1: its largest term is 1
            inv[i] = w[i] / sum[i];
        }
        float block_likelihood = 0.0f, block_worst = std::numeric_limits<float>::infinity();
#pragma omp simd reduction(+ : block_likelihood)
        for (size_t i = 0; i < n; ++i) {
            const bool live = peak[i] > -std::numeric_limits<float>::infinity();
            inv[i] = live ? inv[i] : 0.0f;
            lse[i] = live ? lse[i] : std::numeric_limits<float>::infinity();
            block_likelihood += live ? w[i] * lse[i] : 0.0f;
        }
        // A loop of its own, without the simd pragma: clang vectorizes a float min only where it
        // may assume no NaN (-ffinite-math-only), so in the loop above it left the whole loop
        // scalar and warned (-Wpass-failed). Its 64 comparisons cost nothing beside the exponentials.
        for (size_t i = 0; i < n; ++i) block_worst = std::min(block_worst, lse[i]);
        log_likelihood += double(block_likelihood);
        if (block_worst < worst_log) {  // rare after the first blocks: find which sample it was
            worst_log = block_worst;
            worst_sample = begin + size_t(std::find(lse, lse + n, block_worst) - lse);
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
    if (J > size_t(kMaxLobes))
        throw Error(Status::invalid_argument, "EM fits at most " + std::to_string(kMaxLobes) + " lobes at once");

    // A lobe dies under half the lightest sample: a bin of many normals must not make a lobe of a
    // few count as nothing.
    double total_weight = 0.0, min_weight = std::numeric_limits<double>::infinity();
    for (const WeightedNormal& s : samples) {
        total_weight += s.weight;
        min_weight = std::min(min_weight, double(s.weight));
    }

    const SampleBlocks soa(samples);
    LobeTermArray terms;
    std::array<double, kMaxLobes> lobe_weight;
    std::array<Vec3d, kMaxLobes> lobe_sum;
    std::array<bool, kMaxLobes> reseeded{};
    double previous = -std::numeric_limits<double>::infinity();

    for (int iteration = 0; iteration < settings.max_iterations; ++iteration) {
        lobe_terms(lobes, terms);
        std::fill(lobe_weight.begin(), lobe_weight.end(), 0.0);
        std::fill(lobe_sum.begin(), lobe_sum.end(), Vec3d{});
        double log_likelihood = 0.0;
        float worst_log = std::numeric_limits<float>::infinity();
        size_t worst_sample = 0;

        // E-step (Algorithm 1 line 5, with α_j), accumulating the M-step's sums on the fly.
        e_step(soa, lobes, terms, lobe_weight, lobe_sum, log_likelihood, worst_log, worst_sample);
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
    LobeTermArray terms;
    lobe_terms(lobes, terms);
    for (size_t i = 0; i < samples.size(); ++i) responsibilities(lobes, terms, samples[i].n, &out[i * J]);
}

}  // namespace ndfbake
