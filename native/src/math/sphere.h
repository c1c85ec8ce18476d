// Deterministic direction sets on the sphere.
#pragma once

#include <vector>

#include "math/vec3.h"

namespace ndfbake {

// `count` directions spread evenly over the upper hemisphere (z ≥ 0): a Fibonacci lattice,
// equal area per point. Half vectors of lights and views above the surface live here.
std::vector<Vec3> fibonacci_hemisphere(int count);

// Two unit vectors that complete the unit vector `axis` to a right-handed orthonormal frame
// (t, b, axis): t from whichever of x and y is further from `axis`.
struct OrthonormalFrame {
    Vec3 t, b;
};
OrthonormalFrame orthonormal_frame(const Vec3& axis);

// `count` directions spread evenly over the spherical cap of angular radius `radius` about the
// unit vector `axis` (a Fibonacci spiral), of which those below the horizon (z < 0) are left out.
// `phase` ∈ [0, 1) turns the spiral: two phases give two interleaved sets.
std::vector<Vec3> fibonacci_cap(const Vec3& axis, double radius, int count, double phase);

// Solid angle of a cap of angular radius `radius`: 2π(1 − cos radius).
double cap_solid_angle(double radius);

}  // namespace ndfbake
