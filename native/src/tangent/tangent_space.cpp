#include "tangent/tangent_space.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <cstring>
#include <string>
#include <utility>
#include <vector>

#include "error.h"
#include "tangent/big_vector.h"
#include "tangent/parallel_for.h"
#include "tangent/triangulation.h"
#include "tangent/weld.h"

namespace ndfbake {

namespace {

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

// Signed UV area times two, written exactly as the reference computes it: the orientation of
// near-zero triangles then rounds the same way, which is what makes signs match bit for bit.
float signed_uv_area(const Vec2& t1, const Vec2& t2, const Vec2& t3)
{
    const float t21x = t2.x - t1.x, t21y = t2.y - t1.y, t31x = t3.x - t1.x, t31y = t3.y - t1.y;
    return t21x * t31y - t21y * t31x;
}

// Past this, |dP/du| (world length per UV unit) is capped: a finite float for any input, whose
// group averages (at most π per corner angle times the corners of a group) stay finite too.
constexpr double kMaxDerivativeLength = 1e30;

// |dP/du| and |dP/dv| of a triangle (eqs. 42/43 over the UV area), in double: products of float
// coordinates near their range overflow float (found by fuzz_tangent). Only the magnitudes take
// this path; the tangent's direction stays in float, bit for bit as the reference computes it.
std::pair<float, float> derivative_lengths(const Vec3& v1, const Vec3& v2, const Vec3& v3, const Vec2& t1,
                                           const Vec2& t2, const Vec2& t3)
{
    const double t21x = double(t2.x) - t1.x, t21y = double(t2.y) - t1.y;
    const double t31x = double(t3.x) - t1.x, t31y = double(t3.y) - t1.y;
    const double area = std::fabs(t21x * t31y - t21y * t31x);
    double os_squared = 0.0, ot_squared = 0.0;
    for (int k = 0; k < 3; ++k) {
        const double d1 = double(v2[k]) - v1[k], d2 = double(v3[k]) - v1[k];
        const double os = d1 * t31y - d2 * t21y, ot = -d1 * t31x + d2 * t21x;
        os_squared += os * os;
        ot_squared += ot * ot;
    }
    auto length = [&](double squared) {
        const double value = std::sqrt(squared) / area;
        return float(value < kMaxDerivativeLength ? value : kMaxDerivativeLength);  // NaN (0/0) too
    };
    return {length(os_squared), length(ot_squared)};
}

bool same_position(const Vec3& a, const Vec3& b) { return a.x == b.x && a.y == b.y && a.z == b.z; }

// Triangle corners are numbered t*3+i ("tc"); half edge t*3+i runs from corner i to corner i+1.
// After welding, every triangle corner is an "item" in fan order: the items of one welded vertex
// (its fan) are contiguous and in (t, i) order, so the per-vertex passes stream through memory.
class Generator {
public:
    Generator(const MeshInput& mesh, int threads, std::span<float> tangents, std::span<float> magnitudes)
        : mesh_(mesh), threads_(threads), out_(tangents), mags_(magnitudes)
    {
    }

    TangentStats run()
    {
        tris_ = mikk_triangles(mesh_, threads_);
        stats_.triangles = tris_.size();
        if (tris_.empty()) {
            fill_defaults();
            return stats_;
        }
        build_fans();
        weld_pass();
        triangle_pass();
        quad_pass();
        scatter_to_items();
        group_pass();
        if (any_affected_.load()) {
            ordered_groups();
            refresh_item_flags();
            affected_pass();
        }
        write_corners();
        if (stats_.degenerate_triangles > 0) degenerate_epilogue();
        stats_.groups = groups_.load();
        return stats_;
    }

private:
    // MikkTSpace's frame for corners no group reached: (1, 0, 0), sign -1.
    void fill_defaults()
    {
        parallel_for(mesh_.corner_count(), threads_, 1 << 16, [&](size_t b, size_t e) {
            for (size_t c = b; c < e; ++c) {
                float* t = &out_[4 * c];
                t[0] = 1.0f, t[1] = 0.0f, t[2] = 0.0f, t[3] = -1.0f;
                if (!mags_.empty()) mags_[2 * c] = mags_[2 * c + 1] = 1.0f;
            }
        });
    }

