#include "bake/memory_budget.h"

#include <algorithm>
#include <cstdio>

#include "bake/lobe_atlas.h"
#include "error.h"
#include "ndf/weighted_normal.h"
#include "platform/memory.h"
#include "pyramid/normal_bins.h"
#include "pyramid/parallel.h"

namespace ndfbake {

namespace {

std::string human_bytes(uint64_t bytes)
{
    char buffer[32];
    if (bytes >= (uint64_t(1) << 30)) std::snprintf(buffer, sizeof buffer, "%.2f GiB", double(bytes) / double(1 << 30));
    else std::snprintf(buffer, sizeof buffer, "%.1f MiB", double(bytes) / double(1 << 20));
    return buffer;
}

}  // namespace

uint64_t MemoryEstimate::peak() const { return std::max({decode, fit, write}); }

MemoryEstimate estimate_bake_memory(int width, int height, const SourceLayout& source,
                                    const PyramidSettings& settings, const WriteSettings& write)
{
    MemoryEstimate e;
    if (width <= 0 || height <= 0) return e;
    const uint64_t pixels = uint64_t(width) * uint64_t(height);
    const uint64_t slots = uint64_t(std::clamp(settings.fit.max_lobes, 1, kMaxLobes));
    const uint64_t threads = uint64_t(resolve_thread_count(settings.threads));
    const uint64_t normals = pixels * sizeof(Vec3);

    // The pyramid: its own copy of the normals, level 0's slot per texel, a budget error per texel
    // of every level and the lobes of every level above 0.
    uint64_t pyramid = normals + pixels;
    // The largest working set of the fit: at level l each busy worker gathers one texel's
    // footprint (min(2^l, w) x min(2^l, h) fine normals) and EM copies it into four float arrays;
    // a budgeted fit copies it once more to subsample it, and the farthest-sample seeding keeps a
    // distance per sample. The hierarchical fit gathers wherever a texel's children do not cover
    // it (any level of a 1 x N map), and holds two levels' bins.
    const uint64_t per_sample = sizeof(WeightedNormal) + 4 * sizeof(float) + sizeof(float) +
                                (settings.fit.tolerance > 0.0f ? sizeof(WeightedNormal) : 0);
    const bool hierarchical = settings.method == FitMethod::hierarchical;
    uint64_t working = 0, finer_bins = 0;
    const int levels = pyramid_level_count(width, height, settings);
    for (int l = 0; l < levels; ++l) {
        const LevelSize size = level_size(width, height, l);
        const uint64_t texels = uint64_t(size.width) * uint64_t(size.height);
        pyramid += texels * sizeof(float);
        if (l == 0) continue;
        pyramid += texels * slots * sizeof(VmfLobe);
        const uint64_t footprint = largest_footprint(width, height, l);
        const uint64_t busy = std::min<uint64_t>(threads, uint64_t(size.height));
        const uint64_t bins = hierarchical && binned_level(l)
            ? texels * (std::min<uint64_t>(footprint, kNormalBinCount) * sizeof(NormalBin) + sizeof(uint32_t))
            : 0;
        working = std::max(working, finer_bins + bins + footprint * busy * per_sample);
        finer_bins = bins;
        // Level statistics for the report gather the same footprints (twice when they also
        // refit), one level per thread: at worst the top level's on every thread.
        working = std::max(working, std::min<uint64_t>(threads, uint64_t(levels)) * footprint * 2 * sizeof(WeightedNormal));
    }

    if (source.channels > 0) {
        // OpenImageIO's copy of the file's samples, ours (float for float files) and the normals.
        const uint64_t file_samples = pixels * uint64_t(source.channels) * uint64_t(source.sample_bytes);
        const uint64_t our_samples =
            pixels * uint64_t(source.channels) * (source.float_samples ? sizeof(float) : uint64_t(source.sample_bytes));
        e.decode = file_samples + our_samples + normals;
    }
    e.fit = normals + pyramid + working;
    // Files are written on every thread at once (bake.cpp), each holding one texture in float
    // and as converted for the file (at most float again): level 0 is the largest.
    const uint64_t writers = std::min<uint64_t>(
        threads, slots * uint64_t(levels) + (write.atlas ? slots : 0) + (write.mipmap ? slots : 0));
    uint64_t writing = writers * pixels * 4 * sizeof(float) * 2;
    // Colour: every slot's level-0 texture at once, the colour image twice and its decoded pixels.
    if (!write.color_path.empty())
        writing += slots * pixels * 4 * sizeof(float) + 2 * normals + pixels * 4 * sizeof(float);
    if (write.atlas) {
        // Each writer: one lobe's atlas in float and converted for the file, beside one level.
        std::vector<LevelSize> sizes;
        for (int l = 0; l < levels; ++l) sizes.push_back(level_size(width, height, l));
        const AtlasLayout atlas = atlas_layout(sizes);
        writing = std::max(writing, writers * (uint64_t(atlas.width) * uint64_t(atlas.height) * 4 * sizeof(float) * 2 +
                                               pixels * 4 * sizeof(float)));
    }
    if (write.mipmap)
        // Each writer: every level of one slot in float (under 4/3 of level 0) and one level as
        // converted for the file.
        writing = std::max(writing, writers * (pixels * 4 * sizeof(float) * 4 / 3 + pixels * 4 * sizeof(float)));
    e.write = normals + pyramid + writing;
    return e;
}

uint64_t effective_memory_limit(uint64_t requested)
{
    if (requested > 0) return requested;
    const uint64_t physical = physical_memory_bytes();
    return physical > 0 ? physical : UINT64_MAX;
}

void check_memory_budget(const MemoryEstimate& estimate, uint64_t requested_limit, int width, int height,
                         int slots, const std::string& what)
{
    const uint64_t limit = effective_memory_limit(requested_limit);
    const uint64_t peak = estimate.peak();
    if (peak <= limit) return;
    throw Error(Status::out_of_memory,
                what + ": a " + std::to_string(width) + " x " + std::to_string(height) + " map with " +
                    std::to_string(slots) + " lobe slots needs an estimated " + std::to_string(peak) + " bytes (" +
                    human_bytes(peak) + ") at its peak, over the memory limit of " + std::to_string(limit) +
                    " bytes (" + human_bytes(limit) + (requested_limit > 0 ? "" : ", the physical memory") +
                    "); use fewer lobes or a smaller map, or allow more memory (max_memory_bytes; "
                    "ndfbake bake --max-memory)");
}

uint64_t process_peak_memory() { return peak_resident_bytes(); }

}  // namespace ndfbake
