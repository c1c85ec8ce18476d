// The MikkTSpace generator's shared state, private to native/src/tangent/: one Generator runs the
// passes of generate_tangent_frames (tangent_space.h) over one mesh. This header owns the pass
// order's data (per-triangle flags and frames, welded "items", fan links, per-item results) and
// declares the passes; their definitions live in one file per idea:
//   tangent_space.cpp     the entry point and the pass order (run)
//   tangent_welding.cpp   welding corners into fans, and copying triangle data into fan order
//   triangle_tangents.cpp per-triangle derivatives, orientation, corner-angle contributions, quads
//   tangent_groups.cpp    fan links, groups (parallel, and the reference's ordered replay), sums
//   corner_output.cpp     writing frames to corners, defaults, degenerate-triangle copies
// It may call: the tangent module's helpers (mesh_input, triangulation, weld, big_vector,
// parallel_for, tangent_math) and math/vec3.h. Nothing outside src/tangent/ includes it.
#pragma once

#include <array>
#include <atomic>
#include <cstdint>
#include <span>
#include <vector>

#include "tangent/big_vector.h"
#include "tangent/mesh_input.h"
#include "tangent/tangent_math.h"
#include "tangent/tangent_space.h"
#include "tangent/triangulation.h"
#include "tangent/weld.h"

namespace ndfbake::tangent_generation {

constexpr uint32_t kUnset = 0xffffffffu;

enum : uint8_t {
    kDegenerate = 1,    // two corners share a position: removed before grouping
    kGroupWithAny = 2,  // no usable UV derivative: joins the first group that reaches it
    kPreserving = 4,    // UV area > 0: orientation preserving (bitangent sign +1)
    kQuadOneDegen = 8,  // half of a quad whose other half is degenerate
};

// Plain structs (no initializers) so that big arrays of them are not zeroed before being written.
struct Float3 {
    float x, y, z;
};
struct TriangleFrame {
    Float3 tangent;  // normalized dP/du, sign-corrected; zero when it has no direction
    float mag_s;     // |dP/du|, |dP/dv|
    float mag_t;
};
inline Vec3 vec(const Float3& f) { return {f.x, f.y, f.z}; }
inline Float3 flat(const Vec3& v) { return {v.x, v.y, v.z}; }

inline bool same_position(const Vec3& a, const Vec3& b) { return a.x == b.x && a.y == b.y && a.z == b.z; }

// Triangle corners are numbered t*3+i ("tc"); half edge t*3+i runs from corner i to corner i+1.
// After welding, every triangle corner is an "item" in fan order: the items of one welded vertex
// (its fan) are contiguous and in (t, i) order, so the per-vertex passes stream through memory.
class Generator {
public:
    Generator(const MeshInput& mesh, int threads, std::span<float> tangents, std::span<float> magnitudes)
        : mesh_(mesh), threads_(threads), out_(tangents), mags_(magnitudes)
    {
    }

    TangentStats run();  // tangent_space.cpp

private:
    // ---- welding (tangent_welding.cpp) ----------------------------------------------------------
    uint32_t corner_of(uint32_t tc) const { return tris_[tc / 3].corner[tc % 3]; }
    void build_fans();
    bool same_attributes(uint32_t c, uint32_t d) const;
    bool attributes_less(uint32_t c, uint32_t d) const;
    void weld_pass();
    void scatter_to_items();

    // ---- per triangle (triangle_tangents.cpp) ---------------------------------------------------
    bool good(uint32_t t) const { return (flags_[t] & kDegenerate) == 0; }
    bool preserving(uint32_t t) const { return (flags_[t] & kPreserving) != 0; }
    void triangle_pass();
    void corner_contributions(size_t t, const std::array<Vec3, 3>& p, const Vec3& tangent);
    void quad_pass();
    float uv_area(size_t t) const;

    // ---- fans and groups (tangent_groups.cpp) ---------------------------------------------------
    struct GroupSum {
        Vec3 tangent;
        float weight = 0.0f, mag_s = 0.0f, mag_t = 0.0f, plain_s = 0.0f, plain_t = 0.0f;
        uint32_t members = 0;
        bool preserving = false;
    };
    template <typename Fn>
    void parallel_runs(const Fn& fn);
    template <typename SlotOf>
    void evaluate_run(size_t begin, size_t end, SlotOf slot_of, size_t groups, std::vector<GroupSum>& sums);
    void group_pass();
    void ordered_groups();
    void refresh_item_flags();
    bool any_grouped(uint32_t t) const;
    void affected_pass();

    // ---- output (corner_output.cpp) -------------------------------------------------------------
    void fill_defaults();
    void write_corners();
    size_t tri_of_face(size_t f) const;
    void copy_corner(uint32_t dst, uint32_t src);
    void degenerate_epilogue();

    const MeshInput& mesh_;
    int threads_;
    std::span<float> out_, mags_;
    TangentStats stats_;
    BigVector<MeshTriangle> tris_;
    BigVector<uint8_t> flags_;          // per triangle
    BigVector<TriangleFrame> frame_;    // per triangle
    Buckets fans_;                      // items: triangle corners in fan order
    BigVector<uint32_t> item_weld_;     // per item: its weld id
    BigVector<uint8_t> item_flags_;     // per item: its triangle's flags
    BigVector<uint32_t> item_next_, item_prev_;  // per item: weld ids of the triangle's next/previous corner
    BigVector<uint32_t> item_of_, weld_tc_;        // per triangle corner
    BigVector<uint32_t> link_left_, link_right_;  // per item: fan neighbour items (kUnset: none)
    BigVector<Float3> contrib_;         // per item: weighted, projected tangent, then its frame
    BigVector<float> weight_;           // per item: corner angle (only for magnitudes)
    BigVector<uint32_t> first_good_, group_of_;
    BigVector<uint8_t> affected_;        // per weld id: its fan holds group-with-any triangles
    struct ItemMags {
        float s, t;
    };
    BigVector<int8_t> result_sign_;     // per item: its group's sign, 0 if no group reached it
    BigVector<ItemMags> result_mags_;   // per item: its group's magnitudes (only when asked)
    std::atomic<bool> any_affected_{false};
    std::atomic<uint64_t> groups_{0};
};

}  // namespace ndfbake::tangent_generation