    // ---- welding ------------------------------------------------------------------------------
    uint32_t corner_of(uint32_t tc) const { return tris_[tc / 3].corner[tc % 3]; }

    // Triangle corners bucketed by the position class of their vertex, in (t, i) order.
    void build_fans()
    {
        const BigVector<uint32_t> classes = position_classes(mesh_);
        fans_ = bucket_by_key(
            tris_.size() * 3, mesh_.vertex_count(),
            [&](size_t tc) { return classes[mesh_.corner_vertex(corner_of(uint32_t(tc)))]; }, threads_);
    }

    bool same_attributes(uint32_t c, uint32_t d) const
    {
        return std::memcmp(mesh_.normal_ptr(c), mesh_.normal_ptr(d), 3 * sizeof(float)) == 0 &&
               std::memcmp(mesh_.uv_ptr(c), mesh_.uv_ptr(d), 2 * sizeof(float)) == 0;
    }
    bool attributes_less(uint32_t c, uint32_t d) const
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
    void weld_pass()
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

    // Calls fn(begin, end) for every welded vertex (a run of items with one weld id), in parallel,
    // and adds up what it returns (groups made) into groups_, once per chunk: an atomic add per
    // vertex costs as much as the vertex's own work. Each chunk gets its own copy of fn, so
    // scratch state captured by value is per thread.
    template <typename Fn>
    void parallel_runs(const Fn& fn)
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

    // ---- per triangle -------------------------------------------------------------------------
    bool good(uint32_t t) const { return (flags_[t] & kDegenerate) == 0; }
    bool preserving(uint32_t t) const { return (flags_[t] & kPreserving) != 0; }

    void triangle_pass()
    {
        flags_.resize(tris_.size());
        if (!mags_.empty()) frame_.resize(tris_.size());
        contrib_.resize(tris_.size() * 3);
        if (!mags_.empty()) weight_.resize(tris_.size() * 3);
        std::atomic<uint64_t> degenerate{0}, with_any{0};
        parallel_for(tris_.size(), threads_, 1 << 14, [&](size_t b, size_t e) {
            uint64_t local_degenerate = 0, local_any = 0;
            for (size_t t = b; t < e; ++t) {
                const MeshTriangle& tri = tris_[t];
                const Vec3 v1 = mesh_.position(tri.corner[0]), v2 = mesh_.position(tri.corner[1]),
                           v3 = mesh_.position(tri.corner[2]);
                if (same_position(v1, v2) || same_position(v1, v3) || same_position(v2, v3)) {
                    flags_[t] = kDegenerate;
                    ++local_degenerate;
                    continue;
                }
                const Vec2 t1 = mesh_.uv(tri.corner[0]), t2 = mesh_.uv(tri.corner[1]), t3 = mesh_.uv(tri.corner[2]);
                const float t21x = t2.x - t1.x, t21y = t2.y - t1.y, t31x = t3.x - t1.x, t31y = t3.y - t1.y;
                const Vec3 d1 = v2 - v1, d2 = v3 - v1;
                const float area = signed_uv_area(t1, t2, t3);
                // Numerators of eqs. 42/43; dividing by the UV area gives dP/du and dP/dv.
                const Vec3 os = d1 * t31y - d2 * t21y;
                const Vec3 ot = d1 * (-t31x) + d2 * t21x;
                uint8_t flags = area > 0.0f ? kPreserving : 0;
                bool is_good = false;
                Vec3 tangent;
                if (mikk_not_zero(area)) {
                    const float len_s2 = os.x * os.x + os.y * os.y + os.z * os.z;
                    const float len_t2 = ot.x * ot.x + ot.y * ot.y + ot.z * ot.z;
                    const float sign = (flags & kPreserving) ? 1.0f : -1.0f;
                    // The reference's float arithmetic; where |os|² overflows it would give a zero
                    // tangent, so that case is scaled down first (normalize_keep_zero).
                    if (mikk_not_zero(len_s2))
                        tangent = std::isfinite(len_s2) ? os * (sign / std::sqrt(len_s2)) : normalize_keep_zero(os) * sign;
                    if (!frame_.empty()) {
                        const auto [mag_s, mag_t] = derivative_lengths(v1, v2, v3, t1, t2, t3);
                        frame_[t] = {flat(tangent), mag_s, mag_t};
                    }
                    is_good = mikk_not_zero(len_s2) && mikk_not_zero(len_t2);
                }
                if (!is_good) {
                    flags |= kGroupWithAny;
                    ++local_any;
                }
                flags_[t] = flags;
                if (is_good) corner_contributions(t, {v1, v2, v3}, tangent);
            }
            degenerate += local_degenerate;
            with_any += local_any;
        });
        stats_.degenerate_triangles = degenerate.load();
        stats_.group_with_any = with_any.load();
    }

