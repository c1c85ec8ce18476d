// Self-describing RGBA EXR files: the lobe textures ndfbake writes carry their parameters as
// typed header attributes, so a file explains itself to `ndfbake info` and to the add-on.
#pragma once

#include <string>
#include <utility>
#include <variant>
#include <vector>

namespace ndfbake {

using AttributeValue = std::variant<int, float, std::string>;

struct ExrAttribute {
    std::string name;  // e.g. "ndfbake:level"; stored with its C++ type (int stays int)
    AttributeValue value;
};

enum class PixelPrecision { half, single };

// Writes `rgba` (width * height * 4 floats, row-major, top row first) as a zip-compressed EXR
// with the given header attributes, atomically (see write_file_atomic). Throws Error(io_error).
void write_rgba_exr(const std::string& path, int width, int height, const float* rgba,
                    PixelPrecision precision, const std::vector<ExrAttribute>& attributes);

struct ImageInfo {
    std::string format;  // OpenImageIO format name, e.g. "openexr"
    int width = 0;
    int height = 0;
    int channels = 0;
    std::string pixel_type;  // OpenImageIO type name: "half", "float", "uint8", ...
    std::vector<std::pair<std::string, std::string>> attributes;  // every header attribute
};

// The header of any image OpenImageIO reads; errors as in decode_normal_map.
ImageInfo read_image_info(const std::string& path);

// The pixels of a 4-channel image as width * height * 4 floats, top row first.
std::vector<float> read_rgba_exr(const std::string& path, int& width, int& height);

}  // namespace ndfbake
