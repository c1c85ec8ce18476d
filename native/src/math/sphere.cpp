#include "math/sphere.h"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace ndfbake {

std::vector<Vec3> fibonacci_hemisphere(int count)
{
    std::vector<Vec3> directions;
    directions.reserve(size_t(count));
    const double golden_angle = std::numbers::pi * (3.0 - std::sqrt(5.0));
    for (int i = 0; i < count; ++i) {
        const double z = 1.0 - (i + 0.5) / count;  // uniform in z = uniform in area
        const double radius = std::sqrt(std::max(0.0, 1.0 - z * z));
        const double phi = golden_angle * i;
        directions.push_back({float(radius * std::cos(phi)), float(radius * std::sin(phi)), float(z)});
    }
    return directions;
}

OrthonormalFrame orthonormal_frame(const Vec3& axis)
{
    const Vec3 t = normalize_or(cross(std::abs(axis.x) < 0.9f ? Vec3{1, 0, 0} : Vec3{0, 1, 0}, axis), {1, 0, 0});
    return {t, cross(axis, t)};
}

std::vector<Vec3> fibonacci_cap(const Vec3& axis, double radius, int count, double phase)
{
    const auto [t, b] = orthonormal_frame(axis);
    const double golden_angle = std::numbers::pi * (3.0 - std::sqrt(5.0));
    const double one_minus_cos = 1.0 - std::cos(std::min(radius, std::numbers::pi));
    std::vector<Vec3> directions;
    directions.reserve(size_t(std::max(count, 0)));
    for (int i = 0; i < count; ++i) {
        const double z = 1.0 - one_minus_cos * (i + 0.5) / count;  // uniform in z: equal area
        const double r = std::sqrt(std::max(0.0, 1.0 - z * z));
        const double phi = golden_angle * (i + phase);
        const Vec3 d = float(r * std::cos(phi)) * t + float(r * std::sin(phi)) * b + float(z) * axis;
        if (d.z >= 0.0f) directions.push_back(normalize_or(d, axis));
    }
    return directions;
}

double cap_solid_angle(double radius) { return 2.0 * std::numbers::pi * (1.0 - std::cos(std::min(radius, std::numbers::pi))); }

}  // namespace ndfbake
