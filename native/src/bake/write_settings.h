// What a bake writes besides the lobe textures of every level.
#pragma once

#include <string>

#include "io/lobe_exr.h"

namespace ndfbake {

struct WriteSettings {
    PixelPrecision precision = PixelPrecision::half;
    std::string color_path;   // optional base-colour image: per-lobe colour files
    std::string source_name;  // recorded in every file
    bool atlas = false;       // also every level of each lobe slot in one image (bake/lobe_atlas.h)
    bool mipmap = false;      // also each lobe slot as one MIP-mapped tiled EXR (mip_lobeJ.exr)
};

}  // namespace ndfbake
