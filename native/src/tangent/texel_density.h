// UV texel density: how many UV units (times the texture size: texels) a world unit of surface
// covers. Level-of-detail selection turns it, with the camera distance, into a MIP level.
#pragma once

#include <span>

#include "tangent/mesh_input.h"

namespace ndfbake {

// Writes sqrt(UV area / world area) per face (0 where either area is 0; polygons use their vector
// area, so n-gons are fine) and returns the same ratio over the whole mesh.
double texel_density(const MeshInput& mesh, std::span<float> face_density);

// World and UV area of one face (polygon vector area and shoelace area, both unsigned).
struct FaceAreas {
    double world = 0.0, uv = 0.0, signed_uv = 0.0;
};
FaceAreas face_areas(const MeshInput& mesh, size_t face);

}  // namespace ndfbake
