#include "pyramid/alignment.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <optional>
#include <vector>

#include "error.h"

namespace ndfbake {

namespace {

// The alignment refinement is a short polish of an already converged fit.
constexpr int kAlignmentIterations = 4;

float slot_score(const VmfLobe& lobe, int slot, std::span<const VmfLobe> parent, std::span<const VmfLobe> left)
{
    float score = 0.0f;
    if (!parent.empty()) score += parent[size_t(slot)].alpha * dot(lobe.mu, parent[size_t(slot)].mu);
    if (!left.empty()) score += left[size_t(slot)].alpha * dot(lobe.mu, left[size_t(slot)].mu);
    return score;
}

// The E-step's argmax over one mixture for many normals: each slot's log_weighted_normalizer
// computed once (level 0 asks it of every fine normal).
class MostResponsibleSlot {
public:
    explicit MostResponsibleSlot(std::span<const VmfLobe> mixture) : mixture_(mixture.begin(), mixture.end())
    {
        for (const VmfLobe& lobe : mixture_) log_weight_.push_back(log_weighted_normalizer(lobe));
    }
    int operator()(const Vec3& n) const
    {
        int best_slot = 0;
        float best = -std::numeric_limits<float>::infinity();
        for (size_t s = 0; s < mixture_.size(); ++s) {
            if (!(mixture_[s].alpha > 0.0f)) continue;
            const float log_p = log_vmf_density(mixture_[s], n, log_weight_[s]);
            if (log_p > best) {
                best = log_p;
                best_slot = int(s);
            }
        }
        return best_slot;
    }

private:
    std::vector<VmfLobe> mixture_;
    std::vector<float> log_weight_;
};

}  // namespace

void assign_slots(std::span<const VmfLobe> lobes, std::span<const VmfLobe> parent,
                  std::span<const VmfLobe> left, std::span<int> slot_of_lobe)
{
    const int slots = int(std::max(parent.size(), left.size()));
    const int count = int(lobes.size());
    if (std::max(slots, count) > kMaxLobes)
        throw Error(Status::invalid_argument, "slot assignment takes at most " + std::to_string(kMaxLobes) + " lobes");
    // On the stack: alignment visits every texel of every level. Scores are computed once; the
    // greedy rounds only look them up.
    const int columns = std::max(slots, count);
    std::array<std::array<float, kMaxLobes>, kMaxLobes> scores;
    for (int i = 0; i < count; ++i)
        for (int s = 0; s < columns; ++s)
            scores[size_t(i)][size_t(s)] = s < slots ? slot_score(lobes[size_t(i)], s, parent, left) : -1e29f;
    std::array<bool, kMaxLobes> lobe_done{}, slot_used{};
    std::fill(slot_of_lobe.begin(), slot_of_lobe.end(), -1);
    for (int assigned = 0; assigned < count; ++assigned) {
        int best_lobe = -1, best_slot = -1;
        float best = -1e30f;
        for (int i = 0; i < count; ++i) {
            if (lobe_done[size_t(i)]) continue;
            for (int s = 0; s < columns; ++s) {
                if (slot_used[size_t(s)]) continue;
                const float score = scores[size_t(i)][size_t(s)];
                // Ties go to the heavier lobe and the lower slot: a deterministic order.
                if (score > best + 1e-7f ||
                    (score >= best - 1e-7f && best_lobe >= 0 && lobes[size_t(i)].alpha > lobes[size_t(best_lobe)].alpha)) {
                    best = score;
                    best_lobe = i;
                    best_slot = s;
                }
            }
        }
        lobe_done[size_t(best_lobe)] = true;
        slot_used[size_t(best_slot)] = true;
        slot_of_lobe[size_t(best_lobe)] = best_slot;
    }
}

void align_lobe_slots(LobePyramid& pyramid, const PyramidSettings& settings, const ProgressTick& tick)
{
    const int slots = pyramid.slots;
    const int top = pyramid.level_count() - 1;
    int rows_total = 0;
    for (int l = top - 1; l >= 0; --l) rows_total += pyramid.size(l).height;
    int rows_before = 0;

    EmSettings polish = settings.fit.em;
    polish.max_iterations = kAlignmentIterations;

    for (int l = top - 1; l >= 0; --l) {
        LobeLevel& level = pyramid.levels[size_t(l)];
        const int width = level.size.width;
        const int rows_here = level.size.height;
        parallel_rows(rows_here, settings.threads, [&](int y) {
            std::vector<VmfLobe> ancestor(static_cast<size_t>(slots));
            if (l == 0) {
                // Each level-0 texel joins the slot of the top level's most responsible lobe.
                std::optional<MostResponsibleSlot> slot_of_normal;
                int ancestor_x = -1;
                for (int x = 0; x < width; ++x) {
                    if (x >> top != ancestor_x) {
                        ancestor_x = x >> top;
                        pyramid.texel(top, ancestor_x, y >> top, ancestor);
                        slot_of_normal.emplace(ancestor);
                    }
                    const size_t t = size_t(y) * size_t(width) + size_t(x);
                    level.level0_slot[t] = uint8_t((*slot_of_normal)(pyramid.source.normals[t]));
                }
                return;
            }
            // Alignment visits every texel of every level: the parent and the left neighbour (already
            // aligned) are read where they are stored, and the texel is reordered in place.
            const LobeLevel& coarser = pyramid.levels[size_t(l) + 1];
            std::vector<WeightedNormal> samples;
            std::vector<VmfLobe> lobes;
            std::array<int, kMaxLobes> slot_of;
            for (int x = 0; x < width; ++x) {
                const size_t parent_texel = size_t(y / 2) * size_t(coarser.size.width) + size_t(x / 2);
                const std::span<const VmfLobe> parent(&coarser.lobes[parent_texel * size_t(slots)], size_t(slots));
                const size_t t = size_t(y) * size_t(width) + size_t(x);
                const std::span<VmfLobe> stored(&level.lobes[t * size_t(slots)], size_t(slots));
                const std::span<const VmfLobe> left =
                    x > 0 ? std::span<const VmfLobe>(stored.data() - slots, size_t(slots)) : std::span<const VmfLobe>();
                lobes.clear();
                for (const VmfLobe& lobe : stored)
                    if (lobe.alpha > 0.0f) lobes.push_back(lobe);
                assign_slots(lobes, parent, left, std::span(slot_of).first(lobes.size()));

                if (settings.alignment_strength > 0.0f && lobes.size() > 1) {
                    // eq. 23's pull for each lobe: C Σ_k α_jk μ_jk over the neighbours' slot.
                    std::vector<Vec3> pull(lobes.size());
                    for (size_t i = 0; i < lobes.size(); ++i) {
                        const size_t s = size_t(slot_of[i]);
                        Vec3 sum = parent[s].alpha * parent[s].mu;
                        if (!left.empty()) sum += left[s].alpha * left[s].mu;
                        pull[i] = settings.alignment_strength * sum;
                    }
                    gather_footprint(pyramid.source, l, x, y, pyramid.settings.wrap, samples);
                    std::vector<VmfLobe> polished = lobes;
                    fit_vmf_mixture(samples, polished, polish, pull);
                    // A pull that empties a lobe would change the budget's choice: keep the fit.
                    if (std::all_of(polished.begin(), polished.end(), [](const VmfLobe& l) { return l.alpha > 0.0f; }))
                        lobes = std::move(polished);
                }
                std::fill(stored.begin(), stored.end(), VmfLobe{});
                for (size_t i = 0; i < lobes.size(); ++i) stored[size_t(slot_of[i])] = lobes[i];
            }
        }, [&](double fraction) {
            return !tick || tick(rows_total > 0 ? (rows_before + fraction * rows_here) / rows_total : 1.0);
        });
        rows_before += rows_here;
    }
}

}  // namespace ndfbake
