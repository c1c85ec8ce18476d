// Growing UV islands outward so that MIP filtering near an island border averages the island's own
// normals instead of the empty background (Mikkelsen 2008 §3.6, "filtering seams").
#pragma once

#include <cstdint>
#include <span>
#include <vector>

namespace ndfbake {

// state: per texel 1 = filled by rasterization, 0 = empty; rings of empty texels touching filled
// ones (8-neighbourhood) take the normalized mean of their already-filled neighbours, ring after
// ring, for at most `rings` rings (0xffffffff: until the image is full). Padded texels get state 2.
void pad_islands(std::span<float> normals, int width, int height, std::vector<uint8_t>& state, uint32_t rings);

}  // namespace ndfbake
