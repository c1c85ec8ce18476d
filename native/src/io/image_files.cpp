#include "io/image_files.h"

#include <OpenImageIO/imageio.h>

#include "error.h"
#include "io/atomic_file.h"
#include "io/image_read.h"

namespace ndfbake {

bool reads_image_files() { return true; }

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
    info.tile_width = spec.tile_width;
    info.tile_height = spec.tile_height;
    for (const OIIO::ParamValue& param : spec.extra_attribs)
        info.attributes.emplace_back(param.name().string(), param.get_string());
    for (int level = 0; in->seek_subimage(0, level); ++level)
        info.mip_levels.emplace_back(in->spec().width, in->spec().height);
    return info;
}

ImageLayout read_image_layout(const std::string& path)
{
    const OIIO::ImageSpec spec = open_image(path)->spec();
    const OIIO::TypeDesc::BASETYPE base = OIIO::TypeDesc::BASETYPE(spec.format.basetype);
    return {spec.width, spec.height, spec.depth, spec.nchannels, int(spec.format.size()),
            base == OIIO::TypeDesc::HALF || base == OIIO::TypeDesc::FLOAT || base == OIIO::TypeDesc::DOUBLE};
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

void write_rgb8_image(const std::string& path, int width, int height, const unsigned char* rgb)
{
    write_file_atomic(path, [&](const std::string& temp) {
        auto out = OIIO::ImageOutput::create(temp);
        if (!out) throw Error(Status::io_error, "cannot write '" + path + "': " + OIIO::geterror());
        const OIIO::ImageSpec spec(width, height, 3, OIIO::TypeDesc::UINT8);
        if (!out->open(temp, spec) || !out->write_image(OIIO::TypeDesc::UINT8, rgb) || !out->close())
            throw Error(Status::io_error, "cannot write '" + path + "': " + out->geterror());
    });
}

}  // namespace ndfbake
