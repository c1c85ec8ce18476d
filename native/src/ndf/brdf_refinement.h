// Lobes refined against the effective BRDF they are shaded with. EM (Han et al. 2007, §7.1)
// maximizes the likelihood of the fine normals, but what a renderer shows is the NDF convolved
// with the BRDF (eq. 4–5, 20–21): under a sharp BRDF the likeliest lobes are not the ones whose
// convolved mixture is closest to the exact effective BRDF. Levenberg-Marquardt on that distance
// moves every lobe's α, μ and κ there, starting from EM's fit.
#pragma once

#include <span>
#include <vector>

#include "math/brdf.h"
#include "math/vmf.h"
#include "ndf/weighted_normal.h"

namespace ndfbake {

// Levenberg-Marquardt steps per texel at most. Measured on the six synthetic patterns (Blinn-Phong
// 32 and 128, levels 2–6): the error falls by nine tenths of what 40 steps reach within 10.
inline constexpr int kRefineIterations = 10;

// Directions within this many BRDF widths (BaseBrdf::angular_width) of the texel's normals and
// lobes make up the objective: beyond, the reference and every convolved lobe are below 1% of
// their peak, and a sharp BRDF's dense direction set shrinks to the cap the texel covers.
inline constexpr float kCapMarginWidths = 4.0f;

// The refinement matches the effective BRDF of at most this many of a texel's fine normals
// (subsample_footprint). A sharp BRDF resolves the NDF's fine structure, so a thin subsample
// would be fitted instead of the footprint: measured on the six synthetic patterns at 256²,
// Blinn-Phong 128, level 6 (4096 normals a texel), error 0.241 of Toksvig's with 256 normals,
// 0.211 with 1024, 0.197 with all 4096.
inline constexpr int kRefineSampleCap = 4096;

// A refined lobe lighter than this carries nothing a shader would show and is dropped.
inline constexpr float kNegligibleLobeWeight = 1e-4f;

// The objective's directions are a Fibonacci hemisphere of this fraction of the error measure's
// count (error_direction_count), at least kMinErrorDirections. Measured, mean error over levels
// 1+ of a 1024² fBm map at GGX roughness 0.3 (all directions 0.2021): half 0.2021 in 0.6 of the
// time, a quarter 0.2061 (level 2: 0.099 against 0.074; GGX's peak is narrower than its α).
inline constexpr int kRefineDirectionFraction = 2;

class LobeRefiner {
public:
    explicit LobeRefiner(const BaseBrdf& brdf);

    // Moves `lobes` (every α > 0, Σα = 1) towards the least relative L2 distance between their
    // convolved mixture (what the shader computes) and the normals' exact effective BRDF. Every
    // step it keeps lowers that distance on the directions it uses (the lobes it then drops, under
    // kNegligibleLobeWeight, add at most their weight back); κ stays in [kKappaMin, kKappaMax],
    // Σα = 1.
    void refine(std::span<const WeightedNormal> normals, std::vector<VmfLobe>& lobes) const;

private:
    BaseBrdf brdf_;
    std::vector<Vec3> directions_;  // each texel uses those near its normals
};

}  // namespace ndfbake
