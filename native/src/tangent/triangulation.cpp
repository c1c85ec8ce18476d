#include "tangent/triangulation.h"

#include "tangent/parallel_for.h"

namespace ndfbake {

namespace {

float squared_uv_distance(const Vec2& a, const Vec2& b)
{
    // MikkTSpace treats UVs as 3-vectors with z = 1; keep the same sum so ties are bit-identical.
    const float dx = a.x - b.x, dy = a.y - b.y, dz = 0.0f;
    return dx * dx + dy * dy + dz * dz;
}

float squared_distance(const Vec3& a, const Vec3& b)
{
    const Vec3 d = a - b;
    return d.x * d.x + d.y * d.y + d.z * d.z;
}

}  // namespace

bool mikk_quad_splits_02(const MeshInput& mesh, size_t face)
{
    const uint32_t o = mesh.face_offset(face);
    const float uv02 = squared_uv_distance(mesh.uv(o + 2), mesh.uv(o));
    const float uv13 = squared_uv_distance(mesh.uv(o + 3), mesh.uv(o + 1));
    if (uv02 != uv13) return uv02 < uv13;
    const float p02 = squared_distance(mesh.position(o + 2), mesh.position(o));
    const float p13 = squared_distance(mesh.position(o + 3), mesh.position(o + 1));
    return !(p13 < p02);
}

BigVector<MeshTriangle> mikk_triangles(const MeshInput& mesh, int threads)
{
    const size_t faces = mesh.face_count();
    // Triangle index of each face = face index + quads before it: a prefix sum, then a parallel fill.
    std::vector<uint32_t> first(faces);
    uint32_t count = 0;
    for (size_t f = 0; f < faces; ++f) {
        first[f] = count;
        count += mesh.face_size(f) == 4 ? 2u : 1u;
    }
    BigVector<MeshTriangle> tris(count);
    parallel_for(faces, threads, 1 << 14, [&](size_t begin, size_t end) {
        for (size_t f = begin; f < end; ++f) {
            const uint32_t o = mesh.face_offset(f);
            MeshTriangle* t = &tris[first[f]];
            if (mesh.face_size(f) == 3) {
                t[0] = {{o, o + 1, o + 2}, uint32_t(f)};
            } else if (mikk_quad_splits_02(mesh, f)) {
                t[0] = {{o, o + 1, o + 2}, uint32_t(f)};
                t[1] = {{o, o + 2, o + 3}, uint32_t(f)};
            } else {
                t[0] = {{o, o + 1, o + 3}, uint32_t(f)};
                t[1] = {{o + 1, o + 2, o + 3}, uint32_t(f)};
            }
        }
    });
    return tris;
}

bool render_quad_splits_02(const MeshInput& mesh, size_t face)
{
    // The 0-2 split is wrong for the renderer exactly when the two halves face opposite ways,
    // i.e. the quad is concave at corner 1 or 3.
    const uint32_t o = mesh.face_offset(face);
    const Vec3 p0 = mesh.position(o), p1 = mesh.position(o + 1), p2 = mesh.position(o + 2), p3 = mesh.position(o + 3);
    const Vec3 n012 = cross(p1 - p0, p2 - p0);
    const Vec3 n023 = cross(p2 - p0, p3 - p0);
    return dot(n012, n023) >= 0.0f;
}

}  // namespace ndfbake
