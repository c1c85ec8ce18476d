// Groups (Mikkelsen §3.3): per welded vertex, the fan links across shared edges and the groups
// they make without crossing a mirror seam, each averaged into one frame and sign (evaluate_run);
// vertices whose fans hold group-with-any triangles replay the reference's sequential order
// (ordered_groups). Owns link_left_, link_right_, group_of_, affected_, first_good_, result_sign_,
// result_mags_ and the group count. May call: parallel_for.h, tangent_math.h.
#include <algorithm>
#include <atomic>
#include <vector>

#include "tangent/parallel_for.h"
#include "tangent/tangent_generator.h"

namespace ndfbake::tangent_generation {

// Calls fn(begin, end) for every welded vertex (a run of items with one weld id), in parallel,
// and adds up what it returns (groups made) into groups_, once per chunk: an atomic add per
// vertex costs as much as the vertex's own work. Each chunk gets its own copy of fn, so
// scratch state captured by value is per thread.
template <typename Fn>
void Generator::parallel_runs(const Fn& fn)
{
    const size_t n = item_weld_.size();
    auto aligned = [&](size_t k) {
        while (k > 0 && k < n && item_weld_[k] == item_weld_[k - 1]) ++k;
        return std::min(k, n);
    };
    parallel_for(n, threads_, 1 << 14, [&](size_t b, size_t e) {
        b = aligned(b), e = aligned(e);
        Fn body = fn;
        size_t begin = b;
        uint64_t made = 0;
        while (begin < e) {
            size_t end = begin + 1;
            while (end < e && item_weld_[end] == item_weld_[begin]) ++end;
            made += body(begin, end);
            begin = end;
        }
        groups_.fetch_add(made, std::memory_order_relaxed);
    });
}

// Accumulates the groups of one welded vertex (items [begin, end)) and writes its corners.
// slot_of(k) gives item k's group as an index in [0, groups), or kUnset.
template <typename SlotOf>
void Generator::evaluate_run(size_t begin, size_t end, SlotOf slot_of, size_t groups, std::vector<GroupSum>& sums)
{
    sums.assign(groups, GroupSum{});
    for (size_t k = begin; k < end; ++k) {
        const uint32_t g = slot_of(k);
        if (g == kUnset) continue;
        GroupSum& s = sums[g];
        s.preserving = (item_flags_[k] & kPreserving) != 0;
        if (item_flags_[k] & kGroupWithAny) continue;  // joins the group, adds nothing
        s.tangent += vec(contrib_[k]);
        if (!weight_.empty()) {
            const uint32_t t = fans_.items[k] / 3;
            const float w = weight_[k];
            s.weight += w;
            s.mag_s += w * frame_[t].mag_s;
            s.mag_t += w * frame_[t].mag_t;
            s.plain_s += frame_[t].mag_s;
            s.plain_t += frame_[t].mag_t;
        }
        ++s.members;
    }
    for (GroupSum& s : sums) {
        s.tangent = normalize_keep_zero(s.tangent);
        if (s.weight > 0.0f) {
            s.mag_s /= s.weight;
            s.mag_t /= s.weight;
        } else if (s.members > 0) {
            s.mag_s = s.plain_s / float(s.members);
            s.mag_t = s.plain_t / float(s.members);
        } else {
            s.mag_s = s.mag_t = 1.0f;
        }
    }
    // Results go out in item order (sequential writes); write_corners() moves them to the
    // corners in face order, which is far cheaper than scattering them from here.
    // The frame overwrites the item's contribution, which is no longer needed: one array less
    // to fault in and zero.
    for (size_t k = begin; k < end; ++k) {
        const uint32_t g = slot_of(k);
        if (g == kUnset) {
            result_sign_[k] = 0;
            continue;
        }
        const GroupSum& s = sums[g];
        contrib_[k] = flat(s.tangent);
        result_sign_[k] = s.preserving ? 1 : -1;
        if (!mags_.empty()) result_mags_[k] = {s.mag_s, s.mag_t};
    }
}

// Per welded vertex, in one pass over its items:
//  1. fan links. The half edges of an edge are paired as the reference does it: taken in (t, i)
//     order, each unpaired one pairs with the first later unpaired one running the other way
//     (which also settles non-manifold edges). Every half edge of an edge touches both its
//     ends, so each end finds the same pairs on its own, in its own items, and records only its
//     own links: left = across the edge leaving the vertex, right = across the edge arriving.
//  2. groups: each item has at most two links, so a group is a path or a cycle, found by
//     walking both ways; links between opposite orientations (a mirror seam) are not followed.
//     Such groups do not depend on visiting order, so vertices are done in parallel, except
//     those whose fan holds group-with-any triangles: there the reference's visiting order
//     decides, and ordered_groups() replays it.
void Generator::group_pass()
{
    // Fan links live in per-thread scratch and are copied out only for vertices that
    // ordered_groups() must revisit; untouched pages of these arrays are never faulted in.
    link_left_.resize(fans_.items.size());
    link_right_.resize(fans_.items.size());
    result_sign_.resize(fans_.items.size());
    if (!mags_.empty()) result_mags_.resize(fans_.items.size());
    if (stats_.degenerate_triangles > 0) first_good_.assign(mesh_.corner_count(), kUnset);
    affected_.assign(mesh_.corner_count(), 0);
    struct HalfEdge {
        uint32_t other;  // the far end's weld id
        uint32_t item;   // this vertex's item in the triangle
        bool incoming;
    };
    struct Scratch {
        std::vector<HalfEdge> edges;
        std::vector<uint32_t> slot, left, right;
        std::vector<GroupSum> sums;
    };
    parallel_runs([&, scratch = Scratch()](size_t begin, size_t end) mutable -> uint64_t {
        const uint32_t rep = item_weld_[begin];
        const size_t n = end - begin;
        bool affected = false, any_good = false;
        std::vector<HalfEdge>& edges = scratch.edges;
        std::vector<uint32_t>& left = scratch.left;    // local item indices
        std::vector<uint32_t>& right = scratch.right;
        edges.clear();
        left.assign(n, kUnset);
        right.assign(n, kUnset);
        for (size_t k = begin; k < end; ++k) {
            const uint8_t flags = item_flags_[k];
            if (flags & kDegenerate) {
                result_sign_[k] = 0;
                continue;
            }
            if (!any_good && !first_good_.empty()) first_good_[rep] = corner_of(fans_.items[k]);
            any_good = true;
            affected |= (flags & kGroupWithAny) != 0;
            const uint32_t local = uint32_t(k - begin);
            edges.push_back({item_next_[k], local, false});
            edges.push_back({item_prev_[k], local, true});
        }
        if (!any_good) return 0;
        // Items are in (t, i) order, so the list is too; a triangle cannot hold both half edges
        // of one edge (that needs two corners at one position, i.e. a degenerate triangle).
        for (size_t x = 0; x < edges.size(); ++x) {
            const HalfEdge& hx = edges[x];
            if ((hx.incoming ? right[hx.item] : left[hx.item]) != kUnset) continue;
            for (size_t y = x + 1; y < edges.size(); ++y) {
                const HalfEdge& hy = edges[y];
                if (hy.other != hx.other || hy.incoming == hx.incoming) continue;
                if ((hy.incoming ? right[hy.item] : left[hy.item]) != kUnset) continue;
                const HalfEdge& out = hx.incoming ? hy : hx;
                const HalfEdge& in = hx.incoming ? hx : hy;
                left[out.item] = in.item;
                right[in.item] = out.item;
                break;
            }
        }
        if (affected) {
            for (size_t m = 0; m < n; ++m) {
                link_left_[begin + m] = left[m] == kUnset ? kUnset : uint32_t(begin + left[m]);
                link_right_[begin + m] = right[m] == kUnset ? kUnset : uint32_t(begin + right[m]);
            }
            affected_[rep] = 1;
            any_affected_.store(true, std::memory_order_relaxed);
            return 0;
        }
        std::vector<uint32_t>& slot = scratch.slot;
        slot.assign(n, kUnset);
        uint32_t groups = 0;
        const uint8_t* flags = &item_flags_[begin];
        for (size_t m = 0; m < n; ++m) {
            if (slot[m] != kUnset || (flags[m] & kDegenerate)) continue;
            const uint32_t g = groups++;
            const uint8_t orient = flags[m] & kPreserving;
            slot[m] = g;
            for (const std::vector<uint32_t>* links : {&left, &right}) {
                uint32_t current = uint32_t(m);
                for (;;) {
                    current = (*links)[current];
                    if (current == kUnset) break;
                    if (slot[current] != kUnset || (flags[current] & kPreserving) != orient) break;
                    slot[current] = g;
                }
            }
        }
        evaluate_run(begin, end, [&](size_t k) { return slot[k - begin]; }, groups, scratch.sums);
        return groups;
    });
}

// The reference's sequential group building, restricted to welded vertices whose fans hold
// group-with-any triangles: seeds in (t, i) order, each walking its fan depth first, the edge
// leaving the vertex before the edge arriving. A group-with-any triangle takes the orientation
// of the first group that reaches it, which is the one order dependency MikkTSpace has;
// replaying the same order is the only way to give the same signs as Blender there.
void Generator::ordered_groups()
{
    group_of_.assign(fans_.items.size(), kUnset);  // per item
    std::vector<uint32_t> stack;                   // items to visit
    for (uint32_t t = 0; t < tris_.size(); ++t) {
        if (!good(t) || (flags_[t] & kGroupWithAny)) continue;
        for (uint32_t i = 0; i < 3; ++i) {
            const uint32_t seed = item_of_[t * 3 + i];
            if (!affected_[item_weld_[seed]] || group_of_[seed] != kUnset) continue;
            const bool orient = preserving(t);
            group_of_[seed] = seed;
            stack.assign({link_right_[seed], link_left_[seed]});
            while (!stack.empty()) {
                const uint32_t k = stack.back();
                stack.pop_back();
                if (k == kUnset || group_of_[k] != kUnset) continue;
                const uint32_t u = fans_.items[k] / 3;
                uint8_t& flags = flags_[u];
                if ((flags & kGroupWithAny) && !any_grouped(u))
                    flags = uint8_t((flags & ~kPreserving) | (orient ? kPreserving : 0));
                if (preserving(u) != orient) continue;
                group_of_[k] = seed;
                stack.push_back(link_right_[k]);
                stack.push_back(link_left_[k]);
            }
        }
    }
}

// ordered_groups() may have given group-with-any triangles a new orientation.
void Generator::refresh_item_flags()
{
    for (uint32_t t = 0; t < tris_.size(); ++t)
        if (flags_[t] & kGroupWithAny)
            for (uint32_t i = 0; i < 3; ++i) item_flags_[item_of_[t * 3 + i]] = flags_[t];
}

bool Generator::any_grouped(uint32_t t) const
{
    return group_of_[item_of_[t * 3]] != kUnset || group_of_[item_of_[t * 3 + 1]] != kUnset ||
           group_of_[item_of_[t * 3 + 2]] != kUnset;
}

void Generator::affected_pass()
{
    parallel_runs([&, sums = std::vector<GroupSum>(), ids = std::vector<uint32_t>()](
                      size_t begin, size_t end) mutable -> uint64_t {
        if (!affected_[item_weld_[begin]]) return 0;
        ids.clear();
        for (size_t k = begin; k < end; ++k) {
            const uint32_t g = group_of_[k];
            if (g != kUnset && std::find(ids.begin(), ids.end(), g) == ids.end()) ids.push_back(g);
        }
        evaluate_run(
            begin, end,
            [&](size_t k) {
                const uint32_t g = group_of_[k];
                return g == kUnset ? kUnset : uint32_t(std::find(ids.begin(), ids.end(), g) - ids.begin());
            },
            ids.size(), sums);
        return ids.size();
    });
}

}  // namespace ndfbake::tangent_generation
