// What the library does with image files of any format besides decoding normal and colour maps:
// reading headers and pixels back, and writing 8-bit images. The full library does it through
// OpenImageIO (io/image_files.cpp); the Blender add-on's library, built without it, refuses every
// call with Status::unsupported_format (io/no_image_files.cpp): inside Blender, Blender reads
// images and hands the pixels over.
#pragma once

#include <string>
#include <utility>
#include <vector>

#include "error.h"

namespace ndfbake {

// False in the library built without OpenImageIO: every function here and decode_normal_map,
// decode_color_image and write_normal_map then refuse.
bool reads_image_files();

// How the library built without OpenImageIO refuses: `what` names the operation ("cannot read
// 'x.png'"), the rest says why and what to call instead.
[[noreturn]] inline void refuse_image_files(const std::string& what)
{
    throw Error(Status::unsupported_format,
                what + ": this build of ndfbake (the Blender add-on's library) reads and writes no image "
                       "files (ndfb_has_image_files() is 0); decode the image in the host and pass its "
                       "pixels to ndfb_normal_map_from_pixels, then bake them with ndfb_bake_map");
}

struct ImageInfo {
    std::string format;  // OpenImageIO format name, e.g. "openexr"
    int width = 0;
    int height = 0;
    int channels = 0;
    std::string pixel_type;  // OpenImageIO type name: "half", "float", "uint8", ...
    std::vector<std::pair<std::string, std::string>> attributes;  // every header attribute
    std::vector<std::pair<int, int>> mip_levels;  // width, height of every MIP level (level 0 first)
    int tile_width = 0, tile_height = 0;          // 0: scanlines
};

// The header of any image OpenImageIO reads; errors as in decode_normal_map.
ImageInfo read_image_info(const std::string& path);

// What a file's header says about the memory its pixels take.
struct ImageLayout {
    int width = 0;
    int height = 0;
    int depth = 1;             // > 1 for volume images
    int channels = 0;
    int bytes_per_sample = 0;
    bool float_samples = false;  // half, float or double
};

// The header of `path` only: no pixel is read. Errors as in decode_normal_map.
ImageLayout read_image_layout(const std::string& path);

// The pixels of a 4-channel image as width * height * 4 floats, top row first (the full library
// only: the tests read lobe textures back with it).
std::vector<float> read_rgba_exr(const std::string& path, int& width, int& height);

// Writes width * height RGB 8-bit pixels (top row first) in the format `path`'s extension names,
// atomically. Throws Error(io_error).
void write_rgb8_image(const std::string& path, int width, int height, const unsigned char* rgb);

}  // namespace ndfbake
