// Moment-based single-lobe baselines (Bruneton & Neyret 2012, §1.6).
#pragma once

#include <span>

#include "math/vmf.h"
#include "ndf/weighted_normal.h"

namespace ndfbake {

// Toksvig 2005: the averaged normal's length R gives the angular variance σ² = (1 − R)/R. As a
// lobe for the shared convolution rules this is κ = 1/σ² = R/(1 − R): eq. 20 then reproduces
// Toksvig's s' = s R / (R + s(1 − R)) exactly, and the GGX rule widens α² by 2σ².
VmfLobe toksvig_lobe(std::span<const WeightedNormal> samples);

}  // namespace ndfbake