    // The angle-weighted, projected tangent each corner of a good triangle adds to its group
    // (§3.3.1 with the reference's corner-angle weights), computed while the triangle is in cache
    // and stored in fan order. This is the largest share of the work, so the three corners go
    // through SSE lanes together where available.
    //
    // Corner angles near zero (sliver triangles) are taken from the cross product: arccos of a
    // cosine that rounds to 1 would give a zero weight, and a group made of one such corner would
    // lose its tangent, where the reference (normalizing in another order) keeps a tiny weight.
    void corner_contributions(size_t t, const std::array<Vec3, 3>& p, const Vec3& tangent)
    {
        const MeshTriangle& tri = tris_[t];
        const Vec3 n[3] = {mesh_.normal(tri.corner[0]), mesh_.normal(tri.corner[1]), mesh_.normal(tri.corner[2])};
        float cx[4], cy[4], cz[4], w[4];
#if defined(__SSE2__)
        if (!simd_contributions(p, n, tangent, cx, cy, cz, w))
#endif
            scalar_contributions(p, n, tangent, cx, cy, cz, w);
        for (uint32_t i = 0; i < 3; ++i) {
            const uint32_t item = item_of_[t * 3 + i];
            contrib_[item] = {cx[i], cy[i], cz[i]};
            if (!weight_.empty()) weight_[item] = w[i];
        }
    }

    static constexpr float kSmallAngleCos = 0.9999f;  // below ~0.014 rad: asin(x) = x to 4e-5 relative
    // |q1|²|q2|² below this takes the scalar path: the small-angle branch's |q1 × q2|² is at most
    // this times sin² (≤ 2e-4 there), which must stay a normal float with digits to spare.
    static constexpr float kMinSimdEdgeProduct = 1e-24f;

