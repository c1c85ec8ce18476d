// The vMF lobe pyramid seen through the common NdfPyramid interface, for the benchmark.
#pragma once

#include <string>

#include "ndf/ndf_pyramid.h"
#include "pyramid/lobe_pyramid.h"

namespace ndfbake {

class VmfNdfPyramid final : public NdfPyramid {
public:
    VmfNdfPyramid(LobePyramid pyramid, std::string name) : pyramid_(std::move(pyramid)), name_(std::move(name)) {}

    std::string name() const override { return name_; }
    int level_count() const override { return pyramid_.level_count(); }
    LevelSize size(int level) const override { return pyramid_.size(level); }
    // Every slot is a stored RGBA texel (α, α·r), used or not.
    int floats_per_texel() const override { return 4 * pyramid_.slots; }
    void effective_brdf(int level, int x, int y, const BaseBrdf& brdf, std::span<const Vec3> directions,
                        std::span<float> out) const override
    {
        mixture_effective_brdf(pyramid_.texel_lobes(level, x, y), brdf, directions, out);
    }

private:
    LobePyramid pyramid_;
    std::string name_;
};

}  // namespace ndfbake
