// Mirroring-safe vertex splits: turning per-corner frames into an indexed mesh an engine can draw,
// without ever sharing one vertex between corners whose frames differ (the mistake behind most
// mirrored-UV seams in engine integrations of MikkTSpace).
#pragma once

#include <cstdint>
#include <span>

#include "tangent/mesh_input.h"

namespace ndfbake {

struct SplitStats {
    uint64_t input_vertices = 0, output_vertices = 0;
    uint64_t uv_seams = 0, hard_edges = 0, mirror_seams = 0, tangent_splits = 0;
};

// tangents: 4 floats per corner (xyz, sign). Corners of one input vertex share an output vertex
// iff normal, UV, tangent and sign compare equal. Output vertices are numbered by input vertex,
// then by first corner. corner_to_vertex: one per corner; vertex_source: at least corner_count.
SplitStats split_vertices(const MeshInput& mesh, std::span<const float> tangents, int threads,
                          std::span<uint32_t> corner_to_vertex, std::span<uint32_t> vertex_source);

}  // namespace ndfbake
