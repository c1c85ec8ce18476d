// MikkTSpace-compatible tangent frames per face corner (Mikkelsen 2008, §3; behaviour of the
// reference code and of Blender's C++ port for everything the thesis leaves open).
//
// Per corner: a unit tangent (perpendicular to the corner normal) and the bitangent sign, with
// bitangent = sign * cross(normal, tangent); optionally the averaged lengths |dP/du|, |dP/dv|.
// The algorithm, in order:
//   1. quads are split along the shorter UV diagonal (tie: shorter position diagonal, then 0-2);
//   2. corners are welded when position, normal and UV are bitwise equal (rules 1-3 of §3.3);
//   3. per triangle: dP/du from eqs. 42/43, orientation = sign of the UV area (rule 4); a
//      triangle with two coincident positions is degenerate, one with (near) zero UV area or
//      derivative "groups with any" neighbour and contributes nothing;
//   4. around each welded vertex, triangles connected edge by edge with the same orientation form
//      a group (so groups never cross a mirror seam); each group averages its triangles' tangents
//      projected onto the vertex normal, weighted by the corner angle;
//   5. degenerate triangles copy a frame from a good corner of the same welded vertex.
// Results do not depend on the thread count.
#pragma once

#include <cstdint>
#include <span>

#include "tangent/mesh_input.h"

namespace ndfbake {

struct TangentStats {
    uint64_t triangles = 0;
    uint64_t degenerate_triangles = 0;  // two corners at the same position
    uint64_t group_with_any = 0;        // zero UV area or zero derivative
    uint64_t groups = 0;                // tangent spaces built (welded vertex x connected fan part)
};

// tangents: 4 floats per corner (x, y, z, sign). magnitudes: empty, or 2 floats per corner.
// The default frame of a corner no good triangle reaches is (1, 0, 0) with sign -1, as in MikkTSpace.
TangentStats generate_tangent_frames(const MeshInput& mesh, int threads, std::span<float> tangents,
                                     std::span<float> magnitudes);

}  // namespace ndfbake
