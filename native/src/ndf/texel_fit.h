// One texel's NDF: the fewest vMF lobes whose effective BRDF meets the tolerance.
#pragma once

#include <span>
#include <vector>

#include "math/vmf.h"
#include "ndf/effective_brdf.h"
#include "ndf/spherical_em.h"

namespace ndfbake {

// A texel with at most this many samples (fine normals or bins) is fitted from the finer level's
// lobes only: measured on the synthetic patterns, the second start changes nothing there (few
// samples have few local optima) and costs a third of the fit.
inline constexpr int kSecondStartMinSamples = 64;

// EM's starting κ is capped: seeds taken from finer levels can be near kKappaMax, and a start
// that sharp makes the first E-step a hard assignment that EM cannot recover from.
inline constexpr float kMaxSeedKappa = 1e3f;

// How a texel's lobes are fitted to its samples once seeded.
enum class TexelSolver {
    em,                // spherical EM (ndf/spherical_em.h), as §7.1
    spherical_kmeans,  // its hard-assignment limit (ndf/spherical_kmeans.h), from the finer level's lobes only
};

struct TexelFitSettings {
    int max_lobes = 4;        // 1..kMaxLobes
    // Relative effective-BRDF error a texel may keep; ≤ 0 always fits max_lobes (where the samples
    // have that many distinct directions). Off by default: measured by `ndfbake bench` on the
    // synthetic patterns, scoring every texel costs more time than the lobes it saves (4.1 s
    // against 2.8 s for 4 lobes everywhere, at slightly higher error), so the budget pays only
    // where fewer slots are written or shaded.
    float tolerance = 0.0f;
    EmSettings em;
    // Also start EM from the farthest samples and keep the likelier fit (see fit_from_seeds) where
    // the texel has more than kSecondStartMinSamples samples; off, only the finer level's lobes
    // seed EM, as in §7.1.
    bool two_starts = true;
    // spherical_kmeans runs at most em.max_iterations steps, one start (two_starts is EM's).
    TexelSolver solver = TexelSolver::em;
};

struct TexelFit {
    std::vector<VmfLobe> lobes;  // every α > 0, Σα = 1
    float error = -1.0f;         // relative effective-BRDF error, −1 when not measured
};

// Chooses up to `count` seeds, farthest apart first (Hochbaum-Shmoys, §7.1): the heaviest
// candidate, then repeatedly the one whose nearest chosen seed is farthest away. Candidates are
// the finer level's lobes; when they hold fewer distinct directions, the samples farthest from
// the seeds fill in. Returns fewer than `count` seeds only when the samples have no more
// distinct directions.
std::vector<VmfLobe> farthest_point_seeds(std::span<const VmfLobe> candidates,
                                          std::span<const WeightedNormal> samples, int count);

// A texel of no more samples than lobes, without a lobe budget: each distinct sample is a lobe
// (the maximum-likelihood fit that EM would converge to, without running it), or the samples'
// single lobe where they hold one direction; what fit_texel returns there. Into `lobes`, whose
// storage is reused: level 1 of a 2048² map has a million such texels.
void exact_texel_lobes(std::span<const WeightedNormal> samples, std::vector<VmfLobe>& lobes);

// The lobe budget: one lobe when it meets the tolerance; otherwise the max_lobes fit, merged down
// for as long as the error stays within the tolerance. With tolerance ≤ 0, always the max_lobes
// fit. `meter` scores candidates (and fills TexelFit::error); it may be nullptr without a budget.
TexelFit fit_texel(std::span<const WeightedNormal> samples, std::span<const VmfLobe> child_lobes,
                   const TexelFitSettings& settings, const TexelErrorMeter* meter);

}  // namespace ndfbake
