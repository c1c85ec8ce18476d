#include "ndf/texel_fit.h"

#include <algorithm>
#include <limits>

#include "ndf/spherical_kmeans.h"

namespace ndfbake {

namespace {

// Seeds closer than this (1 − cos, about 0.08°) are the same direction.
constexpr float kDistinctSeedDistance = 1e-6f;

float nearest_seed_distance(const Vec3& n, std::span<const VmfLobe> seeds)
{
    float nearest = std::numeric_limits<float>::infinity();
    for (const VmfLobe& seed : seeds) nearest = std::min(nearest, 1.0f - dot(n, seed.mu));
    return nearest;
}

// EM from the children's seeds, and with settings.two_starts also from the samples, keeping the
// likelier: the finer level's lobes (§7.1), and the fine normals
// farthest apart. Measured on the synthetic patterns, neither start wins everywhere: the
// children's lobes are steadier across neighbours, the fine normals escape the children's
// outlier lobes (fbm at level 6: 0.154 against 0.092 relative error for 4 lobes).
std::vector<VmfLobe> fit_from_seeds(std::span<const WeightedNormal> samples, std::span<const VmfLobe> child_lobes,
                                    int count, const TexelFitSettings& settings)
{
    const EmSettings& em = settings.em;
    std::vector<VmfLobe> from_children = farthest_point_seeds(child_lobes, samples, count);
    if (settings.solver == TexelSolver::spherical_kmeans) {
        spherical_kmeans(samples, from_children, em.max_iterations);
        drop_light_lobes(from_children, 0.0f);
        return from_children;
    }
    const bool few_samples = samples.size() <= size_t(kSecondStartMinSamples);
    const double children_fit = fit_vmf_mixture(samples, from_children, em).mean_log_likelihood;
    if (!settings.two_starts || few_samples) {
        drop_light_lobes(from_children, 0.0f);
        return from_children;
    }
    std::vector<VmfLobe> from_samples = farthest_point_seeds({}, samples, count);
    const double samples_fit = fit_vmf_mixture(samples, from_samples, em).mean_log_likelihood;
    std::vector<VmfLobe>& best = children_fit >= samples_fit ? from_children : from_samples;
    drop_light_lobes(best, 0.0f);
    return std::move(best);
}

// No more samples than lobes: each distinct sample is a lobe, the maximum-likelihood fit that EM
// would converge to, without running it.
void lobes_of_samples(std::span<const WeightedNormal> samples, std::vector<VmfLobe>& lobes)
{
    lobes.clear();
    double total = 0.0;
    for (const WeightedNormal& s : samples) total += s.weight;
    for (const WeightedNormal& s : samples) {
        const Vec3 mu = normalize_or(s.n, {0, 0, 1});
        const float kappa = kappa_from_resultant(length(s.n));
        const float alpha = float(s.weight / total);
        auto same = std::find_if(lobes.begin(), lobes.end(), [&](const VmfLobe& l) {
            return 1.0f - dot(l.mu, mu) < kDistinctSeedDistance && l.kappa == kappa;
        });
        if (same != lobes.end()) same->alpha += alpha;
        else lobes.push_back({alpha, mu, kappa});
    }
}

// Two lobes as one: weights add, and so do their α-weighted mean resultant vectors (the merged
// lobe is the single vMF of the union of their normals).
VmfLobe merge_lobes(const VmfLobe& a, const VmfLobe& b)
{
    const float alpha = a.alpha + b.alpha;
    const Vec3 r = (a.alpha * float(lobe_resultant(a.kappa)) * a.mu + b.alpha * float(lobe_resultant(b.kappa)) * b.mu) /
                   alpha;
    return {alpha, normalize_or(r, a.mu), kappa_from_resultant(length(r))};
}

// The lobe budget from the top down: merge the two closest lobes (the α-weighted nearest pair)
// for as long as the error stays within the tolerance. One EM fit of the most lobes plus cheap
// merges costs less than fitting every lobe count from one upwards.
void merge_within_tolerance(TexelFit& fit, float tolerance, const TexelErrorMeter& meter)
{
    while (fit.lobes.size() > 1) {
        size_t best_i = 0, best_j = 1;
        float best_cost = std::numeric_limits<float>::infinity();
        for (size_t i = 0; i < fit.lobes.size(); ++i)
            for (size_t j = i + 1; j < fit.lobes.size(); ++j) {
                const VmfLobe& a = fit.lobes[i];
                const VmfLobe& b = fit.lobes[j];
                const float cost = a.alpha * b.alpha / (a.alpha + b.alpha) * (1.0f - dot(a.mu, b.mu));
                if (cost < best_cost) { best_cost = cost; best_i = i; best_j = j; }
            }
        std::vector<VmfLobe> merged = fit.lobes;
        merged[best_i] = merge_lobes(fit.lobes[best_i], fit.lobes[best_j]);
        merged.erase(merged.begin() + std::ptrdiff_t(best_j));
        const float error = meter.error(merged);
        if (error > tolerance) return;
        fit.lobes = std::move(merged);
        fit.error = error;
    }
}

}  // namespace

std::vector<VmfLobe> farthest_point_seeds(std::span<const VmfLobe> candidates,
                                          std::span<const WeightedNormal> samples, int count)
{
    std::vector<VmfLobe> seeds;
    seeds.reserve(size_t(std::clamp(count, 1, kMaxLobes)));
    // Each candidate's and sample's distance to its nearest seed, updated as seeds are added (a
    // texel's seeding visits them once per seed, not once per seed pair). The samples' are kept
    // only once the candidates run out.
    thread_local std::vector<float> candidate_distance, sample_distance;
    candidate_distance.assign(candidates.size(), std::numeric_limits<float>::infinity());
    sample_distance.clear();
    auto add_seed = [&](const Vec3& mu, float kappa) {
        seeds.push_back({0.0f, mu, std::clamp(kappa, kKappaMin, kMaxSeedKappa)});
        for (size_t c = 0; c < candidates.size(); ++c)
            candidate_distance[c] = std::min(candidate_distance[c], 1.0f - dot(candidates[c].mu, mu));
        for (size_t i = 0; i < sample_distance.size(); ++i)
            sample_distance[i] = std::min(sample_distance[i], 1.0f - dot(samples[i].n, mu));
    };

    const VmfLobe* heaviest = nullptr;
    for (const VmfLobe& c : candidates)
        if (c.alpha > 0.0f && (!heaviest || c.alpha > heaviest->alpha)) heaviest = &c;
    if (heaviest) add_seed(heaviest->mu, heaviest->kappa);
    else if (!samples.empty()) add_seed(normalize_or(samples.front().n, {0, 0, 1}), kMaxSeedKappa);
    else return seeds;

    while (int(seeds.size()) < count) {
        size_t best = candidates.size();
        float best_distance = kDistinctSeedDistance;
        for (size_t c = 0; c < candidates.size(); ++c) {
            if (!(candidates[c].alpha > 0.0f)) continue;
            if (candidate_distance[c] > best_distance) { best_distance = candidate_distance[c]; best = c; }
        }
        if (best < candidates.size()) { add_seed(candidates[best].mu, candidates[best].kappa); continue; }

        if (sample_distance.empty()) {
            sample_distance.resize(samples.size());
            for (size_t i = 0; i < samples.size(); ++i) sample_distance[i] = nearest_seed_distance(samples[i].n, seeds);
        }
        size_t far_sample = samples.size();
        best_distance = kDistinctSeedDistance;
        for (size_t i = 0; i < samples.size(); ++i)
            if (sample_distance[i] > best_distance) { best_distance = sample_distance[i]; far_sample = i; }
        if (far_sample == samples.size()) break;
        add_seed(normalize_or(samples[far_sample].n, {0, 0, 1}), seeds.front().kappa);
    }
    for (VmfLobe& seed : seeds) seed.alpha = 1.0f / float(seeds.size());
    return seeds;
}

void exact_texel_lobes(std::span<const WeightedNormal> samples, std::vector<VmfLobe>& lobes)
{
    lobes_of_samples(samples, lobes);
    if (lobes.size() <= 1) lobes.assign(1, single_vmf_lobe(samples));
}

TexelFit fit_texel(std::span<const WeightedNormal> samples, std::span<const VmfLobe> child_lobes,
                   const TexelFitSettings& settings, const TexelErrorMeter* meter)
{
    const int max_lobes = std::clamp(settings.max_lobes, 1, kMaxLobes);
    const bool budgeted = meter && settings.tolerance > 0.0f;

    TexelFit best;
    // Without a budget the single lobe is only the fallback where the samples hold one direction:
    // computed when needed (level 1 has a million texels of four normals at 2048²).
    if (max_lobes == 1 || budgeted) {
        best.lobes = {single_vmf_lobe(samples)};
        if (budgeted) best.error = meter->error(best.lobes);
        if (max_lobes == 1 || (budgeted && best.error <= settings.tolerance)) return best;
    }

    if (!budgeted && max_lobes > 1 && int(samples.size()) <= max_lobes) {
        exact_texel_lobes(samples, best.lobes);
        if (meter) best.error = meter->error(best.lobes);
        return best;
    }
    // The most lobes the samples support: each distinct sample when there are few, else EM.
    std::vector<VmfLobe> full;
    if (int(samples.size()) <= max_lobes) lobes_of_samples(samples, full);
    else full = fit_from_seeds(samples, child_lobes, max_lobes, settings);
    if (full.size() > 1) {
        const float error = meter ? meter->error(full) : -1.0f;
        if (!budgeted || error < best.error) {
            best.lobes = std::move(full);
            best.error = error;
        }
    }
    if (best.lobes.empty()) best.lobes = {single_vmf_lobe(samples)};
    if (budgeted && best.lobes.size() > 2) merge_within_tolerance(best, settings.tolerance, *meter);
    if (meter && best.error < 0.0f) best.error = meter->error(best.lobes);
    return best;
}

}  // namespace ndfbake
