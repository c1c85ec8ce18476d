#include "io/normal_decode.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <limits>

#include <OpenImageIO/strutil.h>

#include "error.h"
#include "io/image_read.h"

namespace ndfbake {

namespace {

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

uint64_t hash_file(const std::string& path)
{
    std::ifstream file(path, std::ios::binary);
    Fnv1a64 hash;
    std::vector<char> buffer(1 << 16);
    while (file) {
        file.read(buffer.data(), std::streamsize(buffer.size()));
        hash.add(buffer.data(), size_t(file.gcount()));
    }
    if (!file.is_open() || file.bad())
        throw_read_error(Status::io_error, path, "read failed while hashing the file");
    return hash.value();
}

// The sRGB EOTF (IEC 61966-2-1): encoded value -> linear value, both in [0, 1].
double srgb_to_linear(double v)
{
    return v <= 0.04045 ? v / 12.92 : std::pow((v + 0.055) / 1.055, 2.4);
}

// An unsigned integer code k in [0, M] as a component in [-1, 1]. (2k - M) / M keeps the
// numerator an exact integer, so k and its mirror M - k decode to exact negatives: a DirectX map
// and its OpenGL twin give bit-identical normals.
float code_to_component(uint32_t code, double max_code, bool linearize)
{
    if (linearize)
        return float(2.0 * srgb_to_linear(code / max_code) - 1.0);
    return float((2.0 * code - max_code) / max_code);
}

float float_to_component(float v, bool signed_encoding, bool linearize)
{
    if (signed_encoding)
        return v;
    const double unit = linearize ? srgb_to_linear(v) : double(v);
    return float(2.0 * unit - 1.0);
}

// BC5-style maps store only X and Y of a unit normal in the upper hemisphere.
float reconstruct_z(float x, float y) { return std::sqrt(std::max(0.0f, 1.0f - x * x - y * y)); }

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
void check_channels(int channels, const std::string& context)
{
    if (channels < 2 || channels > 4)
        throw Error(Status::unsupported_format,
                    context + ": " + std::to_string(channels) +
                        (channels == 1 ? " channel" : " channels") +
                        "; a normal map needs 2 (XY), 3 (XYZ) or 4 (XYZ + alpha)");
}

// Runs on header values, before any pixel memory is allocated.
void check_pixel_count(int width, int height, uint64_t max_pixels, const std::string& context)
{
    const uint64_t pixels = uint64_t(width) * uint64_t(height);
    if (pixels > max_pixels)
        throw Error(Status::out_of_memory,
                    context + ": image is " + std::to_string(width) + " x " +
                        std::to_string(height) + " = " + std::to_string(pixels) +
                        " pixels, over the limit of " + std::to_string(max_pixels));
}

// FloatEncoding::automatic looks at the data: [0, 1]-encoded maps never go clearly negative.
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

// Read in the file's own integer type, not float: the exact codes are what make DirectX twins
// and 16/32-bit values decode without a second rounding.
template <typename T>
NormalMap decode_unsigned(OIIO::ImageInput& in, const std::string& path, Convention convention,
                          bool linearize)
{
    const OIIO::ImageSpec& spec = in.spec();
    std::vector<T> samples(size_t(spec.width) * size_t(spec.height) * size_t(spec.nchannels));
    read_all_pixels(in, path, OIIO::TypeDescFromC<T>::value(), samples.data());
    const double max_code = double(std::numeric_limits<T>::max());
    return assemble_normals(samples.data(), spec.width, spec.height, spec.nchannels, convention,
                            [&](T code) { return code_to_component(code, max_code, linearize); });
}

bool is_srgb(const OIIO::ImageSpec& spec)
{
    // OpenImageIO 2.4 says "sRGB"; later versions name the same space "srgb_rec709_scene".
    const std::string space = spec.get_string_attribute("oiio:ColorSpace");
    return OIIO::Strutil::iequals(space, "sRGB") ||
           OIIO::Strutil::iequals(space, "srgb_rec709_scene");
}

bool is_float_type(OIIO::TypeDesc type)
{
    return type.basetype == OIIO::TypeDesc::HALF || type.basetype == OIIO::TypeDesc::FLOAT ||
           type.basetype == OIIO::TypeDesc::DOUBLE;
}

// Float files state no encoding, so the choice is either the caller's or read off the data.
// An sRGB transfer function only applies to [0, 1] data: signed data is never linearized.
void decode_float(OIIO::ImageInput& in, const std::string& path, const DecodeOptions& options,
                  bool linearize_unsigned, DecodeResult& result)
{
    const OIIO::ImageSpec& spec = in.spec();
    std::vector<float> samples(size_t(spec.width) * size_t(spec.height) * size_t(spec.nchannels));
    read_all_pixels(in, path, OIIO::TypeDesc::FLOAT, samples.data());

    if (options.float_encoding == FloatEncoding::automatic) {
        result.signed_encoding = has_signed_samples(samples, spec.nchannels);
        result.assumptions.push_back(
            result.signed_encoding
                ? "float data has components below -0.01: taken as signed [-1, 1] values"
                : "float data has no component below -0.01: taken as unsigned [0, 1] values, "
                  "mapped by 2v - 1");
    } else {
        result.signed_encoding = options.float_encoding == FloatEncoding::signed_unit;
    }

    const bool linearize = linearize_unsigned && !result.signed_encoding;
    result.map = assemble_normals(
        samples.data(), spec.width, spec.height, spec.nchannels, options.convention,
        [&](float v) { return float_to_component(v, result.signed_encoding, linearize); });
}

std::string srgb_assumption(const DecodeResult& result, SrgbPolicy policy)
{
    const std::string source = std::to_string(result.bits_per_channel) + "-bit sRGB-tagged " +
                               OIIO::Strutil::upper(result.format);
    if (policy == SrgbPolicy::treat_as_data)
        return source + ": values taken as raw data, not linearized";
    if (result.signed_encoding)
        return source + ": sRGB tag ignored, signed data has no transfer function to undo";
    return source + ": sRGB transfer function removed before decoding (linearize requested)";
}

// The sentences every decode shares, then the repair pass.
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

DecodeResult decode_normal_map(const std::string& path, const DecodeOptions& options)
{
    const std::unique_ptr<OIIO::ImageInput> in = open_image(path);
    const OIIO::ImageSpec& spec = in->spec();
    const std::string context = "cannot read '" + path + "'";
    if (spec.width <= 0 || spec.height <= 0)
        throw Error(Status::corrupt_file, context + ": header gives a size of " +
                                              std::to_string(spec.width) + " x " +
                                              std::to_string(spec.height) + " pixels");
    if (spec.depth > 1)
        throw Error(Status::unsupported_format, context + ": volume images are not normal maps");
    check_channels(spec.nchannels, context);
    check_pixel_count(spec.width, spec.height, options.max_pixels, context);

    DecodeResult result;
    result.format = in->format_name();
    result.channels = spec.nchannels;
    result.bits_per_channel =
        spec.get_int_attribute("oiio:BitsPerSample", int(spec.format.size() * 8));
    result.srgb_tagged = is_srgb(spec);
    result.float_data = is_float_type(spec.format);
    result.source_hash = hash_file(path);

    const bool linearize = result.srgb_tagged && options.srgb == SrgbPolicy::linearize;
    switch (spec.format.basetype) {
    case OIIO::TypeDesc::UINT8:
        result.map = decode_unsigned<uint8_t>(*in, path, options.convention, linearize);
        break;
    case OIIO::TypeDesc::UINT16:
        result.map = decode_unsigned<uint16_t>(*in, path, options.convention, linearize);
        break;
    case OIIO::TypeDesc::UINT32:
        result.map = decode_unsigned<uint32_t>(*in, path, options.convention, linearize);
        break;
    case OIIO::TypeDesc::HALF:
    case OIIO::TypeDesc::FLOAT:
    case OIIO::TypeDesc::DOUBLE:
        decode_float(*in, path, options, linearize, result);
        break;
    default:
        throw Error(Status::unsupported_format,
                    context + ": " + spec.format.c_str() +
                        " samples are not supported (use unsigned 8/16/32-bit or float)");
    }
    if (result.srgb_tagged)
        result.assumptions.push_back(srgb_assumption(result, options.srgb));
    finish_decode(result, options);
    return result;
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
