// The tangent module through its C API: bad meshes give clear errors (never a crash), vertex
// splits never weld across a mirror seam, texel densities and diagnostics match hand-computed
// values, and the object <-> tangent space conversion is the exact inverse of the Normal Map
// node's per-pixel frame.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <cstddef>
#include <cstring>
#include <limits>
#include <set>
#include <string>
#include <tuple>
#include <vector>

#include "ndfbake.h"
#include "tangent_fixtures.h"

namespace ndfbake {
namespace {

using tangent_testing::bumpy_grid;
using tangent_testing::kUp;
using tangent_testing::TestMesh;

class TangentApi : public tangent_testing::ContextTest {
protected:
    static ndfb_mesh view(const TestMesh& m) { return mesh_view(m); }
    ndfb_status tangents(const TestMesh& m, std::vector<float>& out)
    {
        const ndfb_mesh v = view(m);
        out.assign(m.corner_count() * 4, 0.0f);
        return ndfb_tangents(ctx_, &v, 0, out.data(), out.size(), nullptr, 0);
    }
};

TestMesh unit_square()
{
    TestMesh m;
    const uint32_t a = m.vertex({0, 0, 0}), b = m.vertex({2, 0, 0}), c = m.vertex({2, 2, 0}), d = m.vertex({0, 2, 0});
    m.face({a, b, c, d}, {{{0, 0}}, {{1, 0}}, {{1, 1}}, {{0, 1}}}, kUp);
    return m;
}

TEST_F(TangentApi, BadMeshesAreRefusedWithMessagesNamingTheElement)
{
    std::vector<float> out;
    TestMesh m = unit_square();
    m.positions[4] = std::numeric_limits<float>::quiet_NaN();
    EXPECT_EQ(tangents(m, out), NDFB_ERROR_INVALID_ARGUMENT);
    EXPECT_NE(error().find("position of vertex 1 is not finite"), std::string::npos) << error();

    m = unit_square();
    m.corners[2] = 7;
    EXPECT_EQ(tangents(m, out), NDFB_ERROR_INVALID_ARGUMENT);
    EXPECT_NE(error().find("corner 2 refers to vertex 7 but the mesh has 4 vertices"), std::string::npos) << error();

    m = unit_square();
    m.uvs[5] = std::numeric_limits<float>::infinity();
    EXPECT_EQ(tangents(m, out), NDFB_ERROR_INVALID_ARGUMENT);
    EXPECT_NE(error().find("uv of corner 2 is not finite"), std::string::npos) << error();

    m = unit_square();
    m.sizes = {5};
    m.corners.push_back(0), m.uvs.insert(m.uvs.end(), {0, 0}), m.normals.insert(m.normals.end(), {0, 0, 1});
    EXPECT_EQ(tangents(m, out), NDFB_ERROR_INVALID_ARGUMENT);
    EXPECT_NE(error().find("face 0 has 5 corners"), std::string::npos) << error();
    EXPECT_NE(error().find("triangulate"), std::string::npos) << error();

    m = unit_square();
    m.sizes = {3};
    EXPECT_EQ(tangents(m, out), NDFB_ERROR_INVALID_ARGUMENT);
    EXPECT_NE(error().find("face sizes add up to 3 corners but corner_vertices holds 4"), std::string::npos) << error();

    ndfb_mesh empty;
    ndfb_mesh_init(&empty);
    out.assign(4, 0.0f);
    EXPECT_EQ(ndfb_tangents(ctx_, &empty, 0, out.data(), out.size(), nullptr, 0), NDFB_ERROR_INVALID_ARGUMENT);
    EXPECT_NE(error().find("no faces"), std::string::npos) << error();

    m = unit_square();
    ndfb_mesh v = view(m);
    for (uint32_t size : {0u, 4u, uint32_t(offsetof(ndfb_mesh, uv_domain))}) {  // too short to hold every field
        v.struct_size = size;
        EXPECT_EQ(ndfb_tangents(ctx_, &v, 0, out.data(), out.size(), nullptr, 0), NDFB_ERROR_INVALID_ARGUMENT) << size;
        EXPECT_NE(error().find("ndfb_mesh_init"), std::string::npos) << error();
    }

    // A domain that is no enumerator, stored as a C caller would (an int): refused, and read as
    // an int (exports' raw()), since a load through the enum type is undefined (UBSan: enum).
    for (auto [field, value, says] : {std::tuple{&ndfb_mesh::normal_domain, 7, "unknown normal domain 7"},
                                      std::tuple{&ndfb_mesh::uv_domain, -1, "unknown uv domain -1"}}) {
        v = view(m);
        std::memcpy(&(v.*field), &value, sizeof value);
        out.assign(16, 0.0f);
        EXPECT_EQ(ndfb_tangents(ctx_, &v, 0, out.data(), out.size(), nullptr, 0), NDFB_ERROR_INVALID_ARGUMENT);
        EXPECT_NE(error().find(says), std::string::npos) << error();
    }

    v = view(m);
    out.assign(15, 0.0f);
    EXPECT_EQ(ndfb_tangents(ctx_, &v, 0, out.data(), out.size(), nullptr, 0), NDFB_ERROR_INVALID_ARGUMENT);
    EXPECT_NE(error().find("expected 16 elements, got 15"), std::string::npos) << error();
    EXPECT_EQ(ndfb_tangents(ctx_, nullptr, 0, out.data(), out.size(), nullptr, 0), NDFB_ERROR_INVALID_ARGUMENT);
    EXPECT_EQ(ndfb_tangents(ctx_, &v, 0, nullptr, 16, nullptr, 0), NDFB_ERROR_INVALID_ARGUMENT);

    // A good call clears the message.
    EXPECT_EQ(tangents(unit_square(), out), NDFB_OK);
    EXPECT_EQ(error(), "");
}

TEST_F(TangentApi, TenMillionCoincidentVerticesGiveDefaultFramesQuickly)
{
    // Every vertex at one position: every triangle is degenerate. The welding must stay linear.
    TestMesh m;
    const size_t vertices = 10'000'000;
    m.positions.assign(vertices * 3, 0.5f);
    for (uint32_t t = 0; t < 3000; ++t) {
        const uint32_t base = uint32_t((uint64_t(t) * 3331) % (vertices - 3));
        m.face({base, base + 1, base + 2}, {{{0, 0}}, {{1, 0}}, {{0, 1}}}, kUp);
    }
    std::vector<float> out;
    const auto start = std::chrono::steady_clock::now();
    ASSERT_EQ(tangents(m, out), NDFB_OK) << error();
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    EXPECT_LT(seconds, 5.0);
    for (size_t c = 0; c < m.corner_count(); ++c) {
        EXPECT_EQ(out[4 * c], 1.0f);
        EXPECT_EQ(out[4 * c + 3], -1.0f);
    }
}

TEST_F(TangentApi, SplitsNeverWeldAcrossAMirrorSeam)
{
    // Two quads sharing the edge x = 0; the left one's UVs are the right one's mirrored, and the
    // seam vertices share position, normal and UV: only the sign tells the corners apart.
    TestMesh m;
    const uint32_t s0 = m.vertex({0, 0, 0}), s1 = m.vertex({0, 1, 0});
    const uint32_t r0 = m.vertex({1, 0, 0}), r1 = m.vertex({1, 1, 0}), l0 = m.vertex({-1, 0, 0}), l1 = m.vertex({-1, 1, 0});
    m.face({s0, r0, r1, s1}, {{{0, 0}}, {{1, 0}}, {{1, 1}}, {{0, 1}}}, kUp);
    m.face({l0, s0, s1, l1}, {{{1, 0}}, {{0, 0}}, {{0, 1}}, {{1, 1}}}, kUp);
    const ndfb_mesh v = view(m);
    std::vector<uint32_t> corner_to_vertex(m.corner_count()), source(m.corner_count());
    ndfb_split_stats stats{};
    ASSERT_EQ(ndfb_split_vertices(ctx_, &v, nullptr, 0, 0, corner_to_vertex.data(), corner_to_vertex.size(),
                                  source.data(), source.size(), &stats),
              NDFB_OK)
        << error();
    EXPECT_EQ(stats.input_vertices, 6u);
    EXPECT_EQ(stats.output_vertices, 8u);
    EXPECT_EQ(stats.mirror_seams, 2u);
    EXPECT_EQ(stats.uv_seams + stats.hard_edges + stats.tangent_splits, 0u);
    std::vector<float> t;
    ASSERT_EQ(tangents(m, t), NDFB_OK);
    for (size_t a = 0; a < m.corner_count(); ++a) {
        EXPECT_EQ(source[corner_to_vertex[a]], m.corners[a]);
        for (size_t b = 0; b < m.corner_count(); ++b)
            if (corner_to_vertex[a] == corner_to_vertex[b])
                EXPECT_EQ(std::memcmp(&t[4 * a], &t[4 * b], 16), 0) << a << " and " << b << " share a vertex";
    }
}

TEST_F(TangentApi, AMeshWithoutSplitsKeepsItsVertexNumbering)
{
    const TestMesh m = bumpy_grid(8, 1);
    const ndfb_mesh v = view(m);
    std::vector<uint32_t> corner_to_vertex(m.corner_count()), source(m.corner_count());
    ndfb_split_stats stats{};
    ASSERT_EQ(ndfb_split_vertices(ctx_, &v, nullptr, 0, 0, corner_to_vertex.data(), corner_to_vertex.size(),
                                  source.data(), source.size(), &stats),
              NDFB_OK);
    EXPECT_EQ(stats.output_vertices, stats.input_vertices);
    EXPECT_EQ(corner_to_vertex, m.corners);
}

// Found by fuzz_tangent (corpus/tangent/huge-uv-tiny-positions): UV areas past float's range on a
// face of 1e-34-sized positions and normals of length 1e10 or 0.
TEST_F(TangentApi, FramesStayFiniteWhereUVAreasOverflowFloat)
{
    TestMesh m;
    const uint32_t a = m.vertex({1.01583363e-34f, 1.01583363e-34f, 1.68155816e-44f});
    const uint32_t b = m.vertex({0, 0, 0}), c = m.vertex({1.01583363e-34f, 1.01583363e-34f, 1.01583363e-34f});
    const float big = -6.97300531e+09f;
    m.face({a, a, b, c},
           {{{720.549683f, -3.06676017e+22f}}, {{big, big}}, {{big, big}}, {{1.31716346e+32f, -8.58993408e+09f}}},
           std::vector<Vec3>{{big, big, big}, {big, big, big}, {0, 0, 0}, {0, 0, 0}});
    const ndfb_mesh v = view(m);
    std::vector<float> tangents(4 * 4), magnitudes(4 * 2);
    ASSERT_EQ(ndfb_tangents(ctx_, &v, 1, tangents.data(), tangents.size(), magnitudes.data(), magnitudes.size()),
              NDFB_OK) << error();
    for (float t : tangents) EXPECT_TRUE(std::isfinite(t));
    for (float t : magnitudes) EXPECT_TRUE(std::isfinite(t));
}

// Also from fuzz_tangent: coordinates near float's range over a tiny UV area make |dP/du| ~1e41.
TEST_F(TangentApi, DerivativeLengthsPastFloatRangeAreCappedAndTangentsStayUnit)
{
    TestMesh m;
    const uint32_t a = m.vertex({0, 0, 0}), b = m.vertex({3e38f, 0, 0}), c = m.vertex({0, 3e38f, 0});
    m.face({a, b, c}, {{{0, 0}}, {{1e-3f, 0}}, {{0, 1e-3f}}}, kUp);
    const ndfb_mesh v = view(m);
    std::vector<float> tangents(3 * 4), magnitudes(3 * 2);
    ASSERT_EQ(ndfb_tangents(ctx_, &v, 1, tangents.data(), tangents.size(), magnitudes.data(), magnitudes.size()),
              NDFB_OK) << error();
    for (int corner = 0; corner < 3; ++corner) {
        EXPECT_NEAR(tangents[corner * 4], 1.0f, 1e-6f);  // +X, as dP/du points
        EXPECT_EQ(magnitudes[corner * 2], 1e30f);
        EXPECT_EQ(magnitudes[corner * 2 + 1], 1e30f);
    }
}

// Also from fuzz_tangent (corpus/tangent/small-angle-sine-overflow): a sliver corner whose edges
// are each finite in float when squared (|e|² = 1e38) but not multiplied together; the corner
// angle is taken from their cross product, which overflowed, and its weight came out infinite.
TEST_F(TangentApi, SliverCornersOfHugeEdgesKeepFiniteWeights)
{
    TestMesh m;
    const uint32_t a = m.vertex({0, 0, 0}), b = m.vertex({1e19f, 0, 0}), c = m.vertex({1e19f, 1e14f, 0});
    m.face({a, b, c}, {{{0, 0}}, {{1, 0}}, {{1, 1e-5f}}}, kUp);
    const ndfb_mesh v = view(m);
    std::vector<float> tangents(3 * 4), magnitudes(3 * 2);
    ASSERT_EQ(ndfb_tangents(ctx_, &v, 1, tangents.data(), tangents.size(), magnitudes.data(), magnitudes.size()),
              NDFB_OK) << error();
    for (int corner = 0; corner < 3; ++corner) {
        EXPECT_NEAR(tangents[corner * 4], 1.0f, 1e-6f) << "corner " << corner;  // +X, as dP/du points
        EXPECT_NEAR(magnitudes[corner * 2], 1e19f, 1e14f) << "corner " << corner;  // |dP/du|
        EXPECT_NEAR(magnitudes[corner * 2 + 1], 1e19f, 1e14f) << "corner " << corner;  // |dP/dv|
    }
}

TEST_F(TangentApi, SliverCornersOfTinyEdgesKeepUnitTangents)
{
    // Edges of 1e-12: |q1|²|q2|² underflows, and with it the small-angle sine of the thin corner;
    // MikkTSpace still weights that corner by its angle (0.005 rad) and gives a unit tangent.
    TestMesh m;
    const float s = 1e-12f;
    const uint32_t a = m.vertex({0, 0, 0}), b = m.vertex({s, 0, 0}), c = m.vertex({s, 0.005f * s, 0});
    m.face({a, b, c}, {{{0, 0}}, {{1, 0}}, {{1, 0.005f}}}, kUp);
    const ndfb_mesh v = view(m);
    std::vector<float> tangents(3 * 4);
    ASSERT_EQ(ndfb_tangents(ctx_, &v, 1, tangents.data(), tangents.size(), nullptr, 0), NDFB_OK) << error();
    for (int corner = 0; corner < 3; ++corner) {
        EXPECT_NEAR(tangents[corner * 4], 1.0f, 1e-6f) << "corner " << corner;  // +X, as dP/du points
        EXPECT_EQ(tangents[corner * 4 + 3], 1.0f) << "corner " << corner;
    }
}

TEST_F(TangentApi, TexelDensityIsTheSquareRootOfUVAreaOverWorldArea)
{
    TestMesh m = unit_square();  // 2 x 2 world units mapped onto the unit UV square
    const uint32_t a = m.vertex({0, 0, 1}), b = m.vertex({1, 0, 1}), c = m.vertex({0, 1, 1});
    m.face({a, b, c}, {{{0, 0}}, {{2, 0}}, {{0, 2}}}, kUp);        // 0.5 world, 2 UV: density 2
    m.face({a, b, c}, {{{0.3f, 0.3f}}, {{0.3f, 0.3f}}, {{0.3f, 0.3f}}}, kUp);  // no UV area: 0
    // World area 1e-60 under UV area 0.5: a density of 1e30 overflows no float; 1e-80 would.
    const uint32_t tiny_b = m.vertex({1e-30f, 0, 1}), tiny_c = m.vertex({0, 1e-30f, 1});
    const uint32_t tinier_b = m.vertex({1e-40f, 0, 1}), tinier_c = m.vertex({0, 1e-40f, 1});
    m.face({a, tiny_b, tiny_c}, {{{0, 0}}, {{1, 0}}, {{0, 1}}}, kUp);
    m.face({a, tinier_b, tinier_c}, {{{0, 0}}, {{1, 0}}, {{0, 1}}}, kUp);
    const ndfb_mesh v = view(m);
    std::vector<float> density(5);
    double total = 0;
    ASSERT_EQ(ndfb_texel_density(ctx_, &v, density.data(), density.size(), &total), NDFB_OK) << error();
    EXPECT_NEAR(density[0], 0.5, 1e-6);
    EXPECT_NEAR(density[1], 2.0, 1e-6);
    EXPECT_EQ(density[2], 0.0f);
    EXPECT_NEAR(density[3], 1e30f, 1e24f);
    EXPECT_EQ(density[4], 0.0f);  // sqrt(0.5 / 5e-81) is past float's range: no usable world area
    EXPECT_NEAR(total, std::sqrt(4.0 / 5.0), 1e-6);
}

TEST_F(TangentApi, DiagnosticsCountWhatAUserCanFix)
{
    TestMesh m;
    auto v = [&](float x, float y, float z) { return m.vertex({x, y, z}); };
    // 0: a pentagon (n-gon).
    m.face({v(0, 0, 0), v(1, 0, 0), v(1.5f, 1, 0), v(0.5f, 1.5f, 0), v(-0.5f, 1, 0)},
           {{{0, 0}}, {{0.1f, 0}}, {{0.15f, 0.1f}}, {{0.05f, 0.15f}}, {{-0.05f, 0.1f}}}, kUp);
    // 1: collinear positions (degenerate).
    m.face({v(3, 0, 0), v(4, 0, 0), v(5, 0, 0)}, {{{0.3f, 0.3f}}, {{0.4f, 0.3f}}, {{0.35f, 0.4f}}}, kUp);
    // 2: zero UV area.
    m.face({v(6, 0, 0), v(7, 0, 0), v(6, 1, 0)}, {{{0.5f, 0.5f}}, {{0.5f, 0.5f}}, {{0.5f, 0.5f}}}, kUp);
    // 3: a mirrored island (clockwise UVs).
    m.face({v(8, 0, 0), v(9, 0, 0), v(8, 1, 0)}, {{{0.7f, 0.7f}}, {{0.6f, 0.7f}}, {{0.7f, 0.8f}}}, kUp);
    // 4, 5: an island folded over its shared UV edge (both third UVs on one side).
    const uint32_t p = v(10, 0, 0), q = v(11, 0, 0), r = v(10, 1, 0), s = v(11, 1, 0);
    m.face({p, q, r}, {{{0.8f, 0.1f}}, {{0.9f, 0.1f}}, {{0.8f, 0.2f}}}, kUp);
    m.face({q, s, r}, {{{0.9f, 0.1f}}, {{0.82f, 0.12f}}, {{0.8f, 0.2f}}}, kUp);
    // 6: normals against the winding.
    m.face({v(12, 0, 0), v(13, 0, 0), v(12, 1, 0)}, {{{0.2f, 0.6f}}, {{0.3f, 0.6f}}, {{0.2f, 0.7f}}}, kUp * -1.0f);
    const ndfb_mesh view_ = view(m);
    ndfb_mesh_report r_{};
    char text[2048];
    ASSERT_EQ(ndfb_mesh_diagnose(ctx_, &view_, &r_, text, sizeof text, nullptr), NDFB_OK) << error();
    EXPECT_EQ(r_.faces, 7u);
    EXPECT_EQ(r_.ngons, 1u);
    EXPECT_EQ(r_.ngon_first, 0);
    EXPECT_EQ(r_.degenerate_triangles, 1u);
    EXPECT_EQ(r_.degenerate_first, 1);
    EXPECT_EQ(r_.zero_area_uv_triangles, 1u);
    EXPECT_EQ(r_.zero_area_uv_first, 2);
    EXPECT_EQ(r_.mirrored_islands, 1u);
    EXPECT_EQ(r_.flipped_islands, 1u);
    EXPECT_EQ(r_.flipped_triangles, 1u);
    EXPECT_EQ(r_.flipped_first, 5);
    EXPECT_EQ(r_.inverted_normal_faces, 1u);
    EXPECT_EQ(r_.inverted_normal_first, 6);
    const std::string s_ = text;
    for (const char* phrase : {"n-gons: 1 (first: face 0)", "degenerate triangles: 1", "flipped islands: 1",
                               "inverted normals: 1", "mirrored islands: 1"})
        EXPECT_NE(s_.find(phrase), std::string::npos) << phrase << "\n" << s_;
    // The same mesh is refused for frames, with the reason.
    std::vector<float> out;
    EXPECT_EQ(tangents(m, out), NDFB_ERROR_INVALID_ARGUMENT);
}

}  // namespace
}  // namespace ndfbake
