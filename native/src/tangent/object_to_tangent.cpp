#include "tangent/object_to_tangent.h"

#include <atomic>
#include <cmath>
#include <vector>

#include "error.h"
#include "tangent/island_padding.h"
#include "tangent/uv_raster.h"

namespace ndfbake {

namespace {

struct Vec3D {
    double x, y, z;
};
Vec3D to_d(const Vec3& v) { return {v.x, v.y, v.z}; }
Vec3D cross_d(const Vec3D& a, const Vec3D& b)
{
    return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
double dot_d(const Vec3D& a, const Vec3D& b) { return a.x * b.x + a.y * b.y + a.z * b.z; }

}  // namespace

Vec3 tangent_to_object(const TexelFrame& f, const Vec3& v)
{
    const Vec3 n = f.t * v.x + f.b * v.y + f.n * v.z;
    // The node falls back to the interpolated normal where the result has no length.
    return normalize_or(n, normalize_or(f.n, {0.0f, 0.0f, 0.0f}));
}

bool object_to_tangent(const TexelFrame& f, const Vec3& object_normal, Vec3& out)
{
    // Cramer's rule in double: the frame may be far from orthonormal (unnormalized interpolation,
    // non-orthogonal T and N), and the inverse must still be exact to float precision.
    const Vec3D t = to_d(f.t), b = to_d(f.b), n = to_d(f.n), o = to_d(object_normal);
    const Vec3D bn = cross_d(b, n);
    const double det = dot_d(t, bn);
    const double scale = std::sqrt(dot_d(t, t) * dot_d(b, b) * dot_d(n, n));
    if (!(std::fabs(det) > 1e-12 * scale) || !(scale > 0.0)) {
        out = {0.0f, 0.0f, 1.0f};
        return false;
    }
    const double x = dot_d(o, bn) / det, y = dot_d(t, cross_d(o, n)) / det, z = dot_d(t, cross_d(b, o)) / det;
    const double len = std::sqrt(x * x + y * y + z * z);
    if (!(len > 0.0) || !std::isfinite(len)) {
        out = {0.0f, 0.0f, 1.0f};
        return false;
    }
    out = {float(x / len), float(y / len), float(z / len)};
    return true;
}

size_t convert_normal_map(const MeshInput& mesh, std::span<const float> tangents, SpaceDirection direction,
                          std::span<const float> in, int width, int height, const SpaceSettings& settings,
                          std::span<float> out, std::span<uint8_t> coverage)
{
    const size_t texels = size_t(width) * height;
    if (in.size() != texels * 3 || out.size() != texels * 3 || tangents.size() != mesh.corner_count() * 4 ||
        (!coverage.empty() && coverage.size() != texels))
        throw Error(Status::invalid_argument, "convert_normal_map: array sizes do not match");
    for (size_t i = 0; i < in.size(); ++i)
        if (!std::isfinite(in[i]))
            throw Error(Status::invalid_argument, "input normal map texel " + std::to_string(i / 3) + " is not finite");

    const bool to_tangent = direction == SpaceDirection::object_to_tangent;
    for (size_t i = 0; i < texels; ++i) {
        out[3 * i] = 0.0f, out[3 * i + 1] = 0.0f, out[3 * i + 2] = to_tangent ? 1.0f : 0.0f;
    }
    const std::vector<RenderTriangle> tris = render_triangles(mesh);
    std::vector<uint8_t> state;
    std::atomic<size_t> covered{0};
    rasterize_uv(mesh, tris, width, height, settings.threads, state,
                 [&](int x, int y, uint32_t t, double b0, double b1, double b2) {
                     const double w[3] = {b0, b1, b2};
                     double T[3] = {0, 0, 0}, N[3] = {0, 0, 0}, s = 0;
                     for (int k = 0; k < 3; ++k) {
                         const uint32_t c = tris[t].corner[k];
                         const float* tk = &tangents[4 * c];
                         const Vec3 nk = mesh.normal(c);
                         T[0] += w[k] * tk[0], T[1] += w[k] * tk[1], T[2] += w[k] * tk[2];
                         s += w[k] * tk[3];
                         N[0] += w[k] * nk.x, N[1] += w[k] * nk.y, N[2] += w[k] * nk.z;
                     }
                     TexelFrame f;
                     f.t = {float(T[0]), float(T[1]), float(T[2])};
                     f.n = {float(N[0]), float(N[1]), float(N[2])};
                     // A zero N stays zero: the frame then has no inverse, as in the renderer.
                     if (settings.unit_normal) f.n = normalize_or(f.n, f.n);
                     f.b = cross(f.n, f.t) * float(s);
                     const size_t i = size_t(y) * width + x;
                     const Vec3 v{in[3 * i], in[3 * i + 1], in[3 * i + 2]};
                     Vec3 r;
                     if (to_tangent) object_to_tangent(f, v, r);
                     else r = tangent_to_object(f, v);
                     out[3 * i] = r.x, out[3 * i + 1] = r.y, out[3 * i + 2] = r.z;
                     covered.fetch_add(1, std::memory_order_relaxed);
                 });
    if (settings.padding > 0) pad_islands(out, width, height, state, settings.padding);
    if (!coverage.empty()) std::copy(state.begin(), state.end(), coverage.begin());
    return covered.load();
}

}  // namespace ndfbake
