#include "ndf/texel_fit.h"

#include <algorithm>
#include <array>
#include <limits>
#include <string>

#include "error.h"

namespace ndfbake {

namespace {

// Seeds closer than this (1 − cos, about 0.08°) are the same direction.
constexpr float kDistinctSeedDistance = 1e-6f;

bool has_repeated_direction(std::span<const VmfLobe> lobes)
{
    for (size_t i = 0; i < lobes.size(); ++i)
        for (size_t j = i + 1; j < lobes.size(); ++j)
            if (1.0f - dot(lobes[i].mu, lobes[j].mu) < kDistinctSeedDistance) return true;
    return false;
}

float nearest_seed_distance(const Vec3& n, std::span<const VmfLobe> seeds)
{
    float nearest = std::numeric_limits<float>::infinity();
    for (const VmfLobe& seed : seeds) nearest = std::min(nearest, 1.0f - dot(n, seed.mu));
    return nearest;
}

void prune_dead_lobes(std::vector<VmfLobe>& lobes)
{
    std::erase_if(lobes, [](const VmfLobe& l) { return !(l.alpha > 0.0f); });
    float total = 0.0f;
    for (const VmfLobe& l : lobes) total += l.alpha;
    if (total > 0.0f)
        for (VmfLobe& l : lobes) l.alpha /= total;
}

// EM from the children's seeds (merged, or the farthest of them: §7.1), and with
// settings.two_starts also from the fine normals farthest apart, keeping the likelier. Against
// the farthest children a second start helped (fbm at level 6: 0.154 against 0.092 relative
// error for 4 lobes: it escapes the children's outlier lobes); against merged children it does
// not (see TexelFitSettings::two_starts).
std::vector<VmfLobe> fit_from_seeds(std::span<const WeightedNormal> samples, std::span<const VmfLobe> child_lobes,
                                    int count, const TexelFitSettings& settings)
{
    const bool few_samples = samples.size() <= size_t(kSecondStartMinSamples);
    EmSettings em = settings.em;
    if (few_samples && settings.few_sample_shortcut)
        em.max_iterations = std::min(em.max_iterations, kFewSampleIterations);
    std::vector<VmfLobe> from_children;
    if (settings.merge_children) {
        from_children = merge_nearest_lobes(child_lobes, count);
        for (VmfLobe& seed : from_children) seed.kappa = std::min(seed.kappa, kMaxSeedKappa);
    }
    // Fewer merged lobes than `count`, or two in one direction (the children hold fewer
    // directions; EM cannot part identical seeds): the distinct ones, and the farthest samples.
    if (int(from_children.size()) < count || has_repeated_direction(from_children))
        from_children = farthest_point_seeds(from_children.empty() ? child_lobes : from_children, samples, count);
    const double children_fit = fit_vmf_mixture(samples, from_children, em).mean_log_likelihood;
    if (!settings.two_starts || few_samples) {
        prune_dead_lobes(from_children);
        return from_children;
    }
    std::vector<VmfLobe> from_samples = farthest_point_seeds({}, samples, count);
    const double samples_fit = fit_vmf_mixture(samples, from_samples, em).mean_log_likelihood;
    std::vector<VmfLobe>& best = children_fit >= samples_fit ? from_children : from_samples;
    prune_dead_lobes(best);
    return std::move(best);
}

// No more samples than lobes: each distinct sample is a lobe, the maximum-likelihood fit that EM
// would converge to, without running it.
std::vector<VmfLobe> lobes_of_samples(std::span<const WeightedNormal> samples)
{
    std::vector<VmfLobe> lobes;
    lobes.reserve(samples.size());
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
    return lobes;
}

// The lobe budget from the top down: merge the nearest two lobes (merge_nearest_lobes) for as long
// as the error stays within the tolerance. One EM fit of the most lobes plus cheap merges costs
// less than fitting every lobe count from one upwards.
void merge_within_tolerance(TexelFit& fit, float tolerance, const TexelErrorMeter& meter)
{
    while (fit.lobes.size() > 1) {
        std::vector<VmfLobe> merged = merge_nearest_lobes(fit.lobes, int(fit.lobes.size()) - 1);
        const float error = meter.error(merged);
        if (error > tolerance) return;
        fit.lobes = std::move(merged);
        fit.error = error;
    }
}

}  // namespace

std::vector<VmfLobe> merge_nearest_lobes(std::span<const VmfLobe> lobes, int count)
{
    // A lobe and its α-weighted mean resultant; a lobe never merged is returned as it came.
    struct Cluster {
        VmfLobe lobe;
        Vec3 resultant;
        float length;
    };
    // On the stack: the hierarchical fit merges the children of every binned texel.
    constexpr int kMaxMerged = 4 * kMaxLobes;
    std::array<Cluster, kMaxMerged> clusters;
    int n = 0;
    for (const VmfLobe& lobe : lobes) {
        if (!(lobe.alpha > 0.0f)) continue;
        if (n == kMaxMerged)
            throw Error(Status::invalid_argument, "merging takes at most " + std::to_string(kMaxMerged) + " lobes");
        const Vec3 m = lobe.alpha * float(mean_resultant_length(lobe.kappa)) * lobe.mu;
        clusters[size_t(n++)] = {lobe, m, length(m)};
    }
    // loss[i][j], i < j: the resultant length that merging i and j loses (the scatter it adds).
    std::array<std::array<float, kMaxMerged>, kMaxMerged> loss;
    const auto set_loss = [&](int i, int j) {
        const Cluster &a = clusters[size_t(std::min(i, j))], &b = clusters[size_t(std::max(i, j))];
        loss[size_t(std::min(i, j))][size_t(std::max(i, j))] = a.length + b.length - length(a.resultant + b.resultant);
    };
    for (int i = 0; i < n; ++i)
        for (int j = i + 1; j < n; ++j) set_loss(i, j);
    for (; n > std::max(count, 1); --n) {
        int a = 0, b = 1;
        for (int i = 0; i < n; ++i)
            for (int j = i + 1; j < n; ++j)
                if (loss[size_t(i)][size_t(j)] < loss[size_t(a)][size_t(b)]) a = i, b = j;
        Cluster& into = clusters[size_t(a)];
        const Cluster& from = clusters[size_t(b)];
        const float alpha = into.lobe.alpha + from.lobe.alpha;
        const Vec3 heavier = into.lobe.alpha >= from.lobe.alpha ? into.lobe.mu : from.lobe.mu;
        into.resultant += from.resultant;
        into.length = length(into.resultant);
        // Antipodal lobes cancel (|m| = 0): the merged lobe keeps the heavier's direction, κ = kKappaMin.
        into.lobe = {alpha, normalize_or(into.resultant, heavier), kappa_from_resultant(into.length / alpha)};
        // The last cluster takes b's place; the losses of a and of the moved cluster are new.
        const int last = n - 1;
        clusters[size_t(b)] = clusters[size_t(last)];
        for (int k = 0; k < last; ++k) {
            if (k != a) set_loss(a, k);
            if (b < last && k != b) set_loss(b, k);
        }
    }
    float total = 0.0f;
    for (int i = 0; i < n; ++i) total += clusters[size_t(i)].lobe.alpha;
    std::vector<VmfLobe> merged;
    for (int i = 0; i < n; ++i) {
        merged.push_back(clusters[size_t(i)].lobe);
        merged.back().alpha /= total;
    }
    return merged;
}

std::vector<VmfLobe> farthest_point_seeds(std::span<const VmfLobe> candidates,
                                          std::span<const WeightedNormal> samples, int count)
{
    std::vector<VmfLobe> seeds;
    auto add_seed = [&](const Vec3& mu, float kappa) {
        seeds.push_back({0.0f, mu, std::clamp(kappa, kKappaMin, kMaxSeedKappa)});
    };

    const VmfLobe* heaviest = nullptr;
    for (const VmfLobe& c : candidates)
        if (c.alpha > 0.0f && (!heaviest || c.alpha > heaviest->alpha)) heaviest = &c;
    if (heaviest) add_seed(heaviest->mu, heaviest->kappa);
    else if (!samples.empty()) add_seed(normalize_or(samples.front().n, {0, 0, 1}), kMaxSeedKappa);
    else return seeds;

    while (int(seeds.size()) < count) {
        const VmfLobe* best = nullptr;
        float best_distance = kDistinctSeedDistance;
        for (const VmfLobe& c : candidates) {
            if (!(c.alpha > 0.0f)) continue;
            const float d = nearest_seed_distance(c.mu, seeds);
            if (d > best_distance) { best_distance = d; best = &c; }
        }
        if (best) { add_seed(best->mu, best->kappa); continue; }

        const WeightedNormal* far_sample = nullptr;
        best_distance = kDistinctSeedDistance;
        for (const WeightedNormal& s : samples) {
            const float d = nearest_seed_distance(s.n, seeds);
            if (d > best_distance) { best_distance = d; far_sample = &s; }
        }
        if (!far_sample) break;
        add_seed(normalize_or(far_sample->n, {0, 0, 1}), seeds.front().kappa);
    }
    for (VmfLobe& seed : seeds) seed.alpha = 1.0f / float(seeds.size());
    return seeds;
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

    // The most lobes the samples support: each distinct sample when there are few, else EM.
    std::vector<VmfLobe> full = int(samples.size()) <= max_lobes
                                    ? lobes_of_samples(samples)
                                    : fit_from_seeds(samples, child_lobes, max_lobes, settings);
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
