// Welding by value: MikkTSpace treats two corners as one vertex when position, normal and UV are
// bitwise equal, whatever vertex indices the mesh gives them. These helpers find those classes
// without comparing every pair, so meshes with millions of coincident vertices stay linear.
#pragma once

#include <algorithm>
#include <cstdint>
#include <utility>
#include <vector>

#include "pyramid/parallel.h"
#include "tangent/big_vector.h"
#include "tangent/mesh_input.h"

namespace ndfbake {

// For every vertex, the smallest vertex index whose position has the same bits.
BigVector<uint32_t> position_classes(const MeshInput& mesh);

// Counting sort of `count` items by key in [0, key_range): offsets (key_range + 1 entries) and the
// items in key order, each key's items in increasing item order (the sort is stable). With
// threads != 1 the items are split into a few slices, each counted and scattered by one thread
// into its own part of every bucket, which keeps the order and needs no atomics.
struct Buckets {
    BigVector<uint32_t> offsets;
    BigVector<uint32_t> items;
};
template <typename KeyOf>
Buckets bucket_by_key(size_t count, size_t key_range, KeyOf key_of, int threads = 1)
{
    Buckets b;
    // One histogram per slice: keep them within ~256 MB of counters.
    const size_t budget = std::max<size_t>(1, (size_t(64) << 20) / std::max<size_t>(key_range, 1));
    const size_t slices = std::min({size_t(resolve_thread_count(threads)), budget, std::max<size_t>(1, count >> 16)});
    std::vector<BigVector<uint32_t>> cursor(slices);
    auto slice_range = [&](size_t s) { return std::pair(count * s / slices, count * (s + 1) / slices); };
    auto for_slices = [&](auto&& fn) {
        if (slices == 1) return fn(size_t(0));
        parallel_rows(int(slices), int(slices), [&](int s) { fn(size_t(s)); }, {});
    };
    for_slices([&](size_t s) {
        cursor[s].assign(key_range, 0);
        const auto [begin, end] = slice_range(s);
        for (size_t i = begin; i < end; ++i) ++cursor[s][size_t(key_of(i))];
    });
    b.offsets.resize(key_range + 1);
    uint32_t running = 0;
    for (size_t k = 0; k < key_range; ++k) {
        b.offsets[k] = running;
        for (size_t s = 0; s < slices; ++s) {
            const uint32_t n = cursor[s][k];
            cursor[s][k] = running;
            running += n;
        }
    }
    b.offsets[key_range] = running;
    b.items.resize(count);
    for_slices([&](size_t s) {
        const auto [begin, end] = slice_range(s);
        for (size_t i = begin; i < end; ++i) b.items[cursor[s][size_t(key_of(i))]++] = uint32_t(i);
    });
    return b;
}

}  // namespace ndfbake
