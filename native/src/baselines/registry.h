// Every baseline NDF representation by name, so that benchmarks and tools can loop over them.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "ndf/ndf_pyramid.h"

namespace ndfbake {

// SH orders baseline_names lists (build_baseline accepts "sh-N" for any 0 ≤ N ≤ kMaxShOrder).
inline constexpr int kListedShOrderMin = 2;
inline constexpr int kListedShOrderMax = 8;

// naive, toksvig, single-vmf, lean, xu-1x1, xu-1x4, xu-2x4, xu-adaptive, sh-2 … sh-8.
std::vector<std::string> baseline_names();

// Builds the named representation's full pyramid over gather_footprint's footprints. Throws
// Error(invalid_argument) for an unknown name or an empty map.
std::unique_ptr<NdfPyramid> build_baseline(const std::string& name, const NormalMap& map, WrapMode wrap);

}  // namespace ndfbake
