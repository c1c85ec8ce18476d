// Base-colour textures for per-lobe colour (Han et al. 2007, eq. 22): linear RGB, because lobe
// colours are averages and averages of sRGB-encoded values are too dark.
#pragma once

#include <string>
#include <vector>

namespace ndfbake {

struct ColorImage {
    int width = 0;
    int height = 0;
    std::vector<float> rgb;  // linear, row-major, top row first
    bool linearized = false; // the sRGB curve was decoded
};

// Integer images are sRGB-encoded unless OpenImageIO reports them as linear; float images are
// linear. One channel is grey; alpha and further channels are ignored.
ColorImage decode_color_image(const std::string& path);

}  // namespace ndfbake
