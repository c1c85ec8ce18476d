#include "tangent/vertex_split.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <numeric>
#include <vector>

#include "error.h"
#include "tangent/parallel_for.h"
#include "tangent/weld.h"

namespace ndfbake {

namespace {

// Everything that must agree for two corners to share a vertex. Compared with float ==, so +0 and
// -0 agree (the same frame) while any real difference splits.
struct CornerKey {
    std::array<float, 2> uv;
    std::array<float, 3> normal;
    float sign;
    std::array<float, 3> tangent;

    bool operator==(const CornerKey&) const = default;
    bool operator<(const CornerKey& o) const
    {
        if (uv != o.uv) return uv < o.uv;
        if (normal != o.normal) return normal < o.normal;
        if (sign != o.sign) return sign < o.sign;
        return tangent < o.tangent;
    }
};

CornerKey key_of(const MeshInput& mesh, std::span<const float> tangents, size_t c)
{
    const Vec2 uv = mesh.uv(c);
    const Vec3 n = mesh.normal(c);
    const float* t = &tangents[4 * c];
    return {{uv.x, uv.y}, {n.x, n.y, n.z}, t[3], {t[0], t[1], t[2]}};
}

enum Reason { uv_seam, hard_edge, mirror_seam, tangent_split };

Reason reason(const CornerKey& first, const CornerKey& other)
{
    if (first.uv != other.uv) return uv_seam;
    if (first.normal != other.normal) return hard_edge;
    if (first.sign != other.sign) return mirror_seam;
    return tangent_split;
}

}  // namespace

SplitStats split_vertices(const MeshInput& mesh, std::span<const float> tangents, int threads,
                          std::span<uint32_t> corner_to_vertex, std::span<uint32_t> vertex_source)
{
    const size_t corners = mesh.corner_count(), vertices = mesh.vertex_count();
    if (tangents.size() != corners * 4 || corner_to_vertex.size() != corners || vertex_source.size() < corners)
        throw Error(Status::invalid_argument, "split_vertices: array sizes do not match the mesh");
    const Buckets by_vertex = bucket_by_key(corners, vertices, [&](size_t c) { return mesh.corner_vertex(c); });

    // Pass 1: distinct keys per vertex (their local index goes to corner_to_vertex for now).
    std::vector<uint32_t> copies(vertices + 1, 0);
    std::array<std::atomic<uint64_t>, 4> reasons{};
    parallel_for(vertices, threads, 1 << 12, [&](size_t b, size_t e) {
        std::array<uint64_t, 4> local_reasons{};
        std::vector<CornerKey> keys;
        std::vector<uint32_t> order;
        for (size_t v = b; v < e; ++v) {
            const uint32_t* items = by_vertex.items.data() + by_vertex.offsets[v];
            const size_t n = by_vertex.offsets[v + 1] - by_vertex.offsets[v];
            if (n == 0) continue;
            keys.clear();
            if (n <= 48) {
                for (size_t j = 0; j < n; ++j) {
                    const CornerKey k = key_of(mesh, tangents, items[j]);
                    size_t r = 0;
                    while (r < keys.size() && !(keys[r] == k)) ++r;
                    if (r == keys.size()) keys.push_back(k);
                    corner_to_vertex[items[j]] = uint32_t(r);
                }
            } else {
                // Vertices with very many corners: sort by key, then number the distinct keys by
                // their first corner so the numbering matches the small-vertex path.
                order.resize(n);
                std::iota(order.begin(), order.end(), 0u);
                std::vector<CornerKey> all(n);
                for (size_t j = 0; j < n; ++j) all[j] = key_of(mesh, tangents, items[j]);
                std::stable_sort(order.begin(), order.end(), [&](uint32_t x, uint32_t y) { return all[x] < all[y]; });
                // Runs of equal keys; the stable sort puts each run's first corner at its start.
                std::vector<uint32_t> run_of(n), run_first;
                for (size_t j = 0; j < n; ++j) {
                    if (j == 0 || !(all[order[j]] == all[order[j - 1]])) run_first.push_back(order[j]);
                    run_of[j] = uint32_t(run_first.size() - 1);
                }
                std::vector<uint32_t> by_first(run_first.size()), rank(run_first.size());
                std::iota(by_first.begin(), by_first.end(), 0u);
                std::sort(by_first.begin(), by_first.end(),
                          [&](uint32_t x, uint32_t y) { return run_first[x] < run_first[y]; });
                for (size_t r = 0; r < by_first.size(); ++r) {
                    rank[by_first[r]] = uint32_t(r);
                    keys.push_back(all[run_first[by_first[r]]]);
                }
                for (size_t j = 0; j < n; ++j) corner_to_vertex[items[order[j]]] = rank[run_of[j]];
            }
            copies[v + 1] = uint32_t(keys.size());
            for (size_t r = 1; r < keys.size(); ++r) ++local_reasons[reason(keys[0], keys[r])];
        }
        for (int r = 0; r < 4; ++r) reasons[r] += local_reasons[r];
    });

    SplitStats stats;
    for (size_t v = 0; v < vertices; ++v) {
        if (copies[v + 1] > 0) ++stats.input_vertices;
        copies[v + 1] += copies[v];
    }
    stats.output_vertices = copies[vertices];
    stats.uv_seams = reasons[uv_seam];
    stats.hard_edges = reasons[hard_edge];
    stats.mirror_seams = reasons[mirror_seam];
    stats.tangent_splits = reasons[tangent_split];

    // Pass 2: local indices become output indices.
    parallel_for(vertices, threads, 1 << 12, [&](size_t b, size_t e) {
        for (size_t v = b; v < e; ++v) {
            const uint32_t base = copies[v];
            for (uint32_t j = by_vertex.offsets[v]; j < by_vertex.offsets[v + 1]; ++j)
                corner_to_vertex[by_vertex.items[j]] += base;
            for (uint32_t o = base; o < copies[v + 1]; ++o) vertex_source[o] = uint32_t(v);
        }
    });
    return stats;
}

}  // namespace ndfbake
