#include "tangent/island_padding.h"

#include <cmath>

namespace ndfbake {

void pad_islands(std::span<float> normals, int width, int height, std::vector<uint8_t>& state, uint32_t rings)
{
    const size_t n = size_t(width) * height;
    // ring[i]: the ring a texel was filled in (0 = rasterized), or -1 while empty. Each ring reads
    // only earlier rings, so the result does not depend on the order texels are visited in.
    std::vector<int32_t> ring(n, -1);
    std::vector<uint32_t> frontier, next;
    for (size_t i = 0; i < n; ++i)
        if (state[i]) {
            ring[i] = 0;
            frontier.push_back(uint32_t(i));
        }
    std::vector<float> values;
    for (uint32_t r = 1; r <= rings && !frontier.empty(); ++r) {
        next.clear();
        for (const uint32_t i : frontier) {
            const int x = int(i % width), y = int(i / width);
            for (int dy = -1; dy <= 1; ++dy)
                for (int dx = -1; dx <= 1; ++dx) {
                    const int nx = x + dx, ny = y + dy;
                    if (nx < 0 || ny < 0 || nx >= width || ny >= height) continue;
                    const size_t j = size_t(ny) * width + nx;
                    if (ring[j] != -1) continue;
                    ring[j] = -2;  // queued for this ring
                    next.push_back(uint32_t(j));
                }
        }
        values.assign(next.size() * 3, 0.0f);
        for (size_t k = 0; k < next.size(); ++k) {
            const int x = int(next[k] % width), y = int(next[k] / width);
            double sx = 0, sy = 0, sz = 0;
            for (int dy = -1; dy <= 1; ++dy)
                for (int dx = -1; dx <= 1; ++dx) {
                    const int nx = x + dx, ny = y + dy;
                    if (nx < 0 || ny < 0 || nx >= width || ny >= height) continue;
                    const size_t j = size_t(ny) * width + nx;
                    if (ring[j] < 0) continue;
                    sx += normals[3 * j], sy += normals[3 * j + 1], sz += normals[3 * j + 2];
                }
            const double len = std::sqrt(sx * sx + sy * sy + sz * sz);
            if (len > 0) values[3 * k] = float(sx / len), values[3 * k + 1] = float(sy / len), values[3 * k + 2] = float(sz / len);
        }
        for (size_t k = 0; k < next.size(); ++k) {
            const size_t j = next[k];
            ring[j] = int32_t(r);
            state[j] = 2;
            normals[3 * j] = values[3 * k], normals[3 * j + 1] = values[3 * k + 1], normals[3 * j + 2] = values[3 * k + 2];
        }
        frontier.swap(next);
    }
}

}  // namespace ndfbake
