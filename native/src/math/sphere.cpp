#include "math/sphere.h"

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

}  // namespace ndfbake
