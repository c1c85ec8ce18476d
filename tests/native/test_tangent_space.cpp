// MikkTSpace-compatible frames: analytic derivatives, orientation signs, the four connectivity
// rules, mirror exactness, order independence, corner-angle weighting, quad splits and the
// reference's handling of degenerate triangles. Agreement with Blender's own calc_tangents() on
// real meshes is checked inside Blender by tests/blender/test_tangents.py.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <numeric>
#include <random>

#include "tangent/tangent_math.h"
#include "tangent_fixtures.h"

namespace ndfbake {
namespace {

using tangent_testing::angle_between;
using tangent_testing::bumpy_grid;
using tangent_testing::Frames;
using tangent_testing::frames_of;
using tangent_testing::TestMesh;

using tangent_testing::kUp;

Vec3 project(const Vec3& n, const Vec3& v) { return normalize_or(v - n * dot(n, v), {0, 0, 0}); }

// dP/du of a triangle from eq. 42, in double: the independent truth for derivatives.
Vec3 dp_du(const Vec3& p0, const Vec3& p1, const Vec3& p2, std::array<float, 2> t0, std::array<float, 2> t1,
           std::array<float, 2> t2)
{
    const double s1 = t1[0] - t0[0], s2 = t2[0] - t0[0], r1 = t1[1] - t0[1], r2 = t2[1] - t0[1];
    const double det = s1 * r2 - s2 * r1;
    const Vec3 e1 = p1 - p0, e2 = p2 - p0;
    return {float((r2 * e1.x - r1 * e2.x) / det), float((r2 * e1.y - r1 * e2.y) / det),
            float((r2 * e1.z - r1 * e2.z) / det)};
}

TEST(TangentMath, NormalizeKeepZeroIsUnitWhereverTheSquaredLengthLeavesFloatRange)
{
    // Squares below FLT_MIN (denormal, or zero), normal, and overflowing.
    for (float scale : {1e-42f, 1e-30f, 1.3e-19f, 1e-10f, 1.0f, 1e10f, 1e25f, 3e38f}) {
        for (const Vec3& direction : {Vec3{0, 0, -1}, Vec3{0.6f, -0.8f, 0}, Vec3{1, 2, 2}}) {
            const Vec3 v = direction * scale;
            const float largest = std::max({std::fabs(v.x), std::fabs(v.y), std::fabs(v.z)});
            if (!(largest > 0.0f) || !std::isfinite(largest)) continue;  // underflowed or overflowed
            const Vec3 n = normalize_keep_zero(v);
            EXPECT_NEAR(length(n), 1.0f, 1e-6f) << scale;
            EXPECT_GT(dot(n, direction), 0.0f) << scale;
        }
    }
    EXPECT_EQ(length(normalize_keep_zero(Vec3{})), 0.0f);
    EXPECT_EQ(length(normalize_keep_zero(Vec3{INFINITY, 1, 0})), 0.0f);
}

TEST(TangentFrames, PlaneWithAffineUVsHasTheAnalyticFrameAndMagnitudes)
{
    // P(u, v) = u (2, 0, 0) + v (0.5, 3, 0): dP/du = (2, 0, 0), dP/dv = (0.5, 3, 0).
    TestMesh m;
    const uint32_t a = m.vertex({0, 0, 0}), b = m.vertex({2, 0, 0}), c = m.vertex({2.5f, 3, 0}), d = m.vertex({0.5f, 3, 0});
    m.face({a, b, c, d}, {{{0, 0}}, {{1, 0}}, {{1, 1}}, {{0, 1}}}, kUp);
    const Frames f = frames_of(m);
    for (size_t k = 0; k < 4; ++k) {
        EXPECT_LT(angle_between(f.tangent(k), {1, 0, 0}), 1e-6) << k;
        EXPECT_EQ(f.sign(k), 1.0f);
        EXPECT_NEAR(f.mags[2 * k], 2.0, 1e-5);
        EXPECT_NEAR(f.mags[2 * k + 1], std::sqrt(0.25 + 9.0), 1e-5);
        // The reconstructed bitangent sign*cross(n, t) points along the real dP/dv.
        EXPECT_GT(dot(cross(kUp, f.tangent(k)) * f.sign(k), Vec3{0.5f, 3, 0}), 0.0f);
    }
}

TEST(TangentFrames, MirroredUVsFlipTheSignAndKeepTheBitangentAlongV)
{
    TestMesh m;
    const uint32_t a = m.vertex({0, 0, 0}), b = m.vertex({2, 0, 0}), c = m.vertex({2, 2, 0}), d = m.vertex({0, 2, 0});
    m.face({a, b, c, d}, {{{1, 0}}, {{0, 0}}, {{0, 1}}, {{1, 1}}}, kUp);  // u runs against x: clockwise UVs
    const Frames f = frames_of(m);
    for (size_t k = 0; k < 4; ++k) {
        EXPECT_LT(angle_between(f.tangent(k), {-1, 0, 0}), 1e-6);
        EXPECT_EQ(f.sign(k), -1.0f);
        const Vec3 bitangent = cross(kUp, f.tangent(k)) * f.sign(k);
        EXPECT_LT(angle_between(bitangent, {0, 1, 0}), 1e-6);
    }
}

// Two triangles sharing the edge v1-v2, the second bent up so the two dP/du differ. `variant`
// breaks one rule on the second triangle's copy of the edge.
enum class Variant { shared, hard_edge, uv_seam, folded, far_end_seam };
struct Hinge {
    TestMesh mesh;
    Vec3 own_first, own_second;  // each triangle's dP/du projected on the normal at v1
};
Hinge hinge(Variant variant)
{
    Hinge h;
    TestMesh& m = h.mesh;
    const Vec3 p0{0, 0, 0}, p1{1, 0, 0}, p2{0.4f, 1, 0}, p3{1.6f, 1.1f, 0.5f};
    const uint32_t v0 = m.vertex(p0), v1 = m.vertex(p1), v2 = m.vertex(p2), v3 = m.vertex(p3);
    const Vec3 n = normalize_or(Vec3{0.1f, -0.2f, 1}, kUp);
    const std::array<float, 2> t0{{0, 0}}, t1{{1, 0}}, t2{{0.3f, 1}}, t3{{1.4f, 0.8f}};
    m.face({v0, v1, v2}, {t0, t1, t2}, n);
    std::array<float, 2> s1 = t1, s2 = t2, s3 = t3;
    Vec3 n1 = n;
    if (variant == Variant::hard_edge) n1 = normalize_or(Vec3{-0.3f, 0.1f, 1}, kUp);
    if (variant == Variant::uv_seam) s1 = {1.5f, 0.2f}, s2 = {0.8f, 1.2f}, s3 = {1.9f, 1.0f};
    if (variant == Variant::folded) s3 = {0.1f, -0.5f};  // third UV on the same side as t0: a fold
    if (variant == Variant::far_end_seam) s2 = {0.3f, 1.25f}, s3 = {1.4f, 1.05f};  // edge differs only at v2
    m.face({v1, v3, v2}, {s1, s3, s2}, {n1, n, variant == Variant::hard_edge ? n1 : n});
    h.own_first = project(n, dp_du(p0, p1, p2, t0, t1, t2));
    h.own_second = project(n1, dp_du(p1, p3, p2, s1, s3, s2));
    return h;
}

TEST(TangentFrames, AllFourRulesMakeOneFrameAtTheSharedVertex)
{
    const Hinge h = hinge(Variant::shared);
    const Frames f = frames_of(h.mesh);
    // Corner 1 (first triangle) and corner 3 (second triangle) are both at v1.
    EXPECT_LT(angle_between(f.tangent(1), f.tangent(3)), 1e-7);
    EXPECT_GT(angle_between(f.tangent(1), h.own_first), 0.05);
    EXPECT_GT(angle_between(f.tangent(3), h.own_second), 0.05);
    EXPECT_EQ(f.stats.groups, 4u);  // v0, v1, v2 shared, v3
}

TEST(TangentFrames, BreakingAnyRuleSplitsTheFrameAtTheSharedVertex)
{
    for (const Variant v : {Variant::hard_edge, Variant::uv_seam, Variant::folded, Variant::far_end_seam}) {
        const Hinge h = hinge(v);
        const Frames f = frames_of(h.mesh);
        SCOPED_TRACE(int(v));
        EXPECT_GT(angle_between(f.tangent(1), f.tangent(3)), 0.05);
        // Each corner keeps its own triangle's projected dP/du (a fold flips the sign, not the tangent).
        EXPECT_LT(angle_between(f.tangent(1), h.own_first), 1e-5);
        EXPECT_LT(angle_between(f.tangent(3), h.own_second), 1e-5);
        EXPECT_EQ(f.sign(1), 1.0f);
        EXPECT_EQ(f.sign(3), v == Variant::folded ? -1.0f : 1.0f);
    }
}

// The mirror image of a mesh: x negated, winding reversed, normals reflected, UVs copied.
TestMesh mirrored(const TestMesh& m)
{
    TestMesh r = m;
    for (size_t i = 0; i < r.positions.size(); i += 3) r.positions[i] = -r.positions[i];
    for (size_t i = 0; i < r.normals.size(); i += 3) r.normals[i] = -r.normals[i];
    for (size_t c = 0; c < r.corners.size(); c += 3) {
        std::swap(r.corners[c + 1], r.corners[c + 2]);
        for (int k = 0; k < 3; ++k) std::swap(r.normals[3 * (c + 1) + k], r.normals[3 * (c + 2) + k]);
        for (int k = 0; k < 2; ++k) std::swap(r.uvs[2 * (c + 1) + k], r.uvs[2 * (c + 2) + k]);
    }
    return r;
}

TEST(TangentFrames, MirroredCopyGetsExactlyTheMirroredFramesWithOppositeSigns)
{
    const TestMesh m = bumpy_grid(12, 3);
    const TestMesh r = mirrored(m);
    const Frames f = frames_of(m), g = frames_of(r);
    for (size_t c = 0; c < m.corner_count(); ++c) {
        const size_t mc = c % 3 == 0 ? c : (c % 3 == 1 ? c + 1 : c - 1);  // corners 1 and 2 swapped
        const Vec3 t = f.tangent(c), reflected{-t.x, t.y, t.z};
        EXPECT_LT(length(g.tangent(mc) - reflected), 1e-5f) << c;
        EXPECT_EQ(g.sign(mc), -f.sign(c)) << c;
    }
}

TEST(TangentFrames, FaceOrderAndCornerRotationDoNotChangeTheFrames)
{
    const TestMesh m = bumpy_grid(10, 5);
    const size_t faces = m.sizes.size();
    std::vector<size_t> order(faces);
    std::iota(order.begin(), order.end(), 0);
    std::mt19937 rng(11);
    std::shuffle(order.begin(), order.end(), rng);
    TestMesh s = m;
    s.corners.clear(), s.normals.clear(), s.uvs.clear(), s.sizes.clear();
    std::vector<size_t> source;  // corner of s -> corner of m
    for (const size_t f : order) {
        const size_t rot = rng() % 3;
        std::vector<uint32_t> verts;
        std::vector<std::array<float, 2>> uv;
        std::vector<Vec3> n;
        for (size_t k = 0; k < 3; ++k) {
            const size_t c = 3 * f + (k + rot) % 3;
            source.push_back(c);
            verts.push_back(m.corners[c]);
            uv.push_back({m.uvs[2 * c], m.uvs[2 * c + 1]});
            n.push_back(m.normal(c));
        }
        s.face(verts, uv, n);
    }
    const Frames f = frames_of(m), g = frames_of(s);
    for (size_t c = 0; c < s.corner_count(); ++c) {
        EXPECT_LT(length(g.tangent(c) - f.tangent(source[c])), 2e-6f);
        EXPECT_EQ(g.sign(c), f.sign(source[c]));
    }
}

TEST(TangentFrames, GroupAveragesProjectedDerivativesWeightedByCornerAngle)
{
    // A flat fan of four triangles around the centre with one UV per rim vertex: the mapping is
    // piecewise linear, so each triangle has its own dP/du, and the centre has one group.
    TestMesh m;
    const Vec3 centre{0.1f, 0.05f, 0};
    const std::vector<Vec3> rim{{1, 0, 0}, {0.2f, 1.1f, 0}, {-1, 0.3f, 0}, {-0.1f, -0.9f, 0}};
    const std::vector<std::array<float, 2>> rim_uv{{{0.9f, 0.1f}}, {{0.3f, 0.95f}}, {{-0.8f, 0.2f}}, {{0.1f, -0.7f}}};
    const std::array<float, 2> centre_uv{{0.05f, 0.02f}};
    const uint32_t c0 = m.vertex(centre);
    std::vector<uint32_t> r;
    for (const Vec3& p : rim) r.push_back(m.vertex(p));
    const Vec3 n = normalize_or(Vec3{0.2f, 0.1f, 1}, kUp);  // the corner normal need not be the face's
    Vec3 expected{}, expected_mag{};
    double weight = 0;
    for (size_t k = 0; k < 4; ++k) {
        const size_t j = (k + 1) % 4;
        m.face({c0, r[k], r[j]}, {centre_uv, rim_uv[k], rim_uv[j]}, n);
        const Vec3 du = dp_du(centre, rim[k], rim[j], centre_uv, rim_uv[k], rim_uv[j]);
        const Vec3 e1 = project(n, rim[k] - centre), e2 = project(n, rim[j] - centre);
        const double angle = std::acos(std::clamp(double(dot(e1, e2)), -1.0, 1.0));
        expected += project(n, du) * float(angle);
        expected_mag.x += float(angle * length(du));
        weight += angle;
    }
    const Frames f = frames_of(m);
    for (size_t k = 0; k < 4; ++k) {
        EXPECT_LT(angle_between(f.tangent(3 * k), expected), 2e-4) << k;  // fast arccos: ~7e-5 rad per weight
        EXPECT_NEAR(f.mags[2 * 3 * k], expected_mag.x / weight, 2e-4 * expected_mag.x / weight);
    }
    // Without the weights (the thesis's plain mean) the answer is measurably different.
    Vec3 plain{};
    for (size_t k = 0; k < 4; ++k)
        plain += project(n, dp_du(centre, rim[k], rim[(k + 1) % 4], centre_uv, rim_uv[k], rim_uv[(k + 1) % 4]));
    EXPECT_GT(angle_between(plain, expected), 1e-3);
}

TEST(TangentFrames, QuadsSplitAlongTheShorterUVDiagonalLikeMikkTSpace)
{
    // Non-planar quad whose 1-3 UV diagonal is the shorter one.
    const std::vector<Vec3> p{{0, 0, 0}, {1, 0, 0.2f}, {1.2f, 1, 0}, {0, 1, 0.4f}};
    const std::vector<std::array<float, 2>> uv{{{0, 0}}, {{1, 0.3f}}, {{1.2f, 1.3f}}, {{0.2f, 1}}};
    const std::vector<Vec3> n{normalize_or(Vec3{-0.1f, 0.0f, 1}, kUp), normalize_or(Vec3{0.1f, -0.2f, 1}, kUp),
                              normalize_or(Vec3{0.0f, 0.1f, 1}, kUp), normalize_or(Vec3{0.2f, 0.2f, 1}, kUp)};
    auto mesh = [&](const std::vector<std::vector<uint32_t>>& faces) {
        TestMesh m;
        for (const Vec3& q : p) m.vertex(q);
        for (const auto& f : faces) {
            std::vector<std::array<float, 2>> fu;
            std::vector<Vec3> fn;
            for (const uint32_t v : f) fu.push_back(uv[v]), fn.push_back(n[v]);
            m.face(f, fu, fn);
        }
        return m;
    };
    const Frames quad = frames_of(mesh({{0, 1, 2, 3}}));
    const Frames split13 = frames_of(mesh({{0, 1, 3}, {1, 2, 3}}));
    const Frames split02 = frames_of(mesh({{0, 1, 2}, {0, 2, 3}}));
    // Vertex v's first corner in each triangle mesh.
    auto corner_of = [](const std::vector<std::vector<uint32_t>>& faces, uint32_t v) {
        size_t c = 0;
        for (const auto& f : faces)
            for (const uint32_t w : f) {
                if (w == v) return c;
                ++c;
            }
        return c;
    };
    double worst13 = 0, worst02 = 0;
    for (uint32_t v = 0; v < 4; ++v) {
        worst13 = std::max(worst13, angle_between(quad.tangent(v), split13.tangent(corner_of({{0, 1, 3}, {1, 2, 3}}, v))));
        worst02 = std::max(worst02, angle_between(quad.tangent(v), split02.tangent(corner_of({{0, 1, 2}, {0, 2, 3}}, v))));
    }
    EXPECT_LT(worst13, 1e-6);
    EXPECT_GT(worst02, 1e-3);
}

TEST(TangentFrames, IsolatedZeroUVTriangleGetsTheMikkTSpaceDefault)
{
    TestMesh m;
    const uint32_t a = m.vertex({0, 0, 0}), b = m.vertex({1, 0, 0}), c = m.vertex({0, 1, 0});
    m.face({a, b, c}, {{{0.5f, 0.5f}}, {{0.5f, 0.5f}}, {{0.5f, 0.5f}}}, kUp);
    const Frames f = frames_of(m);
    EXPECT_EQ(f.stats.group_with_any, 1u);
    for (size_t k = 0; k < 3; ++k) {
        EXPECT_EQ(f.tangent(k).x, 1.0f);
        EXPECT_EQ(f.tangent(k).y, 0.0f);
        EXPECT_EQ(f.sign(k), -1.0f);
    }
}

TEST(TangentFrames, ZeroUVTriangleInsideAGroupTakesTheGroupsFrame)
{
    // A strip T0, T1, T2 where T1's UVs are collinear (D's UV on the line B-C) but its edges are
    // shared with T0 and T2: MikkTSpace lets it join their groups ("group with any"), adding
    // nothing, instead of giving it the default frame.
    TestMesh m;
    const uint32_t A = m.vertex({0, 0, 0}), B = m.vertex({1, 0, 0}), C = m.vertex({0.5f, 1, 0}),
                   D = m.vertex({1.2f, 0.8f, 0.1f}), E = m.vertex({1.3f, 1.6f, 0});
    const std::array<float, 2> a{{0, 0}}, b{{1, 0}}, c{{0.5f, 1}}, d{{0.75f, 0.5f}}, e{{1.5f, 1.2f}};
    m.face({A, B, C}, {a, b, c}, kUp);
    m.face({B, D, C}, {b, d, c}, kUp);
    m.face({C, D, E}, {c, d, e}, kUp);
    const Frames f = frames_of(m);
    EXPECT_EQ(f.stats.group_with_any, 1u);
    // T1's corners at B, D, C share the frames of T0 at B, T2 at D and T0 at C.
    EXPECT_EQ(std::memcmp(&f.t[4 * 3], &f.t[4 * 1], 16), 0);
    EXPECT_EQ(std::memcmp(&f.t[4 * 4], &f.t[4 * 7], 16), 0);
    EXPECT_EQ(std::memcmp(&f.t[4 * 5], &f.t[4 * 2], 16), 0);
    // ... and T0's frame at B is T0's own dP/du: T1 contributed nothing to it.
    EXPECT_LT(angle_between(f.tangent(1), dp_du({0, 0, 0}, {1, 0, 0}, {0.5f, 1, 0}, a, b, c)), 1e-6);
}

TEST(TangentFrames, DegenerateTrianglesCopyAFrameAndLeaveTheOthersUnchanged)
{
    const TestMesh m = bumpy_grid(6, 4);
    const Frames clean = frames_of(m);
    // Add degenerate triangles on existing vertices: two corners on one vertex (collapsed), with
    // the attributes of an existing corner so they weld to it.
    TestMesh d = m;
    for (size_t c : {0u, 7u, 20u, 33u}) {
        const uint32_t v = m.corners[c], w = m.corners[c + 1];
        d.face({v, v, w}, {{{m.uvs[2 * c], m.uvs[2 * c + 1]}}, {{m.uvs[2 * c], m.uvs[2 * c + 1]}}, {{0.3f, 0.3f}}},
               {m.normal(c), m.normal(c), kUp});
    }
    const Frames f = frames_of(d);
    EXPECT_EQ(f.stats.degenerate_triangles, 4u);
    for (size_t c = 0; c < m.corner_count(); ++c)
        ASSERT_EQ(std::memcmp(&f.t[4 * c], &clean.t[4 * c], 16), 0) << "good corner " << c << " changed";
    for (size_t k = 0; k < 4; ++k) {
        const size_t c = m.corner_count() + 3 * k;  // the collapsed corner welded to a good one
        const size_t src = std::vector<size_t>{0, 7, 20, 33}[k];
        // The first good corner welded to it has the same frame as `src` (one group per vertex here).
        EXPECT_LT(length(f.tangent(c) - clean.tangent(src)), 1e-6f);
        EXPECT_EQ(f.sign(c), clean.sign(src));
    }
    for (float x : f.t) EXPECT_TRUE(std::isfinite(x));
}

TEST(TangentFrames, QuadWithOneCollapsedHalfCopiesTheCoincidentCorner)
{
    TestMesh m;
    const uint32_t a = m.vertex({0, 0, 0}), b = m.vertex({1, 0, 0}), c = m.vertex({1, 1, 0.2f});
    const uint32_t d = m.vertex({1, 1, 0.2f});  // at c's position: the 0-2-3 half is degenerate
    m.face({a, b, c, d}, {{{0, 0}}, {{1, 0}}, {{1, 1}}, {{0.2f, 1.4f}}}, kUp);
    const Frames f = frames_of(m);
    EXPECT_EQ(f.stats.degenerate_triangles, 1u);
    EXPECT_EQ(std::memcmp(&f.t[4 * 3], &f.t[4 * 2], 16), 0);
}

TEST(TangentFrames, ThreadCountDoesNotChangeASingleBit)
{
    TestMesh m = bumpy_grid(80, 9, true);
    for (size_t c = 0; c < m.uvs.size(); c += 97) m.uvs[c] = 0.25f;  // some folds and zero areas
    const Frames one = frames_of(m, 1), many = frames_of(m, 4);
    EXPECT_EQ(std::memcmp(one.t.data(), many.t.data(), one.t.size() * sizeof(float)), 0);
    EXPECT_EQ(std::memcmp(one.mags.data(), many.mags.data(), one.mags.size() * sizeof(float)), 0);
}

TEST(TangentFrames, WeldingIsByValueSoAnUnindexedMeshGivesTheSameFrames)
{
    const TestMesh m = bumpy_grid(20, 6);
    TestMesh soup = m;  // one vertex per corner, as an STL file would give
    soup.positions.clear();
    soup.corners.clear();
    for (size_t c = 0; c < m.corner_count(); ++c) soup.corners.push_back(soup.vertex(m.position_of_corner(c)));
    const Frames a = frames_of(m), b = frames_of(soup);
    EXPECT_EQ(std::memcmp(a.t.data(), b.t.data(), a.t.size() * sizeof(float)), 0);
}

}  // namespace
}  // namespace ndfbake
