#include "tangent/mesh_input.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstring>
#include <string>

#include "error.h"
#include "tangent/parallel_for.h"

namespace ndfbake {

namespace {

void fail(const std::string& message) { throw Error(Status::invalid_argument, message); }

std::string triple(const float* p)
{
    // Built with += (GCC 12 warns falsely about `"(" + std::string` here).
    std::string s = "(";
    s += std::to_string(p[0]);
    s += ", ";
    s += std::to_string(p[1]);
    s += ", ";
    s += std::to_string(p[2]);
    s += ")";
    return s;
}

// Finite check as an OR over exponent bits (all ones = Inf or NaN): branch-free, so the compiler
// vectorizes it; only a block that fails is searched again for the message.
bool block_finite(const float* v, size_t n)
{
    uint32_t bad = 0;
    for (size_t i = 0; i < n; ++i) {
        uint32_t bits;
        std::memcpy(&bits, v + i, sizeof bits);
        bad |= ((bits & 0x7f800000u) + 0x00800000u) & 0x80000000u;
    }
    return bad == 0;
}

void require_finite(std::span<const float> values, size_t stride, const char* what, const char* element)
{
    constexpr size_t kBlock = 1 << 14;
    std::atomic<size_t> first_bad{values.size()};
    parallel_for((values.size() + kBlock - 1) / kBlock, 0, 8, [&](size_t b, size_t e) {
        for (size_t k = b; k < e; ++k) {
            const size_t begin = k * kBlock, n = std::min(kBlock, values.size() - begin);
            if (block_finite(values.data() + begin, n)) continue;
            for (size_t i = begin; i < begin + n; ++i)
                if (!std::isfinite(values[i])) {
                    size_t current = first_bad.load();
                    while (i < current && !first_bad.compare_exchange_weak(current, i)) {
                    }
                    break;
                }
        }
    });
    const size_t i = first_bad.load();
    if (i == values.size()) return;
    const size_t e = i / stride;
    std::string message = what;
    message += " of ";
    message += element;
    message += " " + std::to_string(e) + " is not finite";
    if (stride == 3) message += " " + triple(values.data() + 3 * e);
    fail(message);
}

}  // namespace

MeshInput MeshInput::validate(const MeshArrays& a, NgonPolicy ngons)
{
    if (a.face_sizes.empty()) fail("the mesh has no faces");
    if (a.positions.empty()) fail("the mesh has no vertices");
    if (a.positions.size() % 3 != 0) fail("positions must hold 3 floats per vertex");
    if (a.corner_vertices.size() > kMaxMeshCorners)
        fail("the mesh has " + std::to_string(a.corner_vertices.size()) + " corners; at most " +
             std::to_string(kMaxMeshCorners) + " are supported");
    if (a.positions.size() / 3 >= 0xFFFFFFFFull) fail("the mesh has more vertices than 32-bit indices can address");

    MeshInput m;
    m.arrays_ = a;
    m.face_offsets_.resize(a.face_sizes.size());
    uint64_t offset = 0;
    size_t first_ngon = 0;
    for (size_t f = 0; f < a.face_sizes.size(); ++f) {
        const uint32_t n = a.face_sizes[f];
        if (n < 3) fail("face " + std::to_string(f) + " has " + std::to_string(n) + " corners; a face needs at least 3");
        if (n == 3) ++m.triangles_;
        else if (n == 4) ++m.quads_;
        else if (m.ngons_++ == 0) first_ngon = f;
        m.face_offsets_[f] = uint32_t(offset);
        offset += n;
        if (offset > a.corner_vertices.size()) break;
    }
    if (offset != a.corner_vertices.size())
        fail("face sizes add up to " + std::string(offset > a.corner_vertices.size() ? "more than " : "") +
             std::to_string(offset) + " corners but corner_vertices holds " + std::to_string(a.corner_vertices.size()));
    if (m.ngons_ > 0 && ngons == NgonPolicy::refuse)
        fail("face " + std::to_string(first_ngon) + " has " + std::to_string(a.face_sizes[first_ngon]) +
             " corners (" + std::to_string(m.ngons_) +
             " n-gons in all): tangent frames are defined for triangles and quads only, as in MikkTSpace and "
             "Blender's calc_tangents; triangulate the n-gons first (Blender: Triangulate modifier)");

    const size_t vertices = a.positions.size() / 3;
    const size_t corners = a.corner_vertices.size();
    uint32_t largest = 0;
    for (const uint32_t v : a.corner_vertices) largest = std::max(largest, v);
    if (largest >= vertices)
        for (size_t c = 0; c < corners; ++c)
            if (a.corner_vertices[c] >= vertices)
                fail("corner " + std::to_string(c) + " refers to vertex " + std::to_string(a.corner_vertices[c]) +
                     " but the mesh has " + std::to_string(vertices) + " vertices");

    const size_t normal_elements = a.normal_domain == AttributeDomain::corner ? corners : vertices;
    const size_t uv_elements = a.uv_domain == AttributeDomain::corner ? corners : vertices;
    const char* normal_element = a.normal_domain == AttributeDomain::corner ? "corner" : "vertex";
    const char* uv_element = a.uv_domain == AttributeDomain::corner ? "corner" : "vertex";
    if (a.normals.size() != normal_elements * 3)
        fail("normals hold " + std::to_string(a.normals.size()) + " floats; expected 3 per " + normal_element + " (" +
             std::to_string(normal_elements * 3) + ")");
    if (a.uvs.size() != uv_elements * 2)
        fail("uvs hold " + std::to_string(a.uvs.size()) + " floats; expected 2 per " + uv_element + " (" +
             std::to_string(uv_elements * 2) + ")");

    require_finite(a.positions, 3, "position", "vertex");
    require_finite(a.normals, 3, "normal", normal_element);
    require_finite(a.uvs, 2, "uv", uv_element);
    return m;
}

}  // namespace ndfbake
