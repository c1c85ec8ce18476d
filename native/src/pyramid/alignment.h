// Aligned lobes for hardware interpolation (Han et al. 2007, §7.3, eq. 23).
#pragma once

#include <span>

#include "pyramid/lobe_pyramid.h"

namespace ndfbake {

// Reorders the lobe slots of every texel, from the top level down and left to right within a
// row, so that slot j points where slot j of the parent and of the left neighbour point; then
// refines each texel's lobes with a few EM iterations whose M-step pulls μ_j towards those
// neighbours (eq. 23, strength settings.alignment_strength). Rows of a level are independent
// given the level above, so they run in parallel.
//
// Level 0 is what hardware MIP-mapping (EEVEE's own levels) averages: each fine normal takes the
// slot of the top level's lobe most responsible for it, so slot j holds one cluster of directions
// over the whole map (as Xu et al. 2017's sphere partitions do) and a box average of any block
// is that block's mixture over the same clusters. Measured on a 64² weave averaged to level 3
// (Blinn-Phong 32): slots chosen by similarity to the parent's slots 0.46 relative error, by the
// parent's responsibilities 0.52, by the top level's 0.15 (the per-level fit: 0.12).
void align_lobe_slots(LobePyramid& pyramid, const PyramidSettings& settings, const ProgressTick& tick);

// Greedy slot assignment: score(i, s) = Σ_refs α_ref,s (μ_i · μ_ref,s); returns, for each lobe,
// the slot it goes to. Lobes are taken heaviest first when scores tie (no references).
void assign_slots(std::span<const VmfLobe> lobes, std::span<const VmfLobe> parent,
                  std::span<const VmfLobe> left, std::span<int> slot_of_lobe);

}  // namespace ndfbake
