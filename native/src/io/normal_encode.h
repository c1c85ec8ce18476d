// Writing normal maps as images (for `ndfbake synth` and test fixtures).
#pragma once

#include <string>

#include "normal_map.h"

namespace ndfbake {

// Encodes n → 0.5 n + 0.5 in every format (float EXR too, as Blender's bakes do, so that the
// decoder's automatic float detection reads it back unchanged); 8-bit for PNG/TGA/JPEG, 16-bit
// for TIFF, float for EXR. Atomic; throws Error(io_error) or Error(unsupported_format).
void write_normal_map(const std::string& path, const NormalMap& map);

}  // namespace ndfbake
