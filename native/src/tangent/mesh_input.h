// A validated, read-only view of a polygon mesh handed to the library as plain arrays: positions
// per vertex, faces as corner counts plus a vertex index per corner, normals and UVs per corner or
// per vertex. Everything downstream may assume indices in range and finite values.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "math/vec3.h"
#include "tangent/tangent_math.h"

namespace ndfbake {

enum class AttributeDomain { corner, vertex };

struct MeshArrays {
    std::span<const float> positions;          // 3 per vertex
    std::span<const uint32_t> face_sizes;      // corners per face
    std::span<const uint32_t> corner_vertices; // vertex index per corner, faces one after another
    std::span<const float> normals;            // 3 per corner or per vertex
    AttributeDomain normal_domain = AttributeDomain::corner;
    std::span<const float> uvs;                // 2 per corner or per vertex
    AttributeDomain uv_domain = AttributeDomain::corner;
};

// Tangent frames exist for triangles and quads only; diagnostics and densities accept n-gons.
enum class NgonPolicy { refuse, accept };

class MeshInput {
public:
    // Throws Error(invalid_argument) naming the first offending face, corner or vertex.
    static MeshInput validate(const MeshArrays& arrays, NgonPolicy ngons);

    size_t vertex_count() const { return arrays_.positions.size() / 3; }
    size_t face_count() const { return arrays_.face_sizes.size(); }
    size_t corner_count() const { return arrays_.corner_vertices.size(); }

    uint32_t face_size(size_t f) const { return arrays_.face_sizes[f]; }
    uint32_t face_offset(size_t f) const { return face_offsets_[f]; }
    uint32_t corner_vertex(size_t c) const { return arrays_.corner_vertices[c]; }

    Vec3 vertex_position(size_t v) const
    {
        const float* p = arrays_.positions.data() + 3 * v;
        return {p[0], p[1], p[2]};
    }
    Vec3 position(size_t c) const { return vertex_position(corner_vertex(c)); }
    Vec3 normal(size_t c) const
    {
        const size_t i = arrays_.normal_domain == AttributeDomain::corner ? c : corner_vertex(c);
        const float* n = arrays_.normals.data() + 3 * i;
        return {n[0], n[1], n[2]};
    }
    Vec2 uv(size_t c) const
    {
        const size_t i = arrays_.uv_domain == AttributeDomain::corner ? c : corner_vertex(c);
        const float* t = arrays_.uvs.data() + 2 * i;
        return {t[0], t[1]};
    }
    // Raw pointers for bitwise comparisons of a corner's attributes.
    const float* normal_ptr(size_t c) const
    {
        return arrays_.normals.data() + 3 * (arrays_.normal_domain == AttributeDomain::corner ? c : corner_vertex(c));
    }
    const float* uv_ptr(size_t c) const
    {
        return arrays_.uvs.data() + 2 * (arrays_.uv_domain == AttributeDomain::corner ? c : corner_vertex(c));
    }

    size_t triangle_faces() const { return triangles_; }
    size_t quad_faces() const { return quads_; }
    size_t ngon_faces() const { return ngons_; }

private:
    MeshArrays arrays_;
    std::vector<uint32_t> face_offsets_;
    size_t triangles_ = 0, quads_ = 0, ngons_ = 0;
};

// The largest mesh the module indexes with 32-bit integers (triangle corners are t*3+i).
inline constexpr uint64_t kMaxMeshCorners = uint64_t(1) << 30;

}  // namespace ndfbake
