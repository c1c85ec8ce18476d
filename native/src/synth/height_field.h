// A periodic height field and the normals of the surface it describes.
#pragma once

#include <vector>

#include "normal_map.h"

namespace ndfbake {

// Heights sampled at pixel centres, in pixel units: a rise of one over one pixel is a 45° slope,
// which is what lets patterns state their steepness independently of the map size. Indices wrap
// around, so differences at the border see the opposite edge and the derived normals tile.
class HeightField {
public:
    HeightField(int width, int height);

    int width() const { return width_; }
    int height() const { return height_; }

    float& at(int x, int y) { return heights_[index(x, y)]; }
    float at(int x, int y) const { return heights_[index(x, y)]; }
    // Wrapping access for callers that rasterize features which cross the border.
    float& at_wrapped(long long x, long long y);

    // Central differences with wrap-around. slope_row follows the row index, i.e. points down the image.
    float slope_x(int x, int y) const;
    float slope_row(int x, int y) const;

    // Root mean square of the gradient magnitude over all pixels.
    double rms_slope() const;

private:
    size_t index(int x, int y) const { return size_t(y) * size_t(width_) + size_t(x); }

    int width_;
    int height_;
    std::vector<float> heights_;
};

// Tangent-space normals of the surface z = slope_scale * h. Row 0 is the top of the image and +Y
// points up the V axis, so a height rising with the row index tilts the normal towards +Y.
NormalMap normals_from_heights(const HeightField& field, float slope_scale = 1.0f);

}  // namespace ndfbake
