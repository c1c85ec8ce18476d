// The storage every linear baseline shares: a fixed number of floats per texel that are the
// footprint-weighted mean of a per-normal feature vector φ(n). Such storage is what hardware
// MIP-mapping and bilinear filtering average correctly, and each level is the plain weighted
// average of the level below wherever the footprints nest.
#pragma once

#include <functional>
#include <span>
#include <vector>

#include "ndf/ndf_pyramid.h"

namespace ndfbake {

class LinearNdfPyramid : public NdfPyramid {
public:
    int level_count() const override { return int(sizes_.size()); }
    LevelSize size(int level) const override;
    int floats_per_texel() const override { return floats_; }

    // The stored floats of texel (x, y) of `level`; throws Error(invalid_argument) out of range.
    std::span<const float> texel(int level, int x, int y) const;

protected:
    // Writes φ(n) to out[0 .. floats).
    using Features = std::function<void(const Vec3& n, float* out)>;

    // Level 0 stores φ of each fine normal; level L the mean of φ over the texel's footprint
    // (gather_footprint's, with its weights). Throws Error(invalid_argument) for an empty or
    // inconsistent map.
    LinearNdfPyramid(const NormalMap& map, WrapMode wrap, int floats, const Features& features);

    // Throws Error(invalid_argument) unless `out` has one slot per direction.
    static void check_output(std::span<const Vec3> directions, std::span<float> out);

private:
    int floats_;
    std::vector<LevelSize> sizes_;
    std::vector<std::vector<float>> levels_;
};

// Throws Error(invalid_argument) unless the map has a positive size and one normal per texel.
void check_normal_map(const NormalMap& map);

}  // namespace ndfbake
