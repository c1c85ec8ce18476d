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

// Levenberg-Marquardt steps per texel (per start) at most. Measured on the six synthetic patterns
// at Blinn-Phong 128: 25 steps instead of 10 moved the level-4 mean from 0.201 to 0.200 of
// Toksvig's error, at twice the time.
inline constexpr int kRefineIterations = 10;

// A texel's objective is its effective BRDF on directions within this many base-BRDF widths
// (BaseBrdf::angular_width) of its normals and lobes, where the reference lives (beyond, it is
// under 1% of its peak). The check that a refined fit is kept by (see refine) reaches this many
// lobe widths, √(w² + 1/κ_min) with the broadest starting lobe, so that lobe mass spread past the
// objective's cap counts there.
inline constexpr float kCapMarginWidths = 4.0f;
// ... spaced at this fraction of the base BRDF's angular width. Measured, mean error over levels
// 1+ of a 1024² fBm map at GGX roughness 0.3: spacing 0.5 (the error measure's own) and 0.7 give
// the same error, 1.0 loses a third of the gain at level 2 (GGX's peak is narrower than its α).
inline constexpr float kRefineSpacingWidths = 0.7f;
// A texel whose objective would need more directions than this (a BRDF far sharper than the
// spread of its normals) keeps EM's fit: the cost grows with the count, and a coarser set would
// let the lobes fit the gaps between directions.
inline constexpr int kMaxRefineDirections = 8192;

// The refinement matches the effective BRDF of at most this many of a texel's fine normals
// (subsample_footprint). A sharp BRDF resolves the NDF's fine structure, so a thin subsample
// would be fitted instead of the footprint: measured on the six synthetic patterns at 256²,
// Blinn-Phong 128, level 6 (4096 normals a texel), error 0.241 of Toksvig's with 256 normals,
// 0.211 with 1024, 0.197 with all 4096.
inline constexpr int kRefineSampleCap = 4096;

// A refined lobe lighter than this carries nothing a shader would show and is dropped.
inline constexpr float kNegligibleLobeWeight = 1e-4f;

class LobeRefiner {
public:
    explicit LobeRefiner(const BaseBrdf& brdf);

    // Moves `lobes` (every α > 0, Σα = 1) towards the least relative L2 distance between their
    // convolved mixture (what the shader computes) and the normals' exact effective BRDF. The
    // result is kept only if it is also closer on a second, interleaved set of directions over the
    // wider cap of the lobes' own width (so a lobe cannot gain by fitting between directions or
    // by spreading outside the objective's cap); otherwise `lobes` stay as they were. κ stays in
    // [kKappaMin, kKappaMax], Σα = 1.
    void refine(std::span<const WeightedNormal> normals, std::vector<VmfLobe>& lobes) const;

private:
    BaseBrdf brdf_;
};

}  // namespace ndfbake