    // Exact square roots and divisions: the reference path, and the fallback for lengths so small
    // (below FLT_MIN squared) that the hardware inverse square root estimate is not usable.
    static void scalar_contributions(const std::array<Vec3, 3>& p, const Vec3 (&n)[3], const Vec3& tangent, float* cx,
                                     float* cy, float* cz, float* w)
    {
        for (uint32_t i = 0; i < 3; ++i) {
            const Vec3 e1 = p[(i + 1) % 3] - p[i], e2 = p[(i + 2) % 3] - p[i];
            const Vec3 q1 = project_normalize(n[i], e1), q2 = project_normalize(n[i], e2);
            const float cosine = dot(q1, q2);
            w[i] = cosine > kSmallAngleCos ? length(cross(q1, q2)) : fast_acos(cosine);
            const Vec3 c = project_normalize(n[i], tangent) * w[i];
            cx[i] = c.x, cy[i] = c.y, cz[i] = c.z;
        }
    }

#if defined(__SSE2__)
    // Lanes 0..2 are the corners; lane 3 is zero and ignored. Returns false (and leaves the work to
    // the scalar path) when a squared length is positive but below FLT_MIN, or not finite.
    static bool simd_contributions(const std::array<Vec3, 3>& p, const Vec3 (&n)[3], const Vec3& tangent, float* cx,
                                   float* cy, float* cz, float* w)
    {
        const __m128 px = _mm_setr_ps(p[0].x, p[1].x, p[2].x, 0.0f), py = _mm_setr_ps(p[0].y, p[1].y, p[2].y, 0.0f),
                     pz = _mm_setr_ps(p[0].z, p[1].z, p[2].z, 0.0f);
        const __m128 e1x = _mm_sub_ps(_mm_setr_ps(p[1].x, p[2].x, p[0].x, 0.0f), px),
                     e1y = _mm_sub_ps(_mm_setr_ps(p[1].y, p[2].y, p[0].y, 0.0f), py),
                     e1z = _mm_sub_ps(_mm_setr_ps(p[1].z, p[2].z, p[0].z, 0.0f), pz);
        const __m128 e2x = _mm_sub_ps(_mm_setr_ps(p[2].x, p[0].x, p[1].x, 0.0f), px),
                     e2y = _mm_sub_ps(_mm_setr_ps(p[2].y, p[0].y, p[1].y, 0.0f), py),
                     e2z = _mm_sub_ps(_mm_setr_ps(p[2].z, p[0].z, p[1].z, 0.0f), pz);
        const __m128 nx = _mm_setr_ps(n[0].x, n[1].x, n[2].x, 0.0f), ny = _mm_setr_ps(n[0].y, n[1].y, n[2].y, 0.0f),
                     nz = _mm_setr_ps(n[0].z, n[1].z, n[2].z, 0.0f);
        auto dot3 = [](__m128 ax, __m128 ay, __m128 az, __m128 bx, __m128 by, __m128 bz) {
            return _mm_add_ps(_mm_add_ps(_mm_mul_ps(ax, bx), _mm_mul_ps(ay, by)), _mm_mul_ps(az, bz));
        };
        const __m128 d1 = dot3(nx, ny, nz, e1x, e1y, e1z), d2 = dot3(nx, ny, nz, e2x, e2y, e2z);
        const __m128 q1x = _mm_sub_ps(e1x, _mm_mul_ps(nx, d1)), q1y = _mm_sub_ps(e1y, _mm_mul_ps(ny, d1)),
                     q1z = _mm_sub_ps(e1z, _mm_mul_ps(nz, d1));
        const __m128 q2x = _mm_sub_ps(e2x, _mm_mul_ps(nx, d2)), q2y = _mm_sub_ps(e2y, _mm_mul_ps(ny, d2)),
                     q2z = _mm_sub_ps(e2z, _mm_mul_ps(nz, d2));
        const __m128 tx = _mm_set1_ps(tangent.x), ty = _mm_set1_ps(tangent.y), tz = _mm_set1_ps(tangent.z);
        const __m128 dt = dot3(nx, ny, nz, tx, ty, tz);
        const __m128 ptx = _mm_sub_ps(tx, _mm_mul_ps(nx, dt)), pty = _mm_sub_ps(ty, _mm_mul_ps(ny, dt)),
                     ptz = _mm_sub_ps(tz, _mm_mul_ps(nz, dt));
        const __m128 l1 = dot3(q1x, q1y, q1z, q1x, q1y, q1z), l2 = dot3(q2x, q2y, q2z, q2x, q2y, q2z),
                     lt = dot3(ptx, pty, ptz, ptx, pty, ptz);
        const __m128 zero = _mm_setzero_ps(), tiny = _mm_set1_ps(1.17549435e-38f), huge = _mm_set1_ps(3.40282347e+38f);
        // Below FLT_MIN the estimate is unusable; past FLT_MAX (overflowed: normals that were
        // never normalized, huge coordinates) or NaN it gives NaN: the scalar path handles both.
        // The same for |q1|²|q2|², which bounds the small-angle branch's |q1 × q2|²: past FLT_MAX
        // its sine came out infinite, and so did the corner's weight (found by fuzz_tangent).
        auto risky = [&](__m128 x) {
            return _mm_or_ps(_mm_and_ps(_mm_cmpgt_ps(x, zero), _mm_cmplt_ps(x, tiny)), _mm_cmpnle_ps(x, huge));
        };
        // And where it underflows (edges under about 1e-9): |q1 × q2|² then loses the thin corner's
        // sine, and a weight of 0 left corners of 1e-12 edges without a tangent (found in review).
        const __m128 product = _mm_mul_ps(l1, l2);
        const __m128 overflowing = _mm_cmpnle_ps(product, huge);
        const __m128 underflowing = _mm_and_ps(_mm_and_ps(_mm_cmpgt_ps(l1, zero), _mm_cmpgt_ps(l2, zero)),
                                               _mm_cmplt_ps(product, _mm_set1_ps(kMinSimdEdgeProduct)));
        if (_mm_movemask_ps(_mm_or_ps(_mm_or_ps(_mm_or_ps(risky(l1), risky(l2)), risky(lt)),
                                      _mm_or_ps(overflowing, underflowing))) & 7)
            return false;
        const __m128 one = _mm_set1_ps(1.0f), half = _mm_set1_ps(0.5f), three_halves = _mm_set1_ps(1.5f);
        auto rsqrt = [&](__m128 x) {  // one Newton step; lanes with x == 0 give 0, like normalizing zero
            const __m128 y = _mm_rsqrt_ps(x);
            const __m128 r = _mm_mul_ps(y, _mm_sub_ps(three_halves, _mm_mul_ps(_mm_mul_ps(half, x), _mm_mul_ps(y, y))));
            return _mm_and_ps(_mm_cmpgt_ps(x, zero), r);
        };
        const __m128 inv12 = _mm_mul_ps(rsqrt(l1), rsqrt(l2));
        __m128 cosine = _mm_mul_ps(dot3(q1x, q1y, q1z, q2x, q2y, q2z), inv12);
        cosine = _mm_min_ps(one, _mm_max_ps(_mm_set1_ps(-1.0f), cosine));
        // fast_acos, lane-wise.
        const __m128 a = _mm_andnot_ps(_mm_set1_ps(-0.0f), cosine);
        __m128 poly = _mm_add_ps(_mm_set1_ps(0.0742610f), _mm_mul_ps(a, _mm_set1_ps(-0.0187293f)));
        poly = _mm_add_ps(_mm_set1_ps(-0.2121144f), _mm_mul_ps(a, poly));
        poly = _mm_add_ps(_mm_set1_ps(1.5707288f), _mm_mul_ps(a, poly));
        const __m128 r = _mm_mul_ps(_mm_sqrt_ps(_mm_sub_ps(one, a)), poly);
        const __m128 negative = _mm_cmplt_ps(cosine, zero);
        __m128 angle = _mm_or_ps(_mm_and_ps(negative, _mm_sub_ps(_mm_set1_ps(3.14159265f), r)), _mm_andnot_ps(negative, r));
        const __m128 small = _mm_cmpgt_ps(cosine, _mm_set1_ps(kSmallAngleCos));
        if (_mm_movemask_ps(small) & 7) {
            const __m128 sx = _mm_sub_ps(_mm_mul_ps(q1y, q2z), _mm_mul_ps(q1z, q2y)),
                         sy = _mm_sub_ps(_mm_mul_ps(q1z, q2x), _mm_mul_ps(q1x, q2z)),
                         sz = _mm_sub_ps(_mm_mul_ps(q1x, q2y), _mm_mul_ps(q1y, q2x));
            const __m128 sine = _mm_mul_ps(_mm_sqrt_ps(dot3(sx, sy, sz, sx, sy, sz)), inv12);
            angle = _mm_or_ps(_mm_and_ps(small, sine), _mm_andnot_ps(small, angle));
        }
        const __m128 scale = _mm_mul_ps(angle, rsqrt(lt));
        _mm_storeu_ps(cx, _mm_mul_ps(ptx, scale));
        _mm_storeu_ps(cy, _mm_mul_ps(pty, scale));
        _mm_storeu_ps(cz, _mm_mul_ps(ptz, scale));
        _mm_storeu_ps(w, angle);
        return true;
    }
#endif

