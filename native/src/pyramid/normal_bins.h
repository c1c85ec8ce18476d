// The sufficient statistics of a footprint for vMF EM, summed up the pyramid: the fine normals
// binned by direction, each bin keeping how many normals it holds and their vector sum.
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include "ndf/weighted_normal.h"
#include "pyramid/footprint.h"

namespace ndfbake {

// Bins per axis of the hemi-octahedral grid: 64² bins about 2° across. EM sees each bin as one
// sample at its mean resultant, so a bin's normals share one responsibility: bins must be narrower
// than the sharpest lobes (measured on the brushed pattern: 32² bins cost 10% error, 64² none).
inline constexpr int kNormalBinsPerAxis = 64;
inline constexpr int kNormalBinCount = kNormalBinsPerAxis * kNormalBinsPerAxis;
static_assert(kNormalBinCount % 64 == 0, "BinAccumulator keeps one occupancy bit per bin in 64-bit words");

struct NormalBin {
    uint32_t index;   // row-major cell of the hemi-octahedral grid
    float weight;     // fine normals in the bin (with footprint multiplicity)
    Vec3 sum;         // Σ weight · n over them
};

// The grid cell of a unit normal with z ≥ 0 (decoded normals are: see normal_decode.h).
uint32_t normal_bin_index(const Vec3& n);

// Sums one texel's normals or bins (its children's) into the grid, then lists its non-empty bins
// in index order. One per thread: it holds a dense grid.
class BinAccumulator {
public:
    BinAccumulator();
    void add(std::span<const WeightedNormal> normals);
    void add(std::span<const NormalBin> bins);
    // The texel's bins, valid until the next finish(); the accumulator starts over empty.
    std::span<const NormalBin> finish();

private:
    void add(uint32_t index, float weight, const Vec3& sum);
    std::vector<float> weight_;
    std::vector<Vec3> sum_;
    // Which bins hold normals, one bit each: finish() lists them in index order by scanning the
    // words, which costs less than sorting the touched indices (a third of the binning's time).
    std::array<uint64_t, kNormalBinCount / 64> occupied_{};
    std::vector<NormalBin> bins_;
};

// One level's bins, kept for the level above to sum: texel (x, y)'s bins are appended in order
// along row y, rows independently (so that rows may be filled on different threads).
class BinnedLevel {
public:
    BinnedLevel() = default;
    explicit BinnedLevel(LevelSize size);

    bool empty() const { return rows_.empty(); }
    LevelSize size() const { return size_; }
    void append_texel(int y, std::span<const NormalBin> bins);
    std::span<const NormalBin> texel(int x, int y) const;

private:
    struct Row {
        std::vector<uint32_t> offsets{0};  // texel x's bins are bins[offsets[x], offsets[x + 1])
        std::vector<NormalBin> bins;
    };
    LevelSize size_;
    std::vector<Row> rows_;
};

// The hierarchical fit fits a level from bins where its texels cover more fine normals than this
// (levels ≥ 4), and keeps them for the level above to sum. Smaller footprints are fitted from
// their fine normals, as the per-level fit does: 64 normals fill about as many bins, so binning
// them only costs time (measured on fbm 2048², one thread: levels 1–3 0.12 s faster, and level 2's
// error 0.0056 instead of 0.0062). Summing the children's bins from level 5 up, rather than
// binning the footprint's normals again, saves 0.11 s; it holds at most two levels' bins, at most
// one bin per fine normal each (bake/memory_budget.cpp counts them).
inline constexpr int kMinBinnedFootprint = 64;

// Whether the hierarchical fit fits (and keeps) bins at this level: see kMinBinnedFootprint.
bool binned_level(int level);

// Adds texel (x, y) of `level` to `bins`: its children's bins from `finer` where it holds them
// (not empty) and they cover the footprint, returning true; otherwise the footprint's fine normals,
// gathered into `gathered`, returning false. Children cover the footprint always when clamping
// (children past the edge cover nothing), and when wrapping unless a child would lie past the
// finer level's edge (its wrapped footprint is then no texel of that level).
bool accumulate_texel_bins(const NormalMap& map, const BinnedLevel& finer, int level, int x, int y, WrapMode wrap,
                           BinAccumulator& bins, std::vector<WeightedNormal>& gathered);

// The most samples EM gets per texel: a texel whose normals spread over more bins has them merged
// 2 × 2 into coarser cells until they fit. A wide NDF needs no 2° cells; a narrow one keeps them.
// Measured at 2048² against 256 (levels 4–6 then cost 0.04 s more on one thread): mean error over
// levels 1+ fbm 0.0873 / 0.0872, bumps 0.0566 / 0.0566, brushed 0.0365 / 0.0365, weave 0.1321 /
// 0.1323; FitAccuracy's 36 cases (Blinn-Phong 32 and 128) 0.1975 / 0.1982 of Toksvig's error.
inline constexpr int kMaxBinSamples = 128;
// ... and in a refined fit (PyramidSettings::refine), which starts its Levenberg-Marquardt steps
// from EM's fit and spends 100–300× the time anyway: there 256 cells keep level 4 at Blinn-Phong 128
// at 0.199 of Toksvig's error instead of 0.201.
inline constexpr int kRefinedBinSamples = 256;

// ... and runs at most this many EM iterations on them (or fewer, as EmSettings::max_iterations
// says). Measured at 2048², mean error over levels 1+ against 10 iterations: fbm 0.0839 / 0.0856,
// weave 0.1294 / 0.1292, brushed 0.0369 / 0.0355, for 0.12 s less fitting on one thread.
inline constexpr int kBinnedIterations = 5;

// The samples EM fits to: each bin (or merged cell, at most max_samples of them) as its mean
// resultant (|n| ≤ 1) weighted by its count.
void bin_samples(std::span<const NormalBin> bins, int max_samples, std::vector<WeightedNormal>& out);

}  // namespace ndfbake
