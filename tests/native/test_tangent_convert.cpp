// Object-space <-> tangent-space normal maps: the per-texel frame is the Normal Map node's
// (unnormalized interpolation, B = sign * cross(N, T)), object_to_tangent is its exact inverse,
// islands are padded ring by ring, and rows run top to bottom. The round trip through Blender's
// own node is checked inside Blender by tests/blender/test_normal_roundtrip.py.
#include <gtest/gtest.h>

#include <chrono>
#include <cstddef>
#include <cmath>
#include <random>
#include <string>
#include <vector>

#include "ndfbake.h"
#include "tangent_fixtures.h"

namespace ndfbake {
namespace {

using tangent_testing::bumpy_grid;
using tangent_testing::kUp;
using tangent_testing::TestMesh;

class TangentConvert : public tangent_testing::ContextTest {
protected:
    // Converts `in` (w*h*3) with the given tangents (empty: computed) and padding.
    std::vector<float> convert(const TestMesh& m, const std::vector<float>& in, int w, int h, bool to_tangent,
                               uint32_t padding, std::vector<uint8_t>* coverage = nullptr,
                               const std::vector<float>& tangents = {},
                               ndfb_frame_normal frame_normal = NDFB_FRAME_NORMAL_INTERPOLATED)
    {
        const ndfb_mesh v = mesh_view(m);
        ndfb_space_options o;
        ndfb_space_options_init(&o);
        o.padding = padding;
        o.frame_normal = frame_normal;
        std::vector<float> out(in.size());
        std::vector<uint8_t> cov(size_t(w) * h);
        auto fn = to_tangent ? ndfb_object_to_tangent : ndfb_tangent_to_object;
        const ndfb_status s = fn(ctx_, &v, tangents.empty() ? nullptr : tangents.data(), tangents.size(), in.data(),
                                 uint32_t(w), uint32_t(h), in.size(), &o, out.data(), cov.data());
        EXPECT_EQ(s, NDFB_OK) << ndfb_last_error(ctx_);
        if (coverage) *coverage = cov;
        return out;
    }
};

Vec3 texel(const std::vector<float>& img, int w, int x, int y)
{
    const size_t i = 3 * (size_t(y) * w + x);
    return {img[i], img[i + 1], img[i + 2]};
}

TestMesh square(bool mirrored_uvs)
{
    TestMesh m;
    const uint32_t a = m.vertex({0, 0, 0}), b = m.vertex({2, 0, 0}), c = m.vertex({2, 2, 0}), d = m.vertex({0, 2, 0});
    if (mirrored_uvs) m.face({a, b, c, d}, {{{1, 0}}, {{0, 0}}, {{0, 1}}, {{1, 1}}}, kUp);
    else m.face({a, b, c, d}, {{{0, 0}}, {{1, 0}}, {{1, 1}}, {{0, 1}}}, kUp);
    return m;
}

TEST_F(TangentConvert, OnAFlatPlaneTheFrameIsTheUVAxesAndTheNormal)
{
    const int w = 16, h = 16;
    const Vec3 object = normalize_or(Vec3{0.3f, -0.2f, 1.0f}, kUp);
    std::vector<float> in(size_t(w) * h * 3);
    for (size_t i = 0; i < in.size(); i += 3) in[i] = object.x, in[i + 1] = object.y, in[i + 2] = object.z;
    std::vector<uint8_t> cov;
    const std::vector<float> plain = convert(square(false), in, w, h, true, 0, &cov);
    const std::vector<float> mirror = convert(square(true), in, w, h, true, 0);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            ASSERT_EQ(cov[size_t(y) * w + x], 1);
            // T = +x, B = +y: tangent space = object space.
            EXPECT_LT(length(texel(plain, w, x, y) - object), 1e-6f);
            // Mirrored UVs: T = -x, sign -1, B = -cross(N, T) = +y: only x flips.
            EXPECT_LT(length(texel(mirror, w, x, y) - Vec3{-object.x, object.y, object.z}), 1e-6f);
        }
}

// One triangle with deliberately uneven corner frames, so that normalizing T or N per pixel gives
// another answer; texel (2, 5) of an 8x8 image lies inside it.
struct UnevenTriangle {
    TestMesh mesh;
    Vec3 n0, n1, n2;
    std::vector<float> tangents{0.9f, 0.3f, -0.3f, 1.0f, 0.6f, -0.7f, 0.4f, 1.0f, 1.0f, 0.1f, 0.0f, -1.0f};
    UnevenTriangle()
        : n0(normalize_or(Vec3{0.4f, 0, 1}, kUp)), n1(normalize_or(Vec3{-0.3f, 0.5f, 1}, kUp)),
          n2(normalize_or(Vec3{0, -0.6f, 1}, kUp))
    {
        const uint32_t a = mesh.vertex({0, 0, 0}), b = mesh.vertex({1, 0, 0.3f}), c = mesh.vertex({0, 1, -0.2f});
        mesh.face({a, b, c}, {{{0.05f, 0.05f}}, {{0.95f, 0.1f}}, {{0.1f, 0.95f}}}, {n0, n1, n2});
    }
    // T, N and s interpolated (unnormalized) at texel (2, 5)'s centre u = 2.5/8, v = 1 - 5.5/8, with
    // the barycentrics solved by hand.
    void frame_at_texel(Vec3& T, Vec3& N, float& s) const
    {
        const double u = 2.5 / 8, v = 1 - 5.5 / 8;
        const double ax = 0.05, ay = 0.05, bx = 0.95, by = 0.1, cx = 0.1, cy = 0.95;
        const double det = (bx - ax) * (cy - ay) - (cx - ax) * (by - ay);
        const double l1 = ((u - ax) * (cy - ay) - (cx - ax) * (v - ay)) / det;
        const double l2 = ((bx - ax) * (v - ay) - (u - ax) * (by - ay)) / det;
        const double l0 = 1 - l1 - l2;
        const Vec3 t0{0.9f, 0.3f, -0.3f}, t1{0.6f, -0.7f, 0.4f}, t2{1.0f, 0.1f, 0.0f};
        T = t0 * float(l0) + t1 * float(l1) + t2 * float(l2);
        N = n0 * float(l0) + n1 * float(l1) + n2 * float(l2);
        s = float(l0 * 1 + l1 * 1 + l2 * -1);
    }
};

TEST_F(TangentConvert, TangentToObjectIsTheNormalMapNodeWithUnnormalizedInterpolation)
{
    const UnevenTriangle tri;
    const TestMesh& m = tri.mesh;
    const int w = 8, h = 8;
    const Vec3 tn = normalize_or(Vec3{0.35f, -0.25f, 0.9f}, kUp);
    std::vector<float> in(size_t(w) * h * 3);
    for (size_t i = 0; i < in.size(); i += 3) in[i] = tn.x, in[i + 1] = tn.y, in[i + 2] = tn.z;
    std::vector<uint8_t> cov;
    const std::vector<float> out = convert(m, in, w, h, false, 0, &cov, tri.tangents);
    const int x = 2, y = 5;
    ASSERT_EQ(cov[size_t(y) * w + x], 1);
    Vec3 T, N;
    float s;
    tri.frame_at_texel(T, N, s);
    const Vec3 B = cross(N, T) * s;
    const Vec3 expected = normalize_or(T * tn.x + B * tn.y + N * tn.z, kUp);
    EXPECT_LT(length(texel(out, w, x, y) - expected), 1e-5f);
    const Vec3 Tn = normalize_or(T, kUp), Nn = normalize_or(N, kUp);
    const Vec3 normalized_frame = normalize_or(Tn * tn.x + cross(Nn, Tn) * s * tn.y + Nn * tn.z, kUp);
    EXPECT_GT(length(normalized_frame - expected), 1e-3f);  // the negative control differs
}

TEST_F(TangentConvert, TheUnitNormalFrameNormalizesOnlyTheInterpolatedNormal)
{
    // Cycles' Normal Map node from Blender 5.1 on: N normalized, T and s as interpolated.
    const UnevenTriangle tri;
    const int w = 8, h = 8, x = 2, y = 5;
    const Vec3 tn = normalize_or(Vec3{0.35f, -0.25f, 0.9f}, kUp);
    std::vector<float> in(size_t(w) * h * 3);
    for (size_t i = 0; i < in.size(); i += 3) in[i] = tn.x, in[i + 1] = tn.y, in[i + 2] = tn.z;
    const std::vector<float> out =
        convert(tri.mesh, in, w, h, false, 0, nullptr, tri.tangents, NDFB_FRAME_NORMAL_UNIT);
    Vec3 T, N;
    float s;
    tri.frame_at_texel(T, N, s);
    const Vec3 Nn = normalize_or(N, kUp);
    const Vec3 expected = normalize_or(T * tn.x + cross(Nn, T) * s * tn.y + Nn * tn.z, kUp);
    EXPECT_LT(length(texel(out, w, x, y) - expected), 1e-5f);
    const Vec3 interpolated = normalize_or(T * tn.x + cross(N, T) * s * tn.y + N * tn.z, kUp);
    EXPECT_GT(length(interpolated - expected), 1e-3f);  // the two rules differ here
    // And the inverse is exact for this frame too.
    const std::vector<float> back =
        convert(tri.mesh, out, w, h, true, 0, nullptr, tri.tangents, NDFB_FRAME_NORMAL_UNIT);
    EXPECT_LT(length(texel(back, w, x, y) - tn), 2e-6f);
}

TEST_F(TangentConvert, AnUnknownFrameNormalIsRefusedByName)
{
    const UnevenTriangle tri;
    std::vector<float> in(8 * 8 * 3, 0.0f), out(in.size());
    for (size_t i = 2; i < in.size(); i += 3) in[i] = 1.0f;
    const ndfb_mesh v = mesh_view(tri.mesh);
    ndfb_space_options o;
    ndfb_space_options_init(&o);
    o.frame_normal = 2;
    EXPECT_EQ(ndfb_tangent_to_object(ctx_, &v, nullptr, 0, in.data(), 8, 8, in.size(), &o, out.data(), nullptr),
              NDFB_ERROR_INVALID_ARGUMENT);
    EXPECT_NE(std::string(ndfb_last_error(ctx_)).find("frame_normal"), std::string::npos) << ndfb_last_error(ctx_);
}

TEST_F(TangentConvert, ObjectToTangentIsTheExactInverse)
{
    const TestMesh m = bumpy_grid(16, 8);
    const int w = 96, h = 96;
    std::mt19937 rng(3);
    std::uniform_real_distribution<float> d(-0.6f, 0.6f);
    std::vector<float> tangent_space(size_t(w) * h * 3);
    for (size_t i = 0; i < tangent_space.size(); i += 3) {
        const Vec3 n = normalize_or(Vec3{d(rng), d(rng), 1.0f}, kUp);
        tangent_space[i] = n.x, tangent_space[i + 1] = n.y, tangent_space[i + 2] = n.z;
    }
    std::vector<uint8_t> cov;
    const std::vector<float> object = convert(m, tangent_space, w, h, false, 0, &cov);
    const std::vector<float> back = convert(m, object, w, h, true, 0);
    size_t covered = 0;
    float worst = 0;
    for (size_t i = 0; i < cov.size(); ++i) {
        if (cov[i] != 1) continue;
        ++covered;
        worst = std::max(worst, length(Vec3{back[3 * i], back[3 * i + 1], back[3 * i + 2]} -
                                       Vec3{tangent_space[3 * i], tangent_space[3 * i + 1], tangent_space[3 * i + 2]}));
    }
    EXPECT_GT(covered, size_t(w) * h / 4);
    EXPECT_LT(worst, 2e-6f);
}

TEST_F(TangentConvert, PaddingGrowsIslandsRingByRingAndRowsRunTopToBottom)
{
    // A small triangle in the top-left quarter of UV space (v near 1 = the first rows).
    TestMesh m;
    const uint32_t a = m.vertex({0, 0, 0}), b = m.vertex({1, 0, 0}), c = m.vertex({0, 1, 0});
    m.face({a, b, c}, {{{0.1f, 0.6f}}, {{0.4f, 0.6f}}, {{0.1f, 0.9f}}}, kUp);
    const int w = 32, h = 32;
    std::vector<float> in(size_t(w) * h * 3);
    for (size_t i = 0; i < in.size(); i += 3) in[i + 2] = 1.0f, in[i] = 0.2f;
    std::vector<uint8_t> cov;
    const std::vector<float> out = convert(m, in, w, h, true, 2, &cov);
    int min_row = h, max_row = -1, ring1 = -1;
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const uint8_t s = cov[size_t(y) * w + x];
            if (s == 1) min_row = std::min(min_row, y), max_row = std::max(max_row, y);
            // Distance (in rings) to the nearest rasterized texel.
            int ring = 99;
            for (int yy = 0; yy < h; ++yy)
                for (int xx = 0; xx < w; ++xx)
                    if (cov[size_t(yy) * w + xx] == 1) ring = std::min(ring, std::max(std::abs(xx - x), std::abs(yy - y)));
            if (ring == 0) continue;
            EXPECT_EQ(s, ring <= 2 ? 2 : 0) << x << "," << y;
            if (ring > 2) EXPECT_EQ(texel(out, w, x, y).z, 1.0f);
            if (ring == 1 && ring1 < 0) ring1 = y * w + x;
        }
    EXPECT_GE(min_row, int(0.1 * h) - 1);
    EXPECT_LE(max_row, int(0.4 * h) + 1);
    // A ring-1 texel is the normalized mean of its rasterized neighbours (all equal here).
    ASSERT_GE(ring1, 0);
    const Vec3 inside = texel(out, w, 4, 8);
    EXPECT_LT(length(texel(out, w, ring1 % w, ring1 / w) - normalize_or(inside, kUp)), 1e-6f);
}

TEST_F(TangentConvert, UVsFarOutsideTheImageCoverNothingAndFinishAtOnce)
{
    // Found by fuzz_tangent: a UV of 1e10 put the raster bounds out of int's range (undefined
    // behaviour, then a 2^31-texel loop per row). It must cover no texel and return at once.
    TestMesh m;
    const uint32_t a = m.vertex({0, 0, 0}), b = m.vertex({1, 0, 0}), c = m.vertex({0, 1, 0});
    m.face({a, b, c}, {{1e10f, 0.0f}, {1e10f + 1e4f, 0.0f}, {-1e11f, 1e10f}}, {kUp, kUp, kUp});
    const std::vector<float> in(8 * 8 * 3, 0.5f);
    std::vector<uint8_t> coverage;
    const auto start = std::chrono::steady_clock::now();
    convert(m, in, 8, 8, true, 0, &coverage);
    EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(), 1.0);
    for (uint8_t covered : coverage) EXPECT_EQ(covered, 0);
}

}  // namespace
}  // namespace ndfbake
