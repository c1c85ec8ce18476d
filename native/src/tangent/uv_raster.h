// Rasterizing a mesh in UV space: which triangle covers each texel centre, and where inside it.
#pragma once

#include <cstdint>
#include <functional>
#include <vector>

#include "tangent/mesh_input.h"

namespace ndfbake {

struct RenderTriangle {
    uint32_t corner[3];
};

// Triangles as Blender's renderer interpolates them: triangles as they are, quads along 0-2 unless
// folded over it (then 1-3), in face order.
std::vector<RenderTriangle> render_triangles(const MeshInput& mesh);

// Calls visit(x, y, triangle, b0, b1, b2) once per texel whose centre lies in a triangle (edges
// included), for the first such triangle in list order; b are the barycentric weights of the
// triangle's corners at the texel centre. Texel (x, y) is centred at u = (x + 0.5) / width,
// v = 1 - (y + 0.5) / height (row 0 at the top, as image files store it). Rows are split among
// threads, each row is visited by one thread, and `covered` (width*height) records the visits.
using TexelVisitor = std::function<void(int x, int y, uint32_t triangle, double b0, double b1, double b2)>;
void rasterize_uv(const MeshInput& mesh, const std::vector<RenderTriangle>& triangles, int width, int height,
                  int threads, std::vector<uint8_t>& covered, const TexelVisitor& visit);

}  // namespace ndfbake
