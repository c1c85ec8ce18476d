// Converting normal maps between object space and tangent space with the exact per-pixel frame of
// Blender's Normal Map node (tangent space), so that a map converted here and rendered through
// that node gives back the object-space normals (the "exact inverse" rule, Mikkelsen 2008 §3.4).
//
// Per texel: barycentric weights b of the covering triangle, then, all unnormalized as the node
// interpolates them, T = Σ b t_k, s = Σ b s_k, N = Σ b n_k (normalized where the renderer does so:
// Cycles from Blender 5.1 on), B = s cross(N, T), and
//   tangent -> object: n = normalize(x T + y B + z N)
//   object -> tangent: (x, y, z) = normalize([T B N]^-1 n)
#pragma once

#include <cstdint>
#include <span>

#include "math/vec3.h"
#include "tangent/mesh_input.h"

namespace ndfbake {

enum class SpaceDirection { object_to_tangent, tangent_to_object };

struct SpaceSettings {
    uint32_t padding = 16;  // rings of texels grown around islands; 0xffffffff fills the image
    int threads = 0;
    bool unit_normal = false;  // normalize the interpolated N before building the frame
};

// The node's forward map for one texel, and its inverse. frame: T, B, N as above.
struct TexelFrame {
    Vec3 t, b, n;
};
Vec3 tangent_to_object(const TexelFrame& frame, const Vec3& tangent_normal);
// Returns false (and (0, 0, 1)) where the frame has no inverse (zero or parallel T and N).
bool object_to_tangent(const TexelFrame& frame, const Vec3& object_normal, Vec3& tangent_normal);

// in/out: width*height*3 floats, rows top to bottom; tangents: 4 per corner (xyz, sign).
// coverage: empty or width*height (0 empty, 1 rasterized, 2 padding). Returns rasterized texels.
size_t convert_normal_map(const MeshInput& mesh, std::span<const float> tangents, SpaceDirection direction,
                          std::span<const float> in, int width, int height, const SpaceSettings& settings,
                          std::span<float> out, std::span<uint8_t> coverage);

}  // namespace ndfbake
