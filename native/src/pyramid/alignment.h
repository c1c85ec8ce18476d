// Aligned lobes for hardware interpolation (Han et al. 2007, §7.3, eq. 23).
#pragma once

#include <span>

#include "pyramid/lobe_pyramid.h"

namespace ndfbake {

// Reorders the lobe slots of every texel, from the top level down and left to right within a
// row, so that slot j points where slot j of the parent and of the left neighbour point; then
// refines each texel's lobes with a few EM iterations whose M-step pulls μ_j towards those
// neighbours (eq. 23, strength settings.alignment_strength). Level 0 texels (one lobe each) take
// the slot their parent and left neighbour favour. Rows of a level are independent given the
// level above, so they run in parallel.
void align_lobe_slots(LobePyramid& pyramid, const PyramidSettings& settings, const ProgressTick& tick);

// Greedy slot assignment: score(i, s) = Σ_refs α_ref,s (μ_i · μ_ref,s); returns, for each lobe,
// the slot it goes to. Lobes are taken heaviest first when scores tie (no references).
void assign_slots(std::span<const VmfLobe> lobes, std::span<const VmfLobe> parent,
                  std::span<const VmfLobe> left, std::span<int> slot_of_lobe);

}  // namespace ndfbake
