#include "tangent/weld.h"

#include <algorithm>
#include <bit>
#include <cstring>

namespace ndfbake {

BigVector<uint32_t> position_classes(const MeshInput& mesh)
{
    const size_t n = mesh.vertex_count();
    BigVector<uint32_t> cls(n);
    // Open addressing over vertex indices; load factor at most 1/2 keeps probes short.
    const size_t capacity = std::bit_ceil(std::max<size_t>(2 * n, 16));
    const size_t mask = capacity - 1;
    constexpr uint32_t kEmpty = 0xffffffffu;
    BigVector<uint32_t> table(capacity, kEmpty);
    for (size_t v = 0; v < n; ++v) {
        const Vec3 p = mesh.vertex_position(v);
        uint32_t bits[3];
        std::memcpy(bits, &p, sizeof bits);
        uint64_t h = (uint64_t(bits[0]) * 0x9E3779B97F4A7C15ull) ^ (uint64_t(bits[1]) * 0xC2B2AE3D27D4EB4Full) ^
                     (uint64_t(bits[2]) * 0x165667B19E3779F9ull);
        h ^= h >> 29;
        size_t slot = size_t(h) & mask;
        for (;;) {
            const uint32_t other = table[slot];
            if (other == kEmpty) {
                table[slot] = uint32_t(v);
                cls[v] = uint32_t(v);
                break;
            }
            const Vec3 q = mesh.vertex_position(other);
            if (std::memcmp(&p, &q, sizeof p) == 0) {
                cls[v] = other;
                break;
            }
            slot = (slot + 1) & mask;
        }
    }
    return cls;
}

}  // namespace ndfbake