    // Both halves of a quad must share one orientation; a quad whose halves disagree has a folded
    // mapping, and the reference settles it in favour of the half with the larger UV area.
    void quad_pass()
    {
        parallel_for(tris_.size() - 1, threads_, 1 << 15, [&](size_t b, size_t e) {
            for (size_t t = b; t < e; ++t) {
                if (tris_[t].face != tris_[t + 1].face) continue;
                uint8_t& a = flags_[t];
                uint8_t& c = flags_[t + 1];
                const bool a_bad = a & kDegenerate, c_bad = c & kDegenerate;
                if (a_bad != c_bad) {
                    a |= kQuadOneDegen;
                    c |= kQuadOneDegen;
                    continue;
                }
                if (a_bad || ((a ^ c) & kPreserving) == 0) continue;
                bool first_wins = (c & kGroupWithAny) != 0;
                if (!first_wins) first_wins = uv_area(t) >= uv_area(t + 1);
                uint8_t& loser = first_wins ? c : a;
                const uint8_t winner = first_wins ? a : c;
                loser = uint8_t((loser & ~kPreserving) | (winner & kPreserving));
            }
        });
    }

    float uv_area(size_t t) const
    {
        const MeshTriangle& tri = tris_[t];
        return std::fabs(signed_uv_area(mesh_.uv(tri.corner[0]), mesh_.uv(tri.corner[1]), mesh_.uv(tri.corner[2])));
    }

