#include "tangent/texel_density.h"

#include <cmath>
#include <limits>

#include "error.h"

namespace ndfbake {

FaceAreas face_areas(const MeshInput& mesh, size_t face)
{
    const uint32_t o = mesh.face_offset(face), n = mesh.face_size(face);
    // Relative to the first corner: areas of small faces far from the origin keep their digits.
    const Vec3 p0 = mesh.position(o);
    const Vec2 t0 = mesh.uv(o);
    double ax = 0, ay = 0, az = 0, uv = 0;
    for (uint32_t k = 1; k + 1 < n; ++k) {
        const Vec3 a = mesh.position(o + k) - p0, b = mesh.position(o + k + 1) - p0;
        ax += double(a.y) * b.z - double(a.z) * b.y;
        ay += double(a.z) * b.x - double(a.x) * b.z;
        az += double(a.x) * b.y - double(a.y) * b.x;
        const Vec2 s = mesh.uv(o + k), t = mesh.uv(o + k + 1);
        uv += (double(s.x) - t0.x) * (double(t.y) - t0.y) - (double(s.y) - t0.y) * (double(t.x) - t0.x);
    }
    FaceAreas f;
    f.world = 0.5 * std::sqrt(ax * ax + ay * ay + az * az);
    f.signed_uv = 0.5 * uv;
    f.uv = std::fabs(f.signed_uv);
    return f;
}

double texel_density(const MeshInput& mesh, std::span<float> face_density)
{
    if (face_density.size() != mesh.face_count())
        throw Error(Status::invalid_argument, "texel_density: one value per face expected");
    double world = 0.0, uv = 0.0;
    for (size_t f = 0; f < mesh.face_count(); ++f) {
        const FaceAreas a = face_areas(mesh, f);
        // A face of next to no world area under real UV area has a density past float's range
        // (found by fuzz_tangent): it has no usable world area either.
        const double density = a.world > 0.0 && a.uv > 0.0 ? std::sqrt(a.uv / a.world) : 0.0;
        face_density[f] = density <= double(std::numeric_limits<float>::max()) ? float(density) : 0.0f;
        world += a.world;
        uv += a.uv;
    }
    return world > 0.0 && uv > 0.0 ? std::sqrt(uv / world) : 0.0;
}

}  // namespace ndfbake
