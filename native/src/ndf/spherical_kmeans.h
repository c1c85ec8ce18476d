// Spherical k-means (Dhillon & Modha 2001): vMF EM's hard-assignment limit, for texels of few
// normals.
#pragma once

#include <span>
#include <vector>

#include "math/vmf.h"
#include "ndf/weighted_normal.h"

namespace ndfbake {

// Fits `lobes` (the initial guess, updated in place, order kept) to the weighted samples by
// alternating two steps at most `max_iterations` times, and fewer once the lobes stop moving:
// each sample joins the lobe whose μ is nearest (largest μ·n; ties to the lower index), then
// each lobe takes α, μ and κ = A⁻¹(|r|) from its samples as EM's M-step does (Algorithm 1
// lines 9–14 with ⟨z_ij⟩ ∈ {0, 1}). A lobe that no sample joins gets α = 0 and keeps its μ
// (a later step may give it samples again); callers prune α = 0 lobes. Returns the steps run.
//
// It is the κ → ∞ limit of EM's E-step: where a texel's few normals are already seeded by
// sharp lobes (the finer level's), EM's responsibilities are nearly 0 or 1 anyway, and the
// hard step costs one dot product per sample and lobe instead of an exponential.
int spherical_kmeans(std::span<const WeightedNormal> samples, std::vector<VmfLobe>& lobes, int max_iterations);

}  // namespace ndfbake
