// decode_normal_map: normal maps from image files, through OpenImageIO (the full library only).
#include "io/normal_decode.h"

#include <fstream>
#include <limits>

#include <OpenImageIO/strutil.h>

#include "error.h"
#include "io/image_read.h"
#include "io/normal_samples.h"
#include "platform/files.h"

namespace ndfbake {

namespace {

uint64_t hash_file(const std::string& path)
{
    std::ifstream file(path_from_utf8(path), std::ios::binary);
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

}  // namespace

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
}  // namespace ndfbake
