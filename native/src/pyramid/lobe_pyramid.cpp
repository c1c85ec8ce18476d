#include "pyramid/lobe_pyramid.h"

#include <algorithm>
#include <numeric>
#include <optional>

#include "error.h"
#include "math/sphere.h"
#include "ndf/brdf_refinement.h"
#include "pyramid/alignment.h"
#include "pyramid/normal_bins.h"

namespace ndfbake {

namespace {

VmfLobe level0_lobe(const Vec3& n) { return {1.0f, n, kKappaMax}; }

void store_texel(LobeLevel& level, int slots, int x, int y, std::span<VmfLobe> lobes, float error)
{
    std::sort(lobes.begin(), lobes.end(), [](const VmfLobe& a, const VmfLobe& b) { return a.alpha > b.alpha; });
    const size_t texel = size_t(y) * size_t(level.size.width) + size_t(x);
    VmfLobe* out = &level.lobes[texel * size_t(slots)];
    for (int s = 0; s < slots; ++s) out[s] = s < int(lobes.size()) ? lobes[size_t(s)] : VmfLobe{};
    level.budget_error[texel] = error;
}


}  // namespace

void LobePyramid::texel(int level, int x, int y, std::span<VmfLobe> out) const
{
    const LobeLevel& l = levels[size_t(level)];
    const size_t t = size_t(y) * size_t(l.size.width) + size_t(x);
    if (level == 0) {
        std::fill(out.begin(), out.end(), VmfLobe{});
        out[l.level0_slot[t]] = level0_lobe(source.normals[t]);
        return;
    }
    std::copy_n(&l.lobes[t * size_t(slots)], size_t(slots), out.begin());
}

std::vector<VmfLobe> LobePyramid::texel_lobes(int level, int x, int y) const
{
    std::vector<VmfLobe> lobes(static_cast<size_t>(slots));
    texel(level, x, y, lobes);
    std::erase_if(lobes, [](const VmfLobe& l) { return !(l.alpha > 0.0f); });
    return lobes;
}

int LobePyramid::lobe_count(int level, int x, int y) const { return int(texel_lobes(level, x, y).size()); }

TexelFitSettings level_fit_settings(const PyramidSettings& settings, int level, uint64_t footprint)
{
    TexelFitSettings fit = settings.fit;
    if (settings.method != FitMethod::hierarchical || level < 1) return fit;
    if (binned_level(level)) fit.em.max_iterations = std::min(fit.em.max_iterations, kBinnedIterations);
    if (!settings.refine && footprint <= kOneStartFootprint) {
        fit.two_starts = false;
        const bool kmeans = footprint <= kKmeansFootprint;
        if (kmeans) fit.solver = TexelSolver::spherical_kmeans;
        fit.em.max_iterations = std::min(fit.em.max_iterations, kmeans ? kKmeansSteps : kOneStartIterations);
    }
    return fit;
}

int pyramid_level_count(int width, int height, const PyramidSettings& settings)
{
    const int all = level_count(width, height);
    return settings.max_levels > 0 ? std::min(all, settings.max_levels) : all;
}

std::vector<bool> LobePyramid::slots_used() const
{
    std::vector<bool> used(static_cast<size_t>(slots), false);
    for (const LobeLevel& level : levels) {
        for (uint8_t slot : level.level0_slot) used[slot] = true;
        for (size_t i = 0; i < level.lobes.size(); ++i)
            if (level.lobes[i].alpha > 0.0f) used[i % size_t(slots)] = true;
    }
    return used;
}

LobePyramid build_lobe_pyramid(const NormalMap& map, const PyramidSettings& settings, const ProgressTick& tick)
{
    LobePyramid pyramid;
    pyramid.source = map;
    pyramid.settings = settings;
    pyramid.slots = std::clamp(settings.fit.max_lobes, 1, kMaxLobes);
    const int slots = pyramid.slots;
    const int levels = pyramid_level_count(map.width, map.height, settings);
    pyramid.levels.resize(static_cast<size_t>(levels));
    for (int l = 0; l < levels; ++l) {
        LobeLevel& level = pyramid.levels[size_t(l)];
        level.size = level_size(map.width, map.height, l);
        const size_t texels = size_t(level.size.width) * size_t(level.size.height);
        level.budget_error.assign(texels, -1.0f);
        if (l == 0) level.level0_slot.assign(texels, 0);
        else level.lobes.resize(texels * size_t(slots));
    }

    const bool budgeted = settings.fit.tolerance > 0.0f && slots > 1;
    const std::vector<Vec3> budget_directions = fibonacci_hemisphere(
        std::min(settings.budget_directions, error_direction_count(settings.brdf)));
    const std::optional<LobeRefiner> refiner =
        settings.refine ? std::optional<LobeRefiner>(std::in_place, settings.brdf) : std::nullopt;

    // Fitting takes one share per level ≥ 1, alignment one share in all.
    const double share = 1.0 / double(levels);
    double done = 0.0;
    auto stage_tick = [&](double fraction) { return !tick || tick(done + share * fraction); };

    // The hierarchical fit's statistics: the level below's bins, and this level's being filled.
    const bool hierarchical = settings.method == FitMethod::hierarchical;
    BinnedLevel finer_bins, bins;

    for (int l = 1; l < levels; ++l) {
        LobeLevel& level = pyramid.levels[size_t(l)];
        const LobeLevel& finer = pyramid.levels[size_t(l - 1)];
        const bool binned = hierarchical && binned_level(l);
        bins = binned ? BinnedLevel(level.size) : BinnedLevel();
        const uint64_t footprint = largest_footprint(map.width, map.height, l);
        const TexelFitSettings fit_settings = level_fit_settings(settings, l, footprint);
        // EM seeds from the children's lobes only where a texel has more samples than lobes.
        const bool seeded = footprint > uint64_t(slots);
        // Texels of no more fine normals than slots (level 1 at 4 lobes) hold them exactly: no
        // seeds, no EM, no refinement; without a budget nothing is scored either. (Never a binned
        // level, whose texels cover more normals than kMaxLobes: their bins are kept below.)
        const bool exact = !seeded && !budgeted && !binned;
        parallel_rows(level.size.height, settings.threads, [&](int y) {
            std::vector<WeightedNormal> samples, scored, refined_normals;
            std::vector<VmfLobe> children, child(static_cast<size_t>(slots)), lobes;
            std::optional<BinAccumulator> binner;
            if (binned) binner.emplace();
            for (int x = 0; x < level.size.width; ++x) {
                if (exact) {
                    gather_footprint(map, l, x, y, settings.wrap, samples);
                    exact_texel_lobes(samples, lobes);
                    store_texel(level, slots, x, y, lobes, -1.0f);
                    continue;
                }
                children.clear();
                for (int cy = 2 * y; seeded && cy < std::min(2 * y + 2, finer.size.height); ++cy)
                    for (int cx = 2 * x; cx < std::min(2 * x + 2, finer.size.width); ++cx) {
                        pyramid.texel(l - 1, cx, cy, child);
                        for (const VmfLobe& lobe : child)
                            if (lobe.alpha > 0.0f) children.push_back(lobe);
                    }
                // `scored`: the fine normals the budget and the refinement score lobes on,
                // whichever samples EM fits.
                const bool scoring = budgeted || refiner;
                if (binned) {
                    const bool summed = accumulate_texel_bins(map, finer_bins, l, x, y, settings.wrap, *binner, scored);
                    const std::span<const NormalBin> texel_bins = binner->finish();
                    bins.append_texel(y, texel_bins);
                    bin_samples(texel_bins, settings.refine ? kRefinedBinSamples : kMaxBinSamples, samples);
                    if (scoring && summed) gather_footprint(map, l, x, y, settings.wrap, scored);
                } else {
                    gather_footprint(map, l, x, y, settings.wrap, samples);
                    if (scoring) scored = samples;
                }
                // The refinement sees more of the footprint than the budget (kRefineSampleCap).
                if (refiner) {
                    refined_normals = scored;
                    subsample_footprint(refined_normals, kRefineSampleCap);
                }
                if (budgeted) subsample_footprint(scored, settings.budget_sample_cap);
                std::optional<TexelErrorMeter> meter;
                if (budgeted) meter.emplace(scored, settings.brdf, budget_directions);
                TexelFit fit = fit_texel(samples, children, fit_settings, meter ? &*meter : nullptr);
                // A texel of no more fine normals than lobes already holds them exactly.
                if (refiner && refined_normals.size() > size_t(slots)) {
                    refiner->refine(refined_normals, fit.lobes);
                    if (meter) fit.error = meter->error(fit.lobes);
                }
                store_texel(level, slots, x, y, fit.lobes, fit.error);
            }
        }, stage_tick);
        finer_bins = std::move(bins);
        done += share;
    }

    if (settings.align && slots > 1)
        align_lobe_slots(pyramid, settings, [&](double fraction) { return !tick || tick(done + share * fraction); });
    // The last tick may ask to stop too: a one-texel map has no other (no level above 0).
    if (tick && !tick(1.0)) throw Error(Status::cancelled, "cancelled");
    return pyramid;
}

}  // namespace ndfbake
