// Small meshes for the tangent tests, built face by face, and helpers to run the generator on them.
#pragma once

#include <gtest/gtest.h>

#include "ndfbake.h"

#include <array>
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "math/vec3.h"
#include "tangent/mesh_input.h"
#include "tangent/tangent_space.h"

namespace ndfbake::tangent_testing {

inline constexpr Vec3 kUp{0.0f, 0.0f, 1.0f};

// A C API context for the tangent API tests (they write no files).
class ContextTest : public ::testing::Test {
protected:
    void SetUp() override { ASSERT_EQ(ndfb_context_create(&ctx_), NDFB_OK); }
    void TearDown() override { ndfb_context_destroy(ctx_); }
    std::string error() const { return ndfb_last_error(ctx_); }

    ndfb_context ctx_ = nullptr;
};

struct TestMesh {
    std::vector<float> positions;  // per vertex
    std::vector<uint32_t> sizes, corners;
    std::vector<float> normals, uvs;  // per corner

    uint32_t vertex(const Vec3& p)
    {
        // push_back rather than insert of a list: GCC 12 warns falsely about the latter.
        positions.push_back(p.x), positions.push_back(p.y), positions.push_back(p.z);
        return uint32_t(positions.size() / 3 - 1);
    }
    // A face over existing vertices with per-corner UVs and normals.
    void face(const std::vector<uint32_t>& verts, const std::vector<std::array<float, 2>>& uv,
              const std::vector<Vec3>& n)
    {
        sizes.push_back(uint32_t(verts.size()));
        for (size_t k = 0; k < verts.size(); ++k) {
            corners.push_back(verts[k]);
            uvs.push_back(uv[k][0]), uvs.push_back(uv[k][1]);
            normals.push_back(n[k].x), normals.push_back(n[k].y), normals.push_back(n[k].z);
        }
    }
    // A face whose corner normals are all the given normal.
    void face(const std::vector<uint32_t>& verts, const std::vector<std::array<float, 2>>& uv, const Vec3& n)
    {
        face(verts, uv, std::vector<Vec3>(verts.size(), n));
    }
    size_t corner_count() const { return corners.size(); }

    MeshArrays arrays() const
    {
        MeshArrays a;
        a.positions = positions;
        a.face_sizes = sizes;
        a.corner_vertices = corners;
        a.normals = normals;
        a.uvs = uvs;
        return a;
    }
    Vec3 position_of_corner(size_t c) const
    {
        const float* p = &positions[3 * corners[c]];
        return {p[0], p[1], p[2]};
    }
    Vec3 normal(size_t c) const { return {normals[3 * c], normals[3 * c + 1], normals[3 * c + 2]}; }
};

struct Frames {
    std::vector<float> t;     // 4 per corner
    std::vector<float> mags;  // 2 per corner
    TangentStats stats;
    Vec3 tangent(size_t c) const { return {t[4 * c], t[4 * c + 1], t[4 * c + 2]}; }
    float sign(size_t c) const { return t[4 * c + 3]; }
};

// The mesh as the C API takes it: plain arrays viewed, not copied.
inline ndfb_mesh mesh_view(const TestMesh& m)
{
    ndfb_mesh v;
    ndfb_mesh_init(&v);
    v.positions = m.positions.data();
    v.vertex_count = m.positions.size() / 3;
    v.face_sizes = m.sizes.data();
    v.face_count = m.sizes.size();
    v.corner_vertices = m.corners.data();
    v.corner_count = m.corners.size();
    v.normals = m.normals.data();
    v.uvs = m.uvs.data();
    return v;
}

inline Frames frames_of(const TestMesh& m, int threads = 1)
{
    const MeshInput input = MeshInput::validate(m.arrays(), NgonPolicy::refuse);
    Frames f;
    f.t.resize(m.corner_count() * 4);
    f.mags.resize(m.corner_count() * 2);
    f.stats = generate_tangent_frames(input, threads, f.t, f.mags);
    return f;
}

inline double angle_between(const Vec3& a, const Vec3& b)
{
    const double c = dot(a, b) / (double(length(a)) * length(b));
    return std::acos(std::clamp(c, -1.0, 1.0));
}

// A bumpy grid, smooth normals from the height field, UVs = scaled positions: a mesh whose
// frames vary from corner to corner, for symmetry and order tests.
inline TestMesh bumpy_grid(int n, uint32_t seed, bool quads = false)
{
    // seed varies the height field, so different seeds give different frames.
    const float phase = float(seed % 97) * 0.1f;
    TestMesh m;
    std::vector<std::vector<uint32_t>> id(n + 1, std::vector<uint32_t>(n + 1));
    std::vector<std::vector<Vec3>> nrm(n + 1, std::vector<Vec3>(n + 1));
    auto height = [&](float x, float y) { return 0.3f * std::sin(2.1f * x + phase) * std::cos(1.7f * y); };
    for (int j = 0; j <= n; ++j)
        for (int i = 0; i <= n; ++i) {
            const float x = float(i) / n * 2.0f + 0.3f, y = float(j) / n * 2.0f - 0.7f;
            id[j][i] = m.vertex({x, y, height(x, y)});
            const float dx = 0.3f * 2.1f * std::cos(2.1f * x + phase) * std::cos(1.7f * y);
            const float dy = -0.3f * 1.7f * std::sin(2.1f * x + phase) * std::sin(1.7f * y);
            nrm[j][i] = normalize_or(Vec3{-dx, -dy, 1.0f}, {0, 0, 1});
        }
    auto uv = [&](int i, int j) {
        const float* p = &m.positions[3 * id[j][i]];
        return std::array<float, 2>{0.4f * p[0] + 0.05f * p[1], 0.45f * p[1]};
    };
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
            const uint32_t a = id[j][i], b = id[j][i + 1], c = id[j + 1][i + 1], d = id[j + 1][i];
            if (quads) {
                m.face({a, b, c, d}, {uv(i, j), uv(i + 1, j), uv(i + 1, j + 1), uv(i, j + 1)},
                       {nrm[j][i], nrm[j][i + 1], nrm[j + 1][i + 1], nrm[j + 1][i]});
            } else {
                m.face({a, b, c}, {uv(i, j), uv(i + 1, j), uv(i + 1, j + 1)}, {nrm[j][i], nrm[j][i + 1], nrm[j + 1][i + 1]});
                m.face({a, c, d}, {uv(i, j), uv(i + 1, j + 1), uv(i, j + 1)}, {nrm[j][i], nrm[j + 1][i + 1], nrm[j + 1][i]});
            }
        }
    return m;
}

}  // namespace ndfbake::tangent_testing
