#include "io/normal_decode.h"

#include <algorithm>
#include <cmath>

#include "error.h"
#include "io/normal_samples.h"

namespace ndfbake {

void check_channels(int channels, const std::string& context)
{
    if (channels < 2 || channels > 4)
        throw Error(Status::unsupported_format,
                    context + ": " + std::to_string(channels) +
                        (channels == 1 ? " channel" : " channels") +
                        "; a normal map needs 2 (XY), 3 (XYZ) or 4 (XYZ + alpha)");
}

void check_pixel_count(int width, int height, uint64_t max_pixels, const std::string& context)
{
    const uint64_t pixels = uint64_t(width) * uint64_t(height);
    if (pixels > max_pixels)
        throw Error(Status::out_of_memory,
                    context + ": image is " + std::to_string(width) + " x " +
                        std::to_string(height) + " = " + std::to_string(pixels) +
                        " pixels, over the limit of " + std::to_string(max_pixels));
}

bool has_signed_samples(const std::vector<float>& samples, int channels)
{
    const int used = std::min(channels, 3);
    for (size_t i = 0; i < samples.size(); ++i) {
        const float v = samples[i];
        if (int(i % size_t(channels)) < used && std::isfinite(v) && v < kSignedDetectThreshold)
            return true;
    }
    return false;
}

void finish_decode(DecodeResult& result, const DecodeOptions& options)
{
    if (result.channels == 2)
        result.assumptions.push_back(
            "2 channels: taken as X and Y, Z reconstructed as sqrt(1 - x^2 - y^2)");
    if (result.channels == 4)
        result.assumptions.push_back("4 channels: the 4th (alpha) is ignored");
    result.assumptions.push_back(options.convention == Convention::directx
                                     ? "green channel taken as -Y (DirectX convention), flipped"
                                     : "green channel taken as +Y (OpenGL convention)");
    repair_normals(result.map, result.repairs);
}

namespace {

Vec3 repair_normal(const Vec3& n, RepairCounts& counts)
{
    constexpr Vec3 kUp{0.0f, 0.0f, 1.0f};
    if (!isfinite(n)) {
        ++counts.non_finite;
        return kUp;
    }
    // Double precision: squaring a large finite float component would overflow to Inf.
    const double x = n.x, y = n.y, z = n.z;
    const double len = std::sqrt(x * x + y * y + z * z);
    if (len < kMinNormalLength) {
        ++counts.zero_length;
        return kUp;
    }
    if (z < 0.0)
        ++counts.below_horizon;
    if (std::abs(len - 1.0) > kUnitLengthTolerance)
        ++counts.renormalized;
    // std::abs also turns a -0 z into +0, so a normal on the horizon has a positive z.
    return {float(x / len), float(y / len), float(std::abs(z) / len)};
}

}  // namespace

void repair_normals(NormalMap& map, RepairCounts& counts)
{
    for (Vec3& n : map.normals)
        n = repair_normal(n, counts);
}

DecodeResult decode_normal_pixels(const float* pixels, int width, int height, int channels,
                                  bool signed_encoding, const DecodeOptions& options)
{
    const std::string context = "cannot decode in-memory pixels";
    if (!pixels)
        throw Error(Status::invalid_argument, context + ": pixel pointer is null");
    if (width <= 0 || height <= 0)
        throw Error(Status::invalid_argument, context + ": size " + std::to_string(width) +
                                                  " x " + std::to_string(height) +
                                                  " has no pixels");
    check_channels(channels, context);
    check_pixel_count(width, height, options.max_pixels, context);

    const size_t sample_count = size_t(width) * size_t(height) * size_t(channels);
    DecodeResult result;
    result.format = "memory";
    result.channels = channels;
    result.bits_per_channel = 32;
    result.float_data = true;
    result.signed_encoding = signed_encoding;
    Fnv1a64 hash;
    hash.add(pixels, sample_count * sizeof(float));
    result.source_hash = hash.value();
    result.map = assemble_normals(
        pixels, width, height, channels, options.convention,
        [&](float v) { return float_to_component(v, signed_encoding, false); });
    finish_decode(result, options);
    return result;
}

}  // namespace ndfbake
