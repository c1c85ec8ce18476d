// libFuzzer target: the tangent-frame entry points with arbitrary meshes.
//
// Input: vertex, face and corner counts, face sizes, corner indices, attribute domains, and
// positions, normals and UVs, either drawn from a few values (so that welds, degenerate and
// zero-UV-area triangles, mirrored and folded islands are common) or as raw float bits (NaN and
// Inf included); sometimes an array count that does not add up. Every entry point runs on it:
// ndfb_mesh_diagnose, ndfb_texel_density, ndfb_tangents, ndfb_split_vertices and both space
// conversions on a small image. Oracle: no NDFB_ERROR_INTERNAL; on success finite unit tangents
// with sign +-1, split indices in range, finite densities and converted normals.
#include <fuzzer/FuzzedDataProvider.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <numeric>
#include <vector>

#include "fuzz_common.h"

namespace {

float value(FuzzedDataProvider& in, bool raw)
{
    if (raw) {
        const uint32_t bits = in.ConsumeIntegral<uint32_t>();
        float f;
        std::memcpy(&f, &bits, sizeof f);
        return f;
    }
    static const float kValues[] = {0.0f, 1.0f, -1.0f, 0.5f, -0.5f, 0.25f, 2.0f, 1e-7f, 0.70710678f, 3.0f};
    return kValues[in.ConsumeIntegralInRange<size_t>(0, sizeof kValues / sizeof kValues[0] - 1)];
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size)
{
    using namespace ndfbake_fuzz;
    FuzzedDataProvider in(data, size);
    ndfb_context ctx = context();

    const bool raw = in.ConsumeIntegralInRange<uint8_t>(0, 7) == 0;
    const size_t vertex_count = in.ConsumeIntegralInRange<size_t>(1, 48);
    const size_t face_count = in.ConsumeIntegralInRange<size_t>(1, 24);
    std::vector<uint32_t> face_sizes(face_count);
    for (uint32_t& s : face_sizes) s = in.ConsumeIntegralInRange<uint8_t>(0, 15) == 0 ? in.ConsumeIntegralInRange<uint32_t>(0, 7) : in.ConsumeIntegralInRange<uint32_t>(3, 4);
    size_t corner_count = std::accumulate(face_sizes.begin(), face_sizes.end(), size_t(0));
    std::vector<uint32_t> corners(corner_count);
    for (uint32_t& c : corners)
        c = in.ConsumeIntegralInRange<uint8_t>(0, 31) == 0 ? in.ConsumeIntegral<uint32_t>()
                                                            : in.ConsumeIntegralInRange<uint32_t>(0, uint32_t(vertex_count - 1));
    const ndfb_domain normal_domain = in.ConsumeBool() ? NDFB_PER_VERTEX : NDFB_PER_CORNER;
    const ndfb_domain uv_domain = in.ConsumeBool() ? NDFB_PER_VERTEX : NDFB_PER_CORNER;
    std::vector<float> positions(vertex_count * 3);
    std::vector<float> normals((normal_domain == NDFB_PER_VERTEX ? vertex_count : corner_count) * 3);
    std::vector<float> uvs((uv_domain == NDFB_PER_VERTEX ? vertex_count : corner_count) * 2);
    for (float& p : positions) p = value(in, raw);
    for (float& n : normals) n = value(in, raw);
    for (float& t : uvs) t = value(in, raw);
    // Sometimes a count that does not add up (the arrays are long enough either way).
    const bool lie = in.ConsumeIntegralInRange<uint8_t>(0, 15) == 0;
    const uint32_t threads = in.ConsumeIntegralInRange<uint32_t>(0, 2);
    const uint32_t padding = in.ConsumeBool() ? NDFB_PAD_ALL : in.ConsumeIntegralInRange<uint32_t>(0, 8);
    const uint32_t image_w = in.ConsumeIntegralInRange<uint32_t>(1, 16), image_h = in.ConsumeIntegralInRange<uint32_t>(1, 16);

    ndfb_mesh mesh;
    ndfb_mesh_init(&mesh);
    mesh.positions = positions.data();
    mesh.vertex_count = vertex_count;
    mesh.face_sizes = face_sizes.data();
    mesh.face_count = face_count;
    mesh.corner_vertices = corners.data();
    mesh.corner_count = lie && corner_count > 1 ? corner_count - 1 : corner_count;
    mesh.normals = normals.data();
    mesh.normal_domain = normal_domain;
    mesh.uvs = uvs.data();
    mesh.uv_domain = uv_domain;

    ndfb_mesh_report report;
    char text[512];
    size_t length = 0;
    check(ndfb_mesh_diagnose(ctx, &mesh, &report, text, sizeof text, &length), "ndfb_mesh_diagnose");

    std::vector<float> density(face_count);
    double mesh_density = 0.0;
    ndfb_status status = ndfb_texel_density(ctx, &mesh, density.data(), density.size(), &mesh_density);
    check(status, "ndfb_texel_density");
    if (status == NDFB_OK) {
        require(std::isfinite(mesh_density) && mesh_density >= 0.0, "mesh density finite");
        for (float d : density) require(std::isfinite(d) && d >= 0.0f, "face density finite");
    }

    std::vector<float> tangents(corner_count * 4), magnitudes(corner_count * 2);
    status = ndfb_tangents(ctx, &mesh, threads, tangents.data(), tangents.size(), magnitudes.data(),
                           magnitudes.size());
    check(status, "ndfb_tangents");
    if (status != NDFB_OK) return 0;
    auto dump_mesh = [&](size_t c, const float* t) {
        std::fprintf(stderr, "corner %zu of %zu: tangent (%g, %g, %g) sign %g\n", c, corner_count, t[0], t[1], t[2],
                     t[3]);
        for (size_t f = 0, first = 0; f < face_count; first += face_sizes[f++]) {
            std::fprintf(stderr, "face %zu:", f);
            for (size_t k = first; k < first + face_sizes[f]; ++k) {
                const uint32_t v = corners[k];
                const float* n = normal_domain == NDFB_PER_VERTEX ? &normals[v * 3] : &normals[k * 3];
                const float* uv = uv_domain == NDFB_PER_VERTEX ? &uvs[v * 2] : &uvs[k * 2];
                std::fprintf(stderr, " [c%zu v%u p(%.9g %.9g %.9g) n(%.9g %.9g %.9g) uv(%.9g %.9g)]", k, v, positions[v * 3],
                             positions[v * 3 + 1], positions[v * 3 + 2], n[0], n[1], n[2], uv[0], uv[1]);
            }
            std::fprintf(stderr, "\n");
        }
    };
    for (size_t c = 0; c < corner_count; ++c) {
        const float* t = &tangents[c * 4];
        for (int k = 0; k < 4; ++k)
            if (!std::isfinite(t[k])) {
                dump_mesh(c, t);
                require(false, "tangents are finite");
            }
        // Unit, or exactly zero: MikkTSpace leaves a group's tangent at zero when its projection on
        // the normal's plane vanishes (VNotZero guard), and so does our implementation; see
        // corpus/tangent/zero_tangent_degenerate_fan.
        const float length = std::sqrt(t[0] * t[0] + t[1] * t[1] + t[2] * t[2]);
        if (!(std::abs(length - 1.0f) < 1e-3f || length == 0.0f)) {
            dump_mesh(c, t);
            require(false, "tangents are unit");
        }
        require(t[3] == 1.0f || t[3] == -1.0f, "bitangent sign is +-1");
        require(std::isfinite(magnitudes[c * 2]) && std::isfinite(magnitudes[c * 2 + 1]), "magnitudes are finite");
    }

    std::vector<uint32_t> corner_to_vertex(corner_count), vertex_source(corner_count);
    ndfb_split_stats stats;
    status = ndfb_split_vertices(ctx, &mesh, in.ConsumeBool() ? tangents.data() : nullptr, tangents.size(), threads,
                                 corner_to_vertex.data(), corner_to_vertex.size(), vertex_source.data(),
                                 vertex_source.size(), &stats);
    check(status, "ndfb_split_vertices");
    if (status == NDFB_OK) {
        require(stats.output_vertices <= corner_count && stats.input_vertices <= stats.output_vertices,
                "split counts");
        for (uint32_t v : corner_to_vertex) require(v < stats.output_vertices, "corner_to_vertex in range");
        for (size_t v = 0; v < stats.output_vertices; ++v) require(vertex_source[v] < vertex_count, "vertex_source in range");
    }

    ndfb_space_options space;
    ndfb_space_options_init(&space);
    space.padding = padding;
    space.threads = threads;
    const size_t count = size_t(image_w) * image_h * 3;
    std::vector<float> object(count), tangent(count);
    for (size_t i = 0; i < count; ++i) object[i] = (i % 3 == 2) ? 1.0f : value(in, false) * 0.5f;
    std::vector<uint8_t> coverage(size_t(image_w) * image_h);
    status = ndfb_object_to_tangent(ctx, &mesh, tangents.data(), tangents.size(), object.data(), image_w, image_h,
                                    count, &space, tangent.data(), coverage.data());
    check(status, "ndfb_object_to_tangent");
    if (status == NDFB_OK) {
        for (float v : tangent) require(std::isfinite(v), "tangent-space normals are finite");
        for (uint8_t c : coverage) require(c <= 2, "coverage is 0, 1 or 2");
        status = ndfb_tangent_to_object(ctx, &mesh, nullptr, 0, tangent.data(), image_w, image_h, count, &space,
                                        object.data(), nullptr);
        check(status, "ndfb_tangent_to_object");
        if (status == NDFB_OK)
            for (float v : object) require(std::isfinite(v), "object-space normals are finite");
    }
    return 0;
}
