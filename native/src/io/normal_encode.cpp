#include "io/normal_encode.h"

#include <OpenImageIO/imageio.h>

#include <algorithm>
#include <vector>

#include "error.h"
#include "io/atomic_file.h"
#include "platform/files.h"

namespace ndfbake {

void write_normal_map(const std::string& path, const NormalMap& map)
{
    std::string extension = path_to_utf8(path_from_utf8(path).extension());
    std::transform(extension.begin(), extension.end(), extension.begin(), [](unsigned char c) { return char(std::tolower(c)); });
    OIIO::TypeDesc type = OIIO::TypeDesc::UINT8;
    if (extension == ".exr") type = OIIO::TypeDesc::FLOAT;
    else if (extension == ".tif" || extension == ".tiff") type = OIIO::TypeDesc::UINT16;
    else if (extension != ".png" && extension != ".tga" && extension != ".jpg" && extension != ".jpeg")
        throw Error(Status::unsupported_format,
                    "cannot write '" + path + "': use .png, .tga, .jpg, .tif or .exr for a normal map");

    std::vector<float> pixels(map.normals.size() * 3);
    for (size_t i = 0; i < map.normals.size(); ++i)
        for (int c = 0; c < 3; ++c) pixels[i * 3 + size_t(c)] = 0.5f * map.normals[i][c] + 0.5f;

    write_file_atomic(path, [&](const std::string& temp) {
        auto out = OIIO::ImageOutput::create(temp);
        if (!out) throw Error(Status::io_error, "cannot write '" + path + "': " + OIIO::geterror());
        OIIO::ImageSpec spec(map.width, map.height, 3, type);
        spec.attribute("oiio:ColorSpace", "Linear");  // a normal map is data, not colour
        if (!out->open(temp, spec) || !out->write_image(OIIO::TypeDesc::FLOAT, pixels.data()) || !out->close())
            throw Error(Status::io_error, "cannot write '" + path + "': " + out->geterror());
    });
}

}  // namespace ndfbake
