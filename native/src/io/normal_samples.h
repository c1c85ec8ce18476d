// Turning stored samples into raw normals: the rules the file decoder (io/normal_file_decode.cpp,
// through OpenImageIO) and the in-memory decoder (io/normal_decode.cpp) share.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "io/normal_decode.h"

namespace ndfbake {

// FNV-1a: dependency-free and fast enough to fingerprint a source file, so a baked texture can
// name the exact input it came from.
class Fnv1a64 {
public:
    void add(const void* data, size_t size)
    {
        const auto* bytes = static_cast<const unsigned char*>(data);
        for (size_t i = 0; i < size; ++i)
            hash_ = (hash_ ^ bytes[i]) * 1099511628211ull;
    }
    uint64_t value() const { return hash_; }

private:
    uint64_t hash_ = 14695981039346656037ull;
};

// The sRGB EOTF (IEC 61966-2-1): encoded value -> linear value, both in [0, 1].
inline double srgb_to_linear(double v)
{
    return v <= 0.04045 ? v / 12.92 : std::pow((v + 0.055) / 1.055, 2.4);
}

// An unsigned integer code k in [0, M] as a component in [-1, 1]. (2k - M) / M keeps the
// numerator an exact integer, so k and its mirror M - k decode to exact negatives: a DirectX map
// and its OpenGL twin give bit-identical normals.
inline float code_to_component(uint32_t code, double max_code, bool linearize)
{
    if (linearize)
        return float(2.0 * srgb_to_linear(code / max_code) - 1.0);
    return float((2.0 * code - max_code) / max_code);
}

inline float float_to_component(float v, bool signed_encoding, bool linearize)
{
    if (signed_encoding)
        return v;
    const double unit = linearize ? srgb_to_linear(v) : double(v);
    return float(2.0 * unit - 1.0);
}

// BC5-style maps store only X and Y of a unit normal in the upper hemisphere.
inline float reconstruct_z(float x, float y) { return std::sqrt(std::max(0.0f, 1.0f - x * x - y * y)); }

// Turns interleaved samples into raw (unrepaired) normals. `to_component` maps one stored sample
// to [-1, 1]; channels beyond the third (alpha) are skipped.
template <typename T, typename ToComponent>
NormalMap assemble_normals(const T* samples, int width, int height, int channels,
                           Convention convention, ToComponent to_component)
{
    NormalMap map;
    map.width = width;
    map.height = height;
    map.normals.resize(size_t(width) * size_t(height));
    for (size_t i = 0; i < map.normals.size(); ++i) {
        const T* s = &samples[i * size_t(channels)];
        const float x = to_component(s[0]);
        const float y = to_component(s[1]);
        const float z = channels == 2 ? reconstruct_z(x, y) : to_component(s[2]);
        map.normals[i] = {x, convention == Convention::directx ? -y : y, z};
    }
    return map;
}

// `context` starts the message: "cannot read 'x.png'" or "cannot decode in-memory pixels".
void check_channels(int channels, const std::string& context);

// Runs on header values, before any pixel memory is allocated.
void check_pixel_count(int width, int height, uint64_t max_pixels, const std::string& context);

// FloatEncoding::automatic looks at the data: [0, 1]-encoded maps never go clearly negative.
bool has_signed_samples(const std::vector<float>& samples, int channels);

// The sentences every decode shares, then the repair pass.
void finish_decode(DecodeResult& result, const DecodeOptions& options);

}  // namespace ndfbake
