#include "io/lobe_exr.h"

#include <cerrno>
#include <cstring>

#include <OpenImageIO/imageio.h>

#include "error.h"
#include "io/atomic_file.h"
#include "io/image_read.h"

namespace ndfbake {

namespace {

// zlib at its fastest level: lossless like the default level, files about 6% larger, written
// 1.5× faster (compressing the lobe textures is most of a bake's write time).
constexpr const char* kZlibCompression = "zip:1";

OIIO::ImageSpec exr_spec(int width, int height, PixelPrecision precision,
                         const std::vector<ExrAttribute>& attributes, ExrCompression compression)
{
    OIIO::ImageSpec spec(width, height, 4,
                         precision == PixelPrecision::half ? OIIO::TypeDesc::HALF
                                                           : OIIO::TypeDesc::FLOAT);
    spec.attribute("compression", compression == ExrCompression::run_length ? "rle" : kZlibCompression);
    for (const ExrAttribute& attribute : attributes)
        std::visit([&](const auto& value) { spec.attribute(attribute.name, value); },
                   attribute.value);
    return spec;
}

[[noreturn]] void throw_write_error(const std::string& path, const std::string& detail)
{
    throw Error(Status::io_error, "cannot write '" + path + "': " + detail);
}

// OpenEXR reports a failed write as "File output failed." without the reason; the errno of the
// write is still set when OpenImageIO returns. Only errors a write can raise are named, so a stale
// errno from an earlier, unrelated call is never blamed.
std::string write_errno_reason(int error)
{
    switch (error) {
    case ENOSPC: case EFBIG: case EDQUOT: case EIO: case EROFS: case EACCES: case EPERM:
        return std::string(" (") + std::strerror(error) + ")";
    default: return {};
    }
}

}  // namespace

void write_rgba_exr(const std::string& path, int width, int height, const float* rgba,
                    PixelPrecision precision, const std::vector<ExrAttribute>& attributes,
                    ExrCompression compression)
{
    if (width <= 0 || height <= 0 || !rgba)
        throw Error(Status::invalid_argument,
                    "cannot write '" + path + "': no pixels (" + std::to_string(width) + " x " +
                        std::to_string(height) + ")");
    const OIIO::ImageSpec spec = exr_spec(width, height, precision, attributes, compression);
    write_file_atomic(path, [&](const std::string& temp_path) {
        // Created by format name, not extension: the file is EXR whatever `path` ends with.
        std::unique_ptr<OIIO::ImageOutput> out = OIIO::ImageOutput::create("openexr");
        if (!out)
            throw_write_error(path, OIIO::geterror());
        errno = 0;
        if (!out->open(temp_path, spec) || !out->write_image(OIIO::TypeDesc::FLOAT, rgba) ||
            !out->close()) {
            const int error = errno;
            throw_write_error(path, out->geterror() + write_errno_reason(error));
        }
    });
}

ImageInfo read_image_info(const std::string& path)
{
    const std::unique_ptr<OIIO::ImageInput> in = open_image(path);
    const OIIO::ImageSpec& spec = in->spec();
    ImageInfo info;
    info.format = in->format_name();
    info.width = spec.width;
    info.height = spec.height;
    info.channels = spec.nchannels;
    info.pixel_type = spec.format.c_str();
    for (const OIIO::ParamValue& param : spec.extra_attribs)
        info.attributes.emplace_back(param.name().string(), param.get_string());
    return info;
}

std::vector<float> read_rgba_exr(const std::string& path, int& width, int& height)
{
    const std::unique_ptr<OIIO::ImageInput> in = open_image(path);
    const OIIO::ImageSpec& spec = in->spec();
    if (spec.nchannels != 4)
        throw_read_error(Status::unsupported_format, path,
                         std::to_string(spec.nchannels) + " channels, expected 4 (RGBA)");
    std::vector<float> rgba(size_t(spec.width) * size_t(spec.height) * 4);
    read_all_pixels(*in, path, OIIO::TypeDesc::FLOAT, rgba.data());
    width = spec.width;
    height = spec.height;
    return rgba;
}

}  // namespace ndfbake
