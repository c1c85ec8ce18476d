// Splitting faces into triangles the way MikkTSpace does, so that frames computed here agree with
// any MikkTSpace-based baker or renderer (Blender's calc_tangents among them).
#pragma once

#include <cstdint>
#include <vector>

#include "tangent/big_vector.h"

#include "tangent/mesh_input.h"

namespace ndfbake {

struct MeshTriangle {
    uint32_t corner[3];  // face-corner indices, in the order MikkTSpace walks them
    uint32_t face;
};

// Which diagonal MikkTSpace cuts a quad along: the shorter one in UV space; on an exact tie the
// shorter one in object space, preferring 0-2 unless 1-3 is strictly shorter. Both the squared
// lengths and their comparison use the reference's float operations, so ties break identically.
bool mikk_quad_splits_02(const MeshInput& mesh, size_t face);

// Triangles in face order (a quad gives two consecutive triangles). Faces must be tris or quads.
BigVector<MeshTriangle> mikk_triangles(const MeshInput& mesh, int threads);

// Blender's renderer tessellates a convex quad along 0-2 and switches to 1-3 only when the quad is
// folded over that diagonal; per-pixel interpolation (and so baking) must follow the renderer.
bool render_quad_splits_02(const MeshInput& mesh, size_t face);

}  // namespace ndfbake
