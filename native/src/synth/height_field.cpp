#include "synth/height_field.h"

#include <cmath>

namespace ndfbake {

namespace {

int wrap(long long i, int n)
{
    const long long r = i % n;
    return int(r < 0 ? r + n : r);
}

}  // namespace

HeightField::HeightField(int width, int height)
    : width_(width), height_(height), heights_(size_t(width) * size_t(height), 0.0f)
{
}

float& HeightField::at_wrapped(long long x, long long y) { return at(wrap(x, width_), wrap(y, height_)); }

float HeightField::slope_x(int x, int y) const
{
    return 0.5f * (at(wrap(x + 1LL, width_), y) - at(wrap(x - 1LL, width_), y));
}

float HeightField::slope_row(int x, int y) const
{
    return 0.5f * (at(x, wrap(y + 1LL, height_)) - at(x, wrap(y - 1LL, height_)));
}

double HeightField::rms_slope() const
{
    double sum = 0.0;
    for (int y = 0; y < height_; ++y) {
        for (int x = 0; x < width_; ++x) {
            const double sx = slope_x(x, y), sr = slope_row(x, y);
            sum += sx * sx + sr * sr;
        }
    }
    return std::sqrt(sum / double(heights_.size()));
}

NormalMap normals_from_heights(const HeightField& field, float slope_scale)
{
    NormalMap map;
    map.width = field.width();
    map.height = field.height();
    map.normals.resize(size_t(map.width) * size_t(map.height));
    for (int y = 0; y < map.height; ++y) {
        for (int x = 0; x < map.width; ++x) {
            // dh/dv = -dh/drow because V grows up the image while rows grow down it.
            const Vec3 n{-slope_scale * field.slope_x(x, y), slope_scale * field.slope_row(x, y), 1.0f};
            map.at(x, y) = n / length(n);
        }
    }
    return map;
}

}  // namespace ndfbake
