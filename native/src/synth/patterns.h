// Synthetic normal maps that stress NDF filtering: each has a strongly multi-modal or anisotropic
// distribution of normals once many texels fall into one MIP texel, as real materials do.
#pragma once

#include <cstdint>
#include <optional>
#include <span>
#include <string_view>

#include "normal_map.h"

namespace ndfbake {

enum class Pattern {
    vgroove,    // alternating columns of two facets tilted ±30° about Y (Han et al. 2007, Fig. 1)
    bumps,      // lattice of smooth cosine bumps on a flat base
    fbm,        // fractal value-noise height field, RMS tilt about 25°
    brushed,    // streaks along X: normals tilt about the X axis
    scratches,  // flat, with thin straight scratches with 55° walls in a few directions
    weave,      // plain weave of round threads in X and Y: four lobes (±X, ±Y tilts)
};

std::span<const Pattern> all_patterns();
const char* pattern_name(Pattern pattern);
std::optional<Pattern> pattern_from_name(std::string_view name);

// Largest width or height synthesize accepts.
inline constexpr int kMaxSynthSide = 16384;

// Unit tangent-space normals (+Z out, OpenGL +Y up the V axis, row 0 the top row) with z > 0
// everywhere. The map tiles seamlessly, features keep their size in pixels up to 256-pixel maps and
// grow with larger ones, and the result depends only on the arguments, on every platform. The
// regular patterns (vgroove, bumps, weave) ignore the seed. Throws Error{invalid_argument} unless
// 1 <= width, height <= kMaxSynthSide.
NormalMap synthesize(Pattern pattern, int width, int height, uint32_t seed = 1);

}  // namespace ndfbake
