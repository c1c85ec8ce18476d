// Value noise on a torus, the building block of the random synthetic patterns.
#pragma once

#include <cstdint>

#include "synth/height_field.h"

namespace ndfbake {

// Adds amplitude × value noise in [-1, 1] to every pixel: random values on a cells_x × cells_y
// lattice stretched over the whole map and wrapping around it, so the noise tiles at any map size.
// The lattice values are blended with a quintic fade, which is C2: slopes taken by finite
// differences show no creases along cell borders. `key` selects the random lattice.
void add_periodic_value_noise(HeightField& field, int cells_x, int cells_y, double amplitude, uint64_t key);

}  // namespace ndfbake
