#include "bake/level_stats.h"

#include <algorithm>
#include <cmath>

#include "math/sphere.h"
#include "ndf/moments.h"

namespace ndfbake {

namespace {

ErrorSummary summarize(std::vector<float> errors)
{
    ErrorSummary summary;
    if (errors.empty()) return summary;
    double sum = 0.0;
    for (float e : errors) sum += e;
    summary.mean = float(sum / double(errors.size()));
    std::sort(errors.begin(), errors.end());
    summary.p95 = errors[std::min(errors.size() - 1, size_t(std::ceil(0.95 * double(errors.size()))) - 1)];
    return summary;
}

}  // namespace

std::vector<uint64_t> lobe_histogram(const LobePyramid& pyramid, int level)
{
    const LevelSize size = pyramid.size(level);
    std::vector<uint64_t> histogram(size_t(pyramid.slots) + 1, 0);
    for (int y = 0; y < size.height; ++y)
        for (int x = 0; x < size.width; ++x) ++histogram[size_t(pyramid.lobe_count(level, x, y))];
    return histogram;
}

void texel_reference_samples(const NormalMap& map, WrapMode wrap, int level, int x, int y, int sample_cap,
                             std::vector<WeightedNormal>& out)
{
    gather_footprint(map, level, x, y, wrap, out);
    subsample_footprint(out, sample_cap);
}

LevelStats measure_level(const LobePyramid& pyramid, int level, const BaseBrdf& brdf, int max_texels,
                         int sample_cap, bool measure_alignment)
{
    const TexelFitSettings fit = level_fit_settings(
        pyramid.settings, level, largest_footprint(pyramid.source.width, pyramid.source.height, level));
    LevelStats stats;
    stats.level = level;
    stats.size = pyramid.size(level);
    const int64_t texels = int64_t(stats.size.width) * stats.size.height;
    stats.lobe_histogram = lobe_histogram(pyramid, level);

    const std::vector<Vec3> directions = fibonacci_hemisphere(error_direction_count(brdf));
    const int64_t measured = max_texels > 0 ? std::min<int64_t>(max_texels, texels) : texels;
    std::vector<float> fit_errors, independent_errors, naive_errors, single_errors, toksvig_errors;
    std::vector<WeightedNormal> samples, all_samples;
    std::vector<VmfLobe> children, child(static_cast<size_t>(pyramid.slots));
    for (int64_t i = 0; i < measured; ++i) {
        const int64_t t = measured == texels ? i : (i * texels) / measured + (texels / measured) / 2;
        const int x = int(t % stats.size.width), y = int(t / stats.size.width);
        texel_reference_samples(pyramid.source, pyramid.settings.wrap, level, x, y, sample_cap, samples);
        const TexelErrorMeter meter(samples, brdf, directions);
        fit_errors.push_back(meter.error(pyramid.texel_lobes(level, x, y)));
        const VmfLobe single = single_vmf_lobe(samples), toksvig = toksvig_lobe(samples);
        single_errors.push_back(meter.error(std::span(&single, 1)));
        const VmfLobe naive{1.0f, single.mu, kKappaMax};  // the renormalized mean, unwidened
        naive_errors.push_back(meter.error(std::span(&naive, 1)));
        toksvig_errors.push_back(meter.error(std::span(&toksvig, 1)));
        if (measure_alignment && level > 0) {
            gather_footprint(pyramid.source, level, x, y, pyramid.settings.wrap, all_samples);
            children.clear();
            const LevelSize finer = pyramid.size(level - 1);
            for (int cy = 2 * y; cy < std::min(2 * y + 2, finer.height); ++cy)
                for (int cx = 2 * x; cx < std::min(2 * x + 2, finer.width); ++cx)
                    for (const VmfLobe& lobe : pyramid.texel_lobes(level - 1, cx, cy)) children.push_back(lobe);
            const TexelFit independent = fit_texel(all_samples, children, fit, &meter);
            independent_errors.push_back(meter.error(independent.lobes));
        }
    }
    stats.measured_texels = int(measured);
    stats.fit = summarize(fit_errors);
    if (!independent_errors.empty()) stats.independent_fit = summarize(independent_errors);
    stats.naive = summarize(naive_errors);
    stats.single_vmf = summarize(single_errors);
    stats.toksvig = summarize(toksvig_errors);
    return stats;
}

}  // namespace ndfbake
