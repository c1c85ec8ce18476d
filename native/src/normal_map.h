// A decoded tangent-space normal map: unit normals, +Z out of the surface, OpenGL convention (+Y up V).
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "math/vec3.h"

namespace ndfbake {

// How many pixels of a decoded map needed repair, by the rule applied (see io/normal_decode.h).
struct RepairCounts {
    uint64_t non_finite = 0;     // NaN or Inf component: replaced by +Z
    uint64_t zero_length = 0;    // length below kMinNormalLength: replaced by +Z
    uint64_t renormalized = 0;   // length off 1 by more than kUnitLengthTolerance: normalized
    uint64_t below_horizon = 0;  // z < 0: reflected to z = |z| (keeps the slope direction)
    uint64_t total() const { return non_finite + zero_length + renormalized + below_horizon; }
};

struct NormalMap {
    int width = 0;
    int height = 0;
    std::vector<Vec3> normals;  // row-major, row 0 at the top of the image as stored in the file

    const Vec3& at(int x, int y) const { return normals[size_t(y) * size_t(width) + size_t(x)]; }
    Vec3& at(int x, int y) { return normals[size_t(y) * size_t(width) + size_t(x)]; }
};

}  // namespace ndfbake
