// Welding (Mikkelsen §3.3 rules 1-3): triangle corners bucketed by vertex position, then split
// by bitwise-equal normal and UV into welded vertices whose items are contiguous, in (t, i) order;
// and the copy of each item's triangle flags and neighbours into that fan order. Owns fans_,
// item_weld_, item_of_, weld_tc_, item_flags_, item_next_, item_prev_. May call: weld.h
// (position_classes, bucket_by_key), parallel_for.h, mesh_input.h.
#include <algorithm>
#include <cstring>
#include <vector>

#include "tangent/parallel_for.h"
#include "tangent/tangent_generator.h"

namespace ndfbake::tangent_generation {

// Triangle corners bucketed by the position class of their vertex, in (t, i) order.
void Generator::build_fans()
{
    const BigVector<uint32_t> classes = position_classes(mesh_);
    fans_ = bucket_by_key(
        tris_.size() * 3, mesh_.vertex_count(),
        [&](size_t tc) { return classes[mesh_.corner_vertex(corner_of(uint32_t(tc)))]; }, threads_);
}

bool Generator::same_attributes(uint32_t c, uint32_t d) const
{
    return std::memcmp(mesh_.normal_ptr(c), mesh_.normal_ptr(d), 3 * sizeof(float)) == 0 &&
           std::memcmp(mesh_.uv_ptr(c), mesh_.uv_ptr(d), 2 * sizeof(float)) == 0;
}

bool Generator::attributes_less(uint32_t c, uint32_t d) const
{
    uint32_t a[5], b[5];
    std::memcpy(a, mesh_.normal_ptr(c), 12);
    std::memcpy(a + 3, mesh_.uv_ptr(c), 8);
    std::memcpy(b, mesh_.normal_ptr(d), 12);
    std::memcpy(b + 3, mesh_.uv_ptr(d), 8);
    return std::lexicographical_compare(a, a + 5, b, b + 5);
}

// Within each position bucket: split by (normal, uv) bits, reorder so each welded vertex is a
// contiguous run in (t, i) order, and record for every item and triangle corner its weld id (the
// representative corner) and for every triangle corner its item.
void Generator::weld_pass()
{
    const size_t items = fans_.items.size();
    item_weld_.resize(items);
    item_of_.resize(items);
    weld_tc_.resize(items);
    parallel_for(mesh_.vertex_count(), threads_, 1 << 12, [&](size_t b, size_t e) {
        std::vector<uint32_t> reps, local, scratch;
        for (size_t k = b; k < e; ++k) {
            const size_t first = fans_.offsets[k];
            uint32_t* it = fans_.items.data() + first;
            const size_t n = fans_.offsets[k + 1] - first;
            if (n == 0) continue;
            auto record = [&](size_t j, uint32_t rep) {
                item_weld_[first + j] = rep;
                item_of_[it[j]] = uint32_t(first + j);
                weld_tc_[it[j]] = rep;
            };
            if (n > 48) {
                // Large buckets (coincident vertices by the thousand): sort instead of scanning.
                std::stable_sort(it, it + n, [&](uint32_t x, uint32_t y) {
                    return attributes_less(corner_of(x), corner_of(y));
                });
                uint32_t rep = corner_of(it[0]);
                for (size_t j = 0; j < n; ++j) {
                    const uint32_t c = corner_of(it[j]);
                    if (!same_attributes(c, rep)) rep = c;
                    record(j, rep);
                }
                continue;
            }
            reps.clear();
            local.resize(n);
            for (size_t j = 0; j < n; ++j) {
                const uint32_t c = corner_of(it[j]);
                size_t r = 0;
                while (r < reps.size() && !same_attributes(c, reps[r])) ++r;
                if (r == reps.size()) reps.push_back(c);
                local[j] = uint32_t(r);
            }
            if (reps.size() == 1) {
                for (size_t j = 0; j < n; ++j) record(j, reps[0]);
                continue;
            }
            scratch.assign(it, it + n);
            size_t w = 0;
            for (size_t r = 0; r < reps.size(); ++r)
                for (size_t j = 0; j < n; ++j)
                    if (local[j] == r) {
                        it[w] = scratch[j];
                        record(w++, reps[r]);
                    }
        }
    });
}

// What the per-vertex pass needs about each item's triangle, copied into fan order in one
// streaming pass over the triangles: reading it through the triangles from the fans would
// cost a cache miss per item.
void Generator::scatter_to_items()
{
    const size_t items = fans_.items.size();
    item_flags_.resize(items);
    item_next_.resize(items);
    item_prev_.resize(items);
    parallel_for(tris_.size(), threads_, 1 << 15, [&](size_t b, size_t e) {
        for (size_t t = b; t < e; ++t)
            for (size_t i = 0; i < 3; ++i) {
                const uint32_t k = item_of_[t * 3 + i];
                item_flags_[k] = flags_[t];
                item_next_[k] = weld_tc_[t * 3 + (i + 1) % 3];
                item_prev_[k] = weld_tc_[t * 3 + (i + 2) % 3];
            }
    });
}

}  // namespace ndfbake::tangent_generation
