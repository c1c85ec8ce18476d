// Linear vMF MIP-mapping with sphere partitions (Xu et al. 2017, §3.2 and §4).
//
// The sphere of normal directions is cut into J cells S⁽ʲ⁾. Per cell a texel stores
// (α_j, α_j r_j) = (Σ_{q∈S⁽ʲ⁾} w_q, Σ_{q∈S⁽ʲ⁾} w_q n_q) / Σ_q w_q: eq. 10 applied per cell, with the
// cell's weight w⁽ʲ⁾ of eq. 15 as α_j, in the layout of our lobe textures (R = α, GBA = α·r).
// Both are linear, so every level is a plain average of the fine texels. The shader evaluates
// eq. 15 with our base BRDFs: Σ_j α_j (f ⊗ γ_j)(ω·μ_j), μ_j = r_j/|r_j|, κ_j = Banerjee(|r_j|)
// (eq. 8), through the shared convolution rules (brdf.convolved).
//
// Cells. The paper names its levels 1×1, 1×4 and 2×4 "where x × y denotes the partitioning of
// longitude and latitude into x and y components" and gives no cell bounds. We use:
//   1×1  one cell (no partition): the single-vMF baseline in the lobe-texture layout;
//   1×4  four azimuthal sectors centred on +X, +Y, −X, −Y;
//   2×4  each sector split into a polar cap (θ < 45°) and a ring (θ ≥ 45°), cell = 2·sector + band,
//        so the 2×4 cells nest in the 1×4 ones (what Algorithm 1's refinement of each level-1
//        lobe into level-2 lobes needs).
// Sectors are centred on the tangent axes because authored normal maps align their features
// with U and V (grooves, threads, brushing): a sector boundary on an axis would cut each such
// lobe in two and put halves of two different lobes into one cell.
#pragma once

#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include "math/vmf.h"
#include "ndf/ndf_pyramid.h"

namespace ndfbake {

enum class XuPartition {
    whole,          // 1×1
    sectors,        // 1×4
    sectors_bands,  // 2×4
};

// α and α·r per cell.
inline constexpr int kXuFloatsPerCell = 4;

// The polar split of the 2×4 partition: cos 45°. The paper partitions the hemisphere of normals
// in latitude without stating where; equal latitude bands over the hemisphere θ ∈ [0°, 90°] put
// the split of two bands at 45°.
inline constexpr float kXuPolarSplitCos = 0.70710678f;

// Adaptive subdivision thresholds on the mean resultant length |r| (Xu et al. 2017, §4,
// Algorithm 1 lines 5 and 8, footnote ‡: "In practice, we pick ε0 = 0.95 and ε1 = 0.85"): a texel
// whose 1×1 |r| is below ε0 uses the 1×4 sectors, and a sector whose |r| is below ε1 uses its two
// 2×4 cells. The paper tests the |r| of vMF *BRDF* lobes; our r is the NDF's own (the base BRDF
// is convolved at shading), so a texel of aligned normals has |r| = 1 under any BRDF and rough
// materials no longer trigger needless subdivision (the limitation the paper notes in §5.3).
inline constexpr double kXuSubdivideWhole = 0.95;   // ε0
inline constexpr double kXuSubdivideSector = 0.85;  // ε1

int xu_cell_count(XuPartition partition);
// The cell a unit direction belongs to.
int xu_cell(XuPartition partition, const Vec3& n);

// The lobes of stored cells (α, α·r) × count; empty cells (α = 0) give none.
void xu_lobes(std::span<const float> cells, std::vector<VmfLobe>& out);

// Fixed partitions: 4 × xu_cell_count floats per texel.
std::unique_ptr<NdfPyramid> make_xu_pyramid(const NormalMap& map, WrapMode wrap, XuPartition partition);

// §4's adaptive choice per texel, storing only the cells its shader evaluates: the 1×1 cell when
// |r| ≥ ε0, otherwise per sector either the sector's cell (|r| ≥ ε1) or its two 2×4 cells, empty
// cells left out. A parent cell is the sum of its children, so storing the leaves loses nothing.
class XuAdaptivePyramid : public NdfPyramid {
public:
    std::string name() const override { return "xu-adaptive"; }
    int level_count() const override { return int(levels_.size()); }
    LevelSize size(int level) const override;
    // ⌈mean_floats_per_texel()⌉: the interface counts whole floats.
    int floats_per_texel() const override;
    // Floats stored over every texel of every level, divided by the texel count.
    double mean_floats_per_texel() const;
    void effective_brdf(int level, int x, int y, const BaseBrdf& brdf, std::span<const Vec3> directions,
                        std::span<float> out) const override;

    // The stored cells of a texel, kXuFloatsPerCell floats each.
    std::span<const float> texel(int level, int x, int y) const;

private:
    friend std::unique_ptr<NdfPyramid> make_xu_adaptive_pyramid(const NormalMap& map, WrapMode wrap);
    struct Level {
        LevelSize size;
        std::vector<uint32_t> begin;  // texel i's cells are cells[begin[i] .. begin[i + 1])
        std::vector<float> cells;
    };
    std::vector<Level> levels_;
};

std::unique_ptr<NdfPyramid> make_xu_adaptive_pyramid(const NormalMap& map, WrapMode wrap);

// The adaptive choice for one texel's 2×4 cells (8 × (α, α·r)): appends the chosen leaf cells.
void xu_adaptive_leaves(std::span<const double> cells_2x4, std::vector<float>& out);

}  // namespace ndfbake
