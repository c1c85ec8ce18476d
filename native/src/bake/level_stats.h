// How good a fitted level is: lobe counts and errors against the exact effective BRDF, beside the
// baselines and the cost of alignment, measured on an even sample of texels.
#pragma once

#include <cstdint>
#include <optional>
#include <vector>

#include "math/brdf.h"
#include "pyramid/lobe_pyramid.h"

namespace ndfbake {

// Texels measured per level by reports, and fine normals per texel (a stride through the
// footprint, see subsample_footprint): the exact reference costs normals × directions, and these bounds keep a report of
// a 4096² map to seconds. Tests that need every texel pass 0 (no limit).
inline constexpr int kReportTexelsPerLevel = 64;
inline constexpr int kReportSampleCap = 256;

struct ErrorSummary {
    float mean = 0.0f;
    float p95 = 0.0f;
};

struct LevelStats {
    int level = 0;
    LevelSize size;
    std::vector<uint64_t> lobe_histogram;  // texels with k lobes, k = 0..slots, over the whole level
    int measured_texels = 0;
    ErrorSummary fit;                // the pyramid's (aligned) lobes
    // The same budget without alignment, for alignment's cost: measured only when asked for
    // (measure_level's measure_alignment) and above level 0, which has no finer level to align to.
    std::optional<ErrorSummary> independent_fit;
    ErrorSummary naive;              // plain MIP-mapping: the base BRDF about the mean normal
    ErrorSummary single_vmf;
    ErrorSummary toksvig;
};

// How many texels of a level have k lobes, for k = 0..pyramid.slots.
std::vector<uint64_t> lobe_histogram(const LobePyramid& pyramid, int level);

// The exact-reference samples of one texel: its footprint, subsampled to `sample_cap` (0: all).
void texel_reference_samples(const NormalMap& map, WrapMode wrap, int level, int x, int y, int sample_cap,
                             std::vector<WeightedNormal>& out);

// `max_texels` = 0 measures every texel. `measure_alignment` adds independent_fit above level 0
// (one extra fit per measured texel, from its fine normals and its children's lobes, with the
// settings the pyramid fitted that level with: level_fit_settings).
LevelStats measure_level(const LobePyramid& pyramid, int level, const BaseBrdf& brdf, int max_texels,
                         int sample_cap, bool measure_alignment);

}  // namespace ndfbake
