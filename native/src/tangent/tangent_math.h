// Small math the tangent module needs beyond math/vec3.h: UV vectors, bit-exact comparisons and a
// fast arc cosine for corner-angle weights.
#pragma once

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>

#include "math/vec3.h"

#if defined(__SSE__)
#include <xmmintrin.h>
#endif

namespace ndfbake {

struct Vec2 {
    float x = 0.0f, y = 0.0f;
};

// MikkTSpace calls a value "not zero" when it exceeds the smallest normal float; matching that
// threshold exactly is what keeps our degenerate/group-with-any decisions equal to Blender's.
inline bool mikk_not_zero(float v) { return std::fabs(v) > 1.17549435e-38f; }

inline uint32_t float_bits(float v) { return std::bit_cast<uint32_t>(v); }

// v normalized; a zero vector stays zero (the reference keeps zero vectors rather than producing
// NaN, and so must we to match it). Where the squared length leaves float's normal range, v is
// scaled by its largest component first: past ~1e19 (normals never normalized) it overflows, and
// below ~1e-19 it is a denormal with too few bits left for a unit result (fuzzing found a tangent
// of length 1.02 that way). A vector with an infinite component has no direction and becomes zero.
inline Vec3 normalize_keep_zero(const Vec3& v)
{
    const float len2 = v.x * v.x + v.y * v.y + v.z * v.z;
    if (len2 >= 1.17549435e-38f && std::isfinite(len2)) return v * (1.0f / std::sqrt(len2));
    const float largest = std::max({std::fabs(v.x), std::fabs(v.y), std::fabs(v.z)});
    if (largest == 0.0f) return v;
    if (!std::isfinite(largest)) return Vec3{};
    const Vec3 s = v / largest;  // a division: 1 / largest overflows for a denormal largest
    return s * (1.0f / std::sqrt(s.x * s.x + s.y * s.y + s.z * s.z));
}

// v projected onto the plane orthogonal to n, then normalized as normalize_keep_zero does.
inline Vec3 project_normalize(const Vec3& n, const Vec3& v) { return normalize_keep_zero(v - n * dot(n, v)); }

// 1/sqrt(x) for x > 0 to ~2e-7 relative: the hardware estimate refined by one Newton step, about
// twice as fast as a square root followed by a division, which dominate the per-corner work.
inline float inverse_sqrt(float x)
{
#if defined(__SSE__)
    const float y = _mm_cvtss_f32(_mm_rsqrt_ss(_mm_set_ss(x)));
    return y * (1.5f - 0.5f * x * y * y);
#else
    return 1.0f / std::sqrt(x);
#endif
}

// arccos with absolute error below 7e-5 rad (Abramowitz & Stegun 4.4.45). Corner angles are only
// weights of an average, so this error moves tangents by ~1e-5 rad, far inside the 1e-3 rad we
// promise, while std::acos would cost a large share of the whole generation time.
inline float fast_acos(float x)
{
    x = std::clamp(x, -1.0f, 1.0f);
    const float a = std::fabs(x);
    const float r = std::sqrt(1.0f - a) * (1.5707288f + a * (-0.2121144f + a * (0.0742610f + a * -0.0187293f)));
    return x < 0.0f ? 3.14159265f - r : r;
}

}  // namespace ndfbake
