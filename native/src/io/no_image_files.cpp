// The Blender add-on's library is built without OpenImageIO, so that it needs nothing but the C
// runtime (the OpenEXR core compiled in): these take the place of the functions that
// read or write image files through OpenImageIO (io/image_files.cpp, io/normal_file_decode.cpp,
// io/color_decode.cpp, io/normal_encode.cpp), and refuse.
#include "io/color_decode.h"
#include "io/image_files.h"
#include "io/normal_decode.h"
#include "io/normal_encode.h"

namespace ndfbake {

bool reads_image_files() { return false; }

ImageInfo read_image_info(const std::string& path) { refuse_image_files("cannot describe '" + path + "'"); }

ImageLayout read_image_layout(const std::string& path) { refuse_image_files("cannot read '" + path + "'"); }

void write_rgb8_image(const std::string& path, int, int, const unsigned char*)
{
    refuse_image_files("cannot write '" + path + "'");
}

DecodeResult decode_normal_map(const std::string& path, const DecodeOptions&)
{
    refuse_image_files("cannot read '" + path + "'");
}

ColorImage decode_color_image(const std::string& path)
{
    refuse_image_files("cannot read the colour image '" + path + "'");
}

void write_normal_map(const std::string& path, const NormalMap&)
{
    refuse_image_files("cannot write '" + path + "'");
}

}  // namespace ndfbake
