// Per triangle (Mikkelsen §3.3, eqs. 42/43): degenerate and group-with-any triangles, the
// orientation (sign of the UV area, rule 4), dP/du and the magnitudes, each corner's
// angle-weighted projected tangent (scalar and SSE paths), and the quad rule that gives both
// halves of a quad one orientation. Owns flags_, frame_, contrib_, weight_ and the degenerate and
// group-with-any counts. May call: tangent_math.h, parallel_for.h, mesh_input.h.
#include <array>
#include <atomic>
#include <cmath>
#include <utility>

#include "tangent/parallel_for.h"
#include "tangent/tangent_generator.h"

namespace ndfbake::tangent_generation {

namespace {

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

constexpr float kSmallAngleCos = 0.9999f;  // below ~0.014 rad: asin(x) = x to 4e-5 relative

// Exact square roots and divisions: the reference path, and the fallback for lengths so small
// (below FLT_MIN squared) that the hardware inverse square root estimate is not usable.
void scalar_contributions(const std::array<Vec3, 3>& p, const Vec3 (&n)[3], const Vec3& tangent, float* cx,
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
// |q1|²|q2|² below this takes the scalar path: the small-angle branch's |q1 × q2|² is at most
// this times sin² (≤ 2e-4 there), which must stay a normal float with digits to spare.
constexpr float kMinSimdEdgeProduct = 1e-24f;

// Lanes 0..2 are the corners; lane 3 is zero and ignored. Returns false (and leaves the work to
// the scalar path) when a squared length is positive but below FLT_MIN, or not finite.
bool simd_contributions(const std::array<Vec3, 3>& p, const Vec3 (&n)[3], const Vec3& tangent, float* cx,
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

}  // namespace

void Generator::triangle_pass()
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
void Generator::corner_contributions(size_t t, const std::array<Vec3, 3>& p, const Vec3& tangent)
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

// Both halves of a quad must share one orientation; a quad whose halves disagree has a folded
// mapping, and the reference settles it in favour of the half with the larger UV area.
void Generator::quad_pass()
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

float Generator::uv_area(size_t t) const
{
    const MeshTriangle& tri = tris_[t];
    return std::fabs(signed_uv_area(mesh_.uv(tri.corner[0]), mesh_.uv(tri.corner[1]), mesh_.uv(tri.corner[2])));
}

}  // namespace ndfbake::tangent_generation
