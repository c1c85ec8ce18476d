// The vMF lobes of every texel of every MIP level of a normal map.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "math/brdf.h"
#include "ndf/texel_fit.h"
#include "normal_map.h"
#include "pyramid/footprint.h"
#include "pyramid/parallel.h"
#include "pyramid/unfilled_vector.h"

namespace ndfbake {

enum class FitMethod {
    // Every level from all the fine normals it covers (§7.1): the reference the hierarchical fit
    // is measured against (examples/speed_ratios.sh).
    per_level,
    // Every level from the sufficient statistics of the level below: each texel's normals binned
    // by direction (pyramid/normal_bins.h), a texel's bins the sum of its children's, and EM run
    // on the bins. EM sees at most kMaxBinSamples samples per texel whatever its footprint
    // (kRefinedBinSamples in a refined fit), so the levels above 4 cost a fraction of a
    // per-level fit's.
    hierarchical,
};

// How the hierarchical fit fits a texel, by how many fine normals its footprint holds (the levels
// named are a square map's at 4 lobes or more). Up to
// kKmeansFootprint (levels 2–3: 330,000 of a 2048² map's 1.4 million fitted texels): one step of
// spherical k-means from the children's lobes (each normal joins the nearest seed, each lobe is
// its normals' vMF); there the seeds sit on the texel's few normals (at level 2 they are the fine
// normals) and EM's responsibilities would be nearly 0 or 1. Up to kOneStartFootprint (levels
// 4–5): EM from the children's lobes alone, at most kOneStartIterations iterations. Above: EM
// from the children's lobes and from the farthest samples, the likelier kept
// (TexelFitSettings::two_starts), at most kBinnedIterations iterations. Measured at 2048², one
// thread, against three EM iterations at levels 2–3 and two starts of five above: fbm fits in
// 0.91 s instead of 1.62 s (per-level EM: 4.71 s) at a mean error over levels 1+ (GGX 0.5) of
// 0.0872 instead of 0.0836 (per-level EM: 0.1029); bumps 0.0566 / 0.0556 (0.0537), brushed
// 0.0365 / 0.0363 (0.0369), weave 0.1323 / 0.1294 (0.1320). Over FitAccuracy's 36 cases
// (Blinn-Phong 32 and 128, where the lobes' shapes matter more) 0.1982 of Toksvig's error instead
// of 0.1963. More k-means steps buy little: two give fbm 0.0864 and 0.1973 there, in 0.07 s more;
// one EM start above level 5 costs brushed a fifth (0.0434), and k-means at level 4 FitAccuracy
// a sixth (0.2304). A refined fit (PyramidSettings::refine) fits every texel as the levels above
// 5: it spends 100–300× the time on lobes for one BRDF, and its Levenberg-Marquardt steps end nearer
// the optimum from EM's full fit (level 4 at Blinn-Phong 128: 0.218 of Toksvig's error from the
// shortcuts, 0.195 from EM's).
inline constexpr uint64_t kKmeansFootprint = 64;
inline constexpr int kKmeansSteps = 1;
inline constexpr uint64_t kOneStartFootprint = 1024;
inline constexpr int kOneStartIterations = 3;

struct PyramidSettings {
    FitMethod method = FitMethod::hierarchical;
    TexelFitSettings fit;
    BaseBrdf brdf = BaseBrdf::ggx(0.5f);
    WrapMode wrap = WrapMode::wrap;
    // Aligned lobes (eq. 23): slot j of neighbouring texels and levels point the same way.
    bool align = true;
    // C in eq. 23. Off by default: slot alignment alone costs no fit error, while the pull moves
    // sharp lobes off their normals (measured: at C = 0.05 level-1 error of fbm under Blinn-Phong
    // 128 grows from 0.007 to 0.044).
    float alignment_strength = 0.0f;
    int threads = 0;                   // 0: all cores
    // The lobe budget scores candidates on a reduced problem: at most this many directions and
    // fine normals per texel (subsample_footprint). Reported errors use the full problem.
    int budget_directions = 256;
    int budget_sample_cap = 256;
    // Refine every texel's lobes against the effective BRDF of `brdf` (ndf/brdf_refinement.h)
    // after EM. Measured: at Blinn-Phong 128 on the six synthetic patterns, 4 lobes' mean error at
    // levels 4 and 6 falls by a quarter (0.26 → 0.20 of Toksvig's); on a 1024² fBm map at GGX
    // roughness 0.3, the mean over levels 1+ from 0.250 to 0.201 (the fit then 0.16 s → 23 s on
    // 2 cores, 2026-11-26; docs/fit.md). `ndfbake bench`: 60–350× the default fit's time (which takes
    // shortcuts a refined fit does not: kKmeansFootprint). The refinement sees the texel's fine
    // normals, at most kRefineSampleCap of them.
    bool refine = false;
    // The most memory a fit or bake may use (bake/memory_budget.h); 0: physical memory.
    uint64_t max_memory_bytes = 0;
    // Levels fitted, from level 0 up; 0: every level down to 1×1 (pyramid_level_count()).
    int max_levels = 0;
};

// What build_lobe_pyramid fits the texels of `level` with: settings.fit, with the hierarchical
// fit's iteration caps and shortcuts for the level's footprint (largest_footprint(w, h, level),
// which build_lobe_pyramid also seeds EM by).
TexelFitSettings level_fit_settings(const PyramidSettings& settings, int level, uint64_t footprint);

// The levels a pyramid of a width × height map has under `settings`.
int pyramid_level_count(int width, int height, const PyramidSettings& settings);

struct LobeLevel {
    LevelSize size;
    // size.width × size.height texels × slots lobes; α = 0 marks an empty slot. Empty at level 0,
    // whose texels are the source normals themselves (one lobe of κ = kKappaMax each). Unfilled
    // when allocated: the fit writes every slot of every texel, on the thread that fits its row
    // (filled up front on one thread, a 2048² map's 80 MB of level 1 took a tenth of a 2-thread fit).
    UnfilledVector<VmfLobe> lobes;
    std::vector<uint8_t> level0_slot;  // level 0 only: the slot its one lobe occupies
    std::vector<float> budget_error;   // per texel; −1 where the budget did not measure
};

class LobePyramid {
public:
    NormalMap source;
    PyramidSettings settings;  // what it was fitted with (wrap mode included): its files and report say so
    int slots = 0;             // lobe slots per texel: settings.fit.max_lobes clamped to 1..kMaxLobes
    std::vector<LobeLevel> levels;

    int level_count() const { return int(levels.size()); }
    LevelSize size(int level) const { return levels[size_t(level)].size; }
    // The `slots` lobes of a texel, empty slots with α = 0.
    void texel(int level, int x, int y, std::span<VmfLobe> out) const;
    // The non-empty lobes of a texel.
    std::vector<VmfLobe> texel_lobes(int level, int x, int y) const;
    int lobe_count(int level, int x, int y) const;
    // Whether any texel of any level has a lobe in slot j: an unused slot's textures are zero
    // everywhere, and a shader can leave it out.
    std::vector<bool> slots_used() const;
};

// Fits every level ≥ 1 (from its fine normals or its bins, as settings.method says), seeded from
// the level below, then aligns lobe slots from the top level down. `tick` gets the overall
// fraction done and may cancel (Error(cancelled)).
LobePyramid build_lobe_pyramid(const NormalMap& map, const PyramidSettings& settings,
                               const ProgressTick& tick);

}  // namespace ndfbake