    // ---- groups -------------------------------------------------------------------------------
    struct GroupSum {
        Vec3 tangent;
        float weight = 0.0f, mag_s = 0.0f, mag_t = 0.0f, plain_s = 0.0f, plain_t = 0.0f;
        uint32_t members = 0;
        bool preserving = false;
    };

    // Accumulates the groups of one welded vertex (items [begin, end)) and writes its corners.
    // slot_of(k) gives item k's group as an index in [0, groups), or kUnset.
    template <typename SlotOf>
    void evaluate_run(size_t begin, size_t end, SlotOf slot_of, size_t groups, std::vector<GroupSum>& sums)
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

    // Every corner takes the frame of its group; a quad's diagonal corners belong to both halves
    // and average the second group in unless it is bitwise the same frame (the reference's rule, so
    // that float noise does not split a frame). The sign is the last group's. Corners no group
    // reached keep MikkTSpace's default (1, 0, 0), sign -1.
    void write_corners()
    {
        parallel_for(mesh_.face_count(), threads_, 1 << 14, [&](size_t b, size_t e) {
            size_t t = tri_of_face(b);
            for (size_t f = b; f < e; ++f) {
                const uint32_t offset = mesh_.face_offset(f), size = mesh_.face_size(f);
                uint32_t seen = 0;
                for (const size_t last = t + (size == 4 ? 2 : 1); t < last; ++t) {
                    if (!good(uint32_t(t))) continue;
                    for (uint32_t i = 0; i < 3; ++i) {
                        const uint32_t k = item_of_[t * 3 + i];
                        if (result_sign_[k] == 0) continue;
                        const Float3& r = contrib_[k];
                        const uint32_t c = tris_[t].corner[i];
                        float* o = &out_[4 * c];
                        const uint32_t bit = 1u << (c - offset);
                        if (!(seen & bit)) {
                            o[0] = r.x, o[1] = r.y, o[2] = r.z;
                            if (!mags_.empty()) mags_[2 * c] = result_mags_[k].s, mags_[2 * c + 1] = result_mags_[k].t;
                        } else {
                            if (!(o[0] == r.x && o[1] == r.y && o[2] == r.z)) {
                                const Vec3 avg = normalize_keep_zero(Vec3{o[0], o[1], o[2]} + Vec3{r.x, r.y, r.z});
                                o[0] = avg.x, o[1] = avg.y, o[2] = avg.z;
                            }
                            if (!mags_.empty()) {
                                mags_[2 * c] = 0.5f * (mags_[2 * c] + result_mags_[k].s);
                                mags_[2 * c + 1] = 0.5f * (mags_[2 * c + 1] + result_mags_[k].t);
                            }
                        }
                        seen |= bit;
                        o[3] = float(result_sign_[k]);
                    }
                }
                for (uint32_t c = offset; c < offset + size; ++c) {
                    if (seen & (1u << (c - offset))) continue;
                    float* o = &out_[4 * c];
                    o[0] = 1.0f, o[1] = 0.0f, o[2] = 0.0f, o[3] = -1.0f;
                    if (!mags_.empty()) mags_[2 * c] = mags_[2 * c + 1] = 1.0f;
                }
            }
        });
    }

