// The shader that goes with a bake's lobe textures: GLSL functions that decode the lobes and
// shade with them, written into every bake folder as ndfbake.glsl for real-time engines.
#pragma once

#include <string>
#include <string_view>

#include "io/lobe_exr.h"

namespace ndfbake {

inline constexpr const char* kLobeShaderFileName = "ndfbake.glsl";

// GLSL (330 core and later, GLSL ES 3.0, Vulkan GLSL: no #version line, for inclusion in an
// engine's shader) for `slots` lobe textures stored at `precision`: the decoding of a lobe texel
// into a weight, a tangent-space normal and a widened GGX α (the same rule as the Blender add-on's
// node group, with kGgxVmfWidening and kHalfInvKappaResolution), and the filtered GGX
// distribution, GGX specular and Lambert terms summed over the lobes.
std::string lobe_shader_glsl(int slots, PixelPrecision precision);

}  // namespace ndfbake
