// The samples every NDF fit consumes: fine normals with a weight (footprint multiplicity).
#pragma once

#include "math/vec3.h"

namespace ndfbake {

struct WeightedNormal {
    Vec3 n;          // unit length
    float weight;    // > 0
};

}  // namespace ndfbake