    // Triangle index of face f's first triangle: faces before it plus quads before it. Only needed
    // at chunk starts, so it is found by binary search over the triangles' faces.
    size_t tri_of_face(size_t f) const
    {
        return size_t(std::lower_bound(tris_.begin(), tris_.end(), uint32_t(f),
                                       [](const MeshTriangle& tri, uint32_t face) { return tri.face < face; }) -
                      tris_.begin());
    }

    // What the per-vertex pass needs about each item's triangle, copied into fan order in one
    // streaming pass over the triangles: reading it through the triangles from the fans would
    // cost a cache miss per item.
    void scatter_to_items()
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

    // ---- fans and groups -----------------------------------------------------------------------
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
    void group_pass()
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
    void ordered_groups()
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
    void refresh_item_flags()
    {
        for (uint32_t t = 0; t < tris_.size(); ++t)
            if (flags_[t] & kGroupWithAny)
                for (uint32_t i = 0; i < 3; ++i) item_flags_[item_of_[t * 3 + i]] = flags_[t];
    }

    bool any_grouped(uint32_t t) const
    {
        return group_of_[item_of_[t * 3]] != kUnset || group_of_[item_of_[t * 3 + 1]] != kUnset ||
               group_of_[item_of_[t * 3 + 2]] != kUnset;
    }

    void affected_pass()
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

    // ---- degenerate triangles -----------------------------------------------------------------
    void copy_corner(uint32_t dst, uint32_t src)
    {
        std::memcpy(&out_[4 * dst], &out_[4 * src], 4 * sizeof(float));
        if (!mags_.empty()) std::memcpy(&mags_[2 * dst], &mags_[2 * src], 2 * sizeof(float));
    }

    void degenerate_epilogue()
    {
        // A degenerate triangle's corner copies the frame of the first good corner welded to it.
        for (size_t t = 0; t < tris_.size(); ++t) {
            if (good(uint32_t(t)) || (flags_[t] & kQuadOneDegen)) continue;
            for (uint32_t i = 0; i < 3; ++i) {
                const uint32_t c = tris_[t].corner[i];
                const uint32_t src = first_good_[weld_tc_[t * 3 + i]];
                if (src != kUnset) copy_corner(c, src);
            }
        }
        // A quad with one degenerate half: its lone corner copies the coincident corner of the
        // good half (one always exists, since the bad half has two equal positions).
        for (size_t t = 0; t < tris_.size(); ++t) {
            if (!good(uint32_t(t)) || !(flags_[t] & kQuadOneDegen)) continue;
            const MeshTriangle& tri = tris_[t];
            const uint32_t offset = mesh_.face_offset(tri.face);
            uint32_t present = 0;
            for (uint32_t i = 0; i < 3; ++i) present |= 1u << (tri.corner[i] - offset);
            uint32_t missing = 0;
            for (uint32_t v = 1; v < 4; ++v)
                if (!(present & (1u << v))) {
                    missing = v;
                    break;
                }
            const Vec3 target = mesh_.position(offset + missing);
            for (uint32_t i = 0; i < 3; ++i)
                if (same_position(mesh_.position(tri.corner[i]), target)) {
                    copy_corner(offset + missing, tri.corner[i]);
                    break;
                }
        }
    }

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

}  // namespace

TangentStats generate_tangent_frames(const MeshInput& mesh, int threads, std::span<float> tangents,
                                     std::span<float> magnitudes)
{
    if (mesh.ngon_faces() > 0)
        throw Error(Status::invalid_argument, "tangent frames need triangles and quads; the mesh has " +
                                                  std::to_string(mesh.ngon_faces()) + " n-gons");
    if (tangents.size() != mesh.corner_count() * 4)
        throw Error(Status::invalid_argument, "tangents must hold 4 floats per corner (" +
                                                  std::to_string(mesh.corner_count() * 4) + "), got " +
                                                  std::to_string(tangents.size()));
    if (!magnitudes.empty() && magnitudes.size() != mesh.corner_count() * 2)
        throw Error(Status::invalid_argument, "magnitudes must hold 2 floats per corner (" +
                                                  std::to_string(mesh.corner_count() * 2) + "), got " +
                                                  std::to_string(magnitudes.size()));
    return Generator(mesh, threads, tangents, magnitudes).run();
}

}  // namespace ndfbake
