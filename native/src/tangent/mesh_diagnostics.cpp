#include "tangent/mesh_diagnostics.h"

#include <algorithm>
#include <array>
#include <cstring>
#include <numeric>
#include <vector>

#include "tangent/triangulation.h"
#include "tangent/weld.h"

namespace ndfbake {

namespace {

struct DiagTriangle {
    uint32_t corner[3];
    uint32_t face;
};

std::vector<DiagTriangle> triangles_of(const MeshInput& mesh)
{
    std::vector<DiagTriangle> tris;
    tris.reserve(mesh.corner_count());
    for (uint32_t f = 0; f < mesh.face_count(); ++f) {
        const uint32_t o = mesh.face_offset(f), n = mesh.face_size(f);
        if (n == 4) {
            if (mikk_quad_splits_02(mesh, f)) {
                tris.push_back({{o, o + 1, o + 2}, f});
                tris.push_back({{o, o + 2, o + 3}, f});
            } else {
                tris.push_back({{o, o + 1, o + 3}, f});
                tris.push_back({{o + 1, o + 2, o + 3}, f});
            }
        } else {
            for (uint32_t k = 1; k + 1 < n; ++k) tris.push_back({{o, o + k, o + k + 1}, f});
        }
    }
    return tris;
}

uint32_t find_root(std::vector<uint32_t>& parent, uint32_t x)
{
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
}

}  // namespace

MeshReport diagnose_mesh(const MeshInput& mesh)
{
    MeshReport r;
    r.faces = mesh.face_count();
    r.triangles = mesh.triangle_faces();
    r.quads = mesh.quad_faces();
    r.ngons = mesh.ngon_faces();
    for (size_t f = 0; f < mesh.face_count() && r.ngon_first < 0; ++f)
        if (mesh.face_size(f) > 4) r.ngon_first = int64_t(f);

    // Inverted normals: the face's vector area against the sum of its corner normals.
    for (size_t f = 0; f < mesh.face_count(); ++f) {
        const uint32_t o = mesh.face_offset(f), n = mesh.face_size(f);
        Vec3 area, normals;
        const Vec3 p0 = mesh.position(o);
        for (uint32_t k = 1; k + 1 < n; ++k) area += cross(mesh.position(o + k) - p0, mesh.position(o + k + 1) - p0);
        for (uint32_t k = 0; k < n; ++k) normals += mesh.normal(o + k);
        if (dot(area, normals) < 0.0f && r.inverted_normal_faces++ == 0) r.inverted_normal_first = int64_t(f);
    }

    const std::vector<DiagTriangle> tris = triangles_of(mesh);
    std::vector<float> signed_area(tris.size());
    for (size_t t = 0; t < tris.size(); ++t) {
        const DiagTriangle& tri = tris[t];
        const Vec3 p0 = mesh.position(tri.corner[0]);
        const Vec3 world = cross(mesh.position(tri.corner[1]) - p0, mesh.position(tri.corner[2]) - p0);
        if (dot(world, world) == 0.0f && r.degenerate_triangles++ == 0) r.degenerate_first = tri.face;
        const Vec2 a = mesh.uv(tri.corner[0]), b = mesh.uv(tri.corner[1]), c = mesh.uv(tri.corner[2]);
        const float uv = (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x);
        signed_area[t] = mikk_not_zero(uv) ? uv : 0.0f;
        if (signed_area[t] == 0.0f && r.zero_area_uv_triangles++ == 0) r.zero_area_uv_first = tri.face;
    }

    // UV islands: corners keyed by (position bits, UV bits); triangles joined by edges whose ends
    // have equal keys. Sorting keeps this linear-ish even for millions of coincident vertices.
    const BigVector<uint32_t> classes = position_classes(mesh);
    const size_t corners = mesh.corner_count();
    std::vector<uint32_t> order(corners), corner_key(corners);
    std::iota(order.begin(), order.end(), 0u);
    auto key = [&](uint32_t c) {
        uint32_t uv[2];
        std::memcpy(uv, mesh.uv_ptr(c), sizeof uv);
        return std::array<uint32_t, 3>{classes[mesh.corner_vertex(c)], uv[0], uv[1]};
    };
    std::sort(order.begin(), order.end(), [&](uint32_t a, uint32_t b) { return key(a) < key(b); });
    for (size_t k = 0; k < corners; ++k)
        corner_key[order[k]] = (k > 0 && key(order[k]) == key(order[k - 1])) ? corner_key[order[k - 1]] : uint32_t(k);

    std::vector<std::pair<uint64_t, uint32_t>> edges;
    edges.reserve(tris.size() * 3);
    for (uint32_t t = 0; t < tris.size(); ++t)
        for (int i = 0; i < 3; ++i) {
            const uint64_t a = corner_key[tris[t].corner[i]], b = corner_key[tris[t].corner[(i + 1) % 3]];
            if (a != b) edges.push_back({(std::min(a, b) << 32) | std::max(a, b), t});
        }
    std::sort(edges.begin(), edges.end());
    std::vector<uint32_t> parent(tris.size());
    std::iota(parent.begin(), parent.end(), 0u);
    for (size_t k = 1; k < edges.size(); ++k)
        if (edges[k].first == edges[k - 1].first) {
            const uint32_t x = find_root(parent, edges[k].second), y = find_root(parent, edges[k - 1].second);
            if (x != y) parent[std::max(x, y)] = std::min(x, y);
        }

    struct Island {
        double positive = 0, negative = 0;
    };
    std::vector<Island> islands(tris.size());
    for (uint32_t t = 0; t < tris.size(); ++t) {
        Island& is = islands[find_root(parent, t)];
        if (signed_area[t] > 0) is.positive += signed_area[t];
        if (signed_area[t] < 0) is.negative -= signed_area[t];
    }
    for (uint32_t t = 0; t < tris.size(); ++t) {
        if (find_root(parent, t) != t) continue;
        ++r.uv_islands;
        const Island& is = islands[t];
        if (is.positive > 0 && is.negative > 0) ++r.flipped_islands;
        else if (is.negative > 0) ++r.mirrored_islands;
    }
    for (uint32_t t = 0; t < tris.size(); ++t) {
        const Island& is = islands[find_root(parent, t)];
        if (!(is.positive > 0 && is.negative > 0)) continue;
        const bool minority = is.positive >= is.negative ? signed_area[t] < 0 : signed_area[t] > 0;
        if (minority && r.flipped_triangles++ == 0) r.flipped_first = tris[t].face;
    }
    return r;
}

std::string describe(const MeshReport& r)
{
    auto first = [](int64_t f) { return f >= 0 ? " (first: face " + std::to_string(f) + ")" : std::string(); };
    std::string s = "faces: " + std::to_string(r.faces) + " (" + std::to_string(r.triangles) + " triangles, " +
                    std::to_string(r.quads) + " quads, " + std::to_string(r.ngons) + " n-gons); UV islands: " +
                    std::to_string(r.uv_islands) + "\n";
    bool clean = true;
    auto line = [&](uint64_t n, const std::string& text) {
        if (n == 0) return;
        clean = false;
        s += text + "\n";
    };
    line(r.ngons, "n-gons: " + std::to_string(r.ngons) + first(r.ngon_first) +
                      ": tangent frames need triangles and quads; triangulate them (Blender: Triangulate modifier)");
    line(r.degenerate_triangles, "degenerate triangles: " + std::to_string(r.degenerate_triangles) +
                                     first(r.degenerate_first) +
                                     ": no area, so no frame of their own; merge or dissolve them");
    line(r.zero_area_uv_triangles,
         "zero-area UV triangles: " + std::to_string(r.zero_area_uv_triangles) + first(r.zero_area_uv_first) +
             ": their UVs are collapsed, so they take a neighbour's frame and get no texels; unwrap them");
    line(r.flipped_islands, "flipped islands: " + std::to_string(r.flipped_islands) + " holding " +
                                std::to_string(r.flipped_triangles) + " triangles wound against the rest" +
                                first(r.flipped_first) +
                                ": the UVs fold over a shared edge, so the frames split inside the island and both "
                                "sides use the same texels; unfold them unless it is an intended mirror seam");
    line(r.inverted_normal_faces, "faces with inverted normals: " + std::to_string(r.inverted_normal_faces) +
                                      first(r.inverted_normal_first) +
                                      ": the normals point against the winding, so the bitangent flips there; "
                                      "recalculate normals outside");
    if (r.mirrored_islands > 0)
        s += "mirrored islands: " + std::to_string(r.mirrored_islands) +
             " (UVs run clockwise: bitangent sign -1, frames split at their border; fine for MikkTSpace)\n";
    if (clean) s += "no problems found\n";
    return s;
}

}  // namespace ndfbake
