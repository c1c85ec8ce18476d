// Small 3-vector value type for directions and normals on the unit sphere.
#pragma once

#include <cmath>
#include <span>

namespace ndfbake {

struct Vec3 {
    float x = 0.0f, y = 0.0f, z = 0.0f;

    constexpr Vec3() = default;
    constexpr Vec3(float x_, float y_, float z_) : x(x_), y(y_), z(z_) {}

    constexpr Vec3 operator+(const Vec3& o) const { return {x + o.x, y + o.y, z + o.z}; }
    constexpr Vec3 operator-(const Vec3& o) const { return {x - o.x, y - o.y, z - o.z}; }
    constexpr Vec3 operator-() const { return {-x, -y, -z}; }
    constexpr Vec3 operator*(float s) const { return {x * s, y * s, z * s}; }
    constexpr Vec3 operator/(float s) const { return {x / s, y / s, z / s}; }
    constexpr Vec3& operator+=(const Vec3& o) { x += o.x; y += o.y; z += o.z; return *this; }
    constexpr Vec3& operator*=(float s) { x *= s; y *= s; z *= s; return *this; }
    constexpr float operator[](int i) const { return i == 0 ? x : (i == 1 ? y : z); }
};

constexpr Vec3 operator*(float s, const Vec3& v) { return v * s; }
constexpr float dot(const Vec3& a, const Vec3& b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
constexpr Vec3 cross(const Vec3& a, const Vec3& b)
{
    return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
inline float length(const Vec3& v) { return std::sqrt(dot(v, v)); }
inline bool isfinite(const Vec3& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }

// Returns v / |v|, or `fallback` when v has no usable direction (zero or non-finite length).
inline Vec3 normalize_or(const Vec3& v, const Vec3& fallback)
{
    const float len = length(v);
    return (len > 0.0f && std::isfinite(len)) ? v / len : fallback;
}

// out[i] = vectors[i] · v, for every vector.
inline void dot_each(std::span<const Vec3> vectors, const Vec3& v, std::span<float> out)
{
    for (size_t i = 0; i < vectors.size(); ++i) out[i] = dot(vectors[i], v);
}

// Double-precision accumulator: sums of millions of unit vectors lose digits in float.
struct Vec3d {
    double x = 0.0, y = 0.0, z = 0.0;
    void add(const Vec3& v, double w) { x += w * v.x; y += w * v.y; z += w * v.z; }
    double length() const { return std::sqrt(x * x + y * y + z * z); }
    Vec3 to_float() const { return {float(x), float(y), float(z)}; }
};

}  // namespace ndfbake
