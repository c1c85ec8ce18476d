// Findings about a mesh that decide whether its tangent frames, and so its normal maps, come out
// right: the things a user can fix before baking (or should know are intended, like mirroring).
#pragma once

#include <cstdint>
#include <string>

#include "tangent/mesh_input.h"

namespace ndfbake {

struct MeshReport {
    uint64_t faces = 0, triangles = 0, quads = 0, ngons = 0;
    uint64_t degenerate_triangles = 0;    // zero world area
    uint64_t zero_area_uv_triangles = 0;  // |UV area| at or below FLT_MIN (MikkTSpace "group with any")
    uint64_t uv_islands = 0;
    uint64_t mirrored_islands = 0;        // every triangle clockwise in UV: sign -1
    uint64_t flipped_islands = 0;         // both windings joined by shared UV edges
    uint64_t flipped_triangles = 0;       // the minority winding (by UV area) of those islands
    uint64_t inverted_normal_faces = 0;   // normals against the winding
    int64_t ngon_first = -1, degenerate_first = -1, zero_area_uv_first = -1, flipped_first = -1,
            inverted_normal_first = -1;
};

// Triangulates like MikkTSpace (n-gons as fans, for counting only). Accepts any face size >= 3.
MeshReport diagnose_mesh(const MeshInput& mesh);

// One line per finding with what it means and what to do; "no problems found" when clean.
std::string describe(const MeshReport& report);

}  // namespace ndfbake
