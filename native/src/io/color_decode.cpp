#include "io/color_decode.h"

#include <cmath>

#include "io/image_read.h"

namespace ndfbake {

namespace {

float srgb_to_linear(float v)
{
    return v <= 0.04045f ? v / 12.92f : std::pow((v + 0.055f) / 1.055f, 2.4f);
}

}  // namespace

ColorImage decode_color_image(const std::string& path)
{
    const std::unique_ptr<OIIO::ImageInput> in = open_image(path);
    const OIIO::ImageSpec& spec = in->spec();
    const int channels = spec.nchannels;
    std::vector<float> pixels(size_t(spec.width) * size_t(spec.height) * size_t(channels));
    read_all_pixels(*in, path, OIIO::TypeDesc::FLOAT, pixels.data());

    const bool is_float = spec.format.basetype == OIIO::TypeDesc::HALF ||
                          spec.format.basetype == OIIO::TypeDesc::FLOAT ||
                          spec.format.basetype == OIIO::TypeDesc::DOUBLE;
    const std::string space = spec.get_string_attribute("oiio:ColorSpace");
    const bool tagged_linear = space == "Linear" || space == "linear";

    ColorImage image;
    image.width = spec.width;
    image.height = spec.height;
    image.linearized = !is_float && !tagged_linear;
    image.rgb.resize(size_t(spec.width) * size_t(spec.height) * 3);
    // Fewer than three channels is grey (plus alpha, which is no colour): R = G = B = channel 0.
    const bool grey = channels < 3;
    for (size_t p = 0; p < size_t(spec.width) * size_t(spec.height); ++p)
        for (int c = 0; c < 3; ++c) {
            float v = pixels[p * size_t(channels) + size_t(grey ? 0 : c)];
            if (!std::isfinite(v)) v = 0.0f;
            image.rgb[p * 3 + size_t(c)] = image.linearized ? srgb_to_linear(v) : v;
        }
    return image;
}

}  // namespace ndfbake
