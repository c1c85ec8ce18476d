// Every NDF representation as a full MIP pyramid over the same footprints, so that they can be
// measured on the same footing: the effective BRDF each one gives a shader, its storage and
// its build time.
#pragma once

#include <memory>
#include <span>
#include <string>

#include "math/brdf.h"
#include "normal_map.h"
#include "pyramid/footprint.h"

namespace ndfbake {

class NdfPyramid {
public:
    virtual ~NdfPyramid() = default;

    // A short name for tables: "toksvig", "lean", "vmf-4", "sh-6", "xu-2x4", ...
    virtual std::string name() const = 0;
    virtual int level_count() const = 0;
    virtual LevelSize size(int level) const = 0;
    // Scalars a texel stores (what a texture set of this representation holds per texel).
    virtual int floats_per_texel() const = 0;
    // The effective BRDF a shader computes from texel (x, y) of `level` under `brdf`, at each
    // direction: what the exact effective BRDF (eq. 4) is compared with.
    virtual void effective_brdf(int level, int x, int y, const BaseBrdf& brdf, std::span<const Vec3> directions,
                                std::span<float> out) const = 0;
};

}  // namespace ndfbake
