// Deterministic direction sets on the sphere.
#pragma once

#include <vector>

#include "math/vec3.h"

namespace ndfbake {

// `count` directions spread evenly over the upper hemisphere (z ≥ 0): a Fibonacci lattice,
// equal area per point. Half vectors of lights and views above the surface live here.
std::vector<Vec3> fibonacci_hemisphere(int count);

}  // namespace ndfbake
