// C entry points of the tangent module: argument checks and array plumbing only; the work is in
// native/src/tangent/.
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstring>
#include <string>
#include <vector>

#include "capi/context.h"
#include "ndfbake.h"
#include "tangent/mesh_diagnostics.h"
#include "tangent/mesh_input.h"
#include "tangent/object_to_tangent.h"
#include "tangent/tangent_space.h"
#include "tangent/texel_density.h"
#include "tangent/vertex_split.h"

namespace {

using namespace ndfbake;

// `d`: the field as raw() reads it, since the caller's value may be no enumerator.
AttributeDomain to_domain(int d, const char* what)
{
    require(d == NDFB_PER_CORNER || d == NDFB_PER_VERTEX,
            std::string("mesh: unknown ") + what + " domain " + std::to_string(d));
    return d == NDFB_PER_CORNER ? AttributeDomain::corner : AttributeDomain::vertex;
}

// Checks the struct and its pointers, then validates the arrays it points to.
MeshInput mesh_input(const ndfb_mesh* m, NgonPolicy ngons)
{
    // Every field of ABI 1's ndfb_mesh is needed: a shorter struct cannot be read in full.
    require_struct_size(m, "mesh", NDFB_SIZE_THROUGH(ndfb_mesh, uv_domain), "ndfb_mesh_init");
    require(m->face_count > 0, "the mesh has no faces");
    require(m->vertex_count > 0, "the mesh has no vertices");
    require(m->corner_count > 0, "the mesh has no corners");
    require(m->positions && m->face_sizes && m->corner_vertices && m->normals && m->uvs,
            "mesh: positions, face_sizes, corner_vertices, normals and uvs must not be null");
    require(m->vertex_count <= SIZE_MAX / 3 && m->corner_count <= SIZE_MAX / 3, "mesh: sizes overflow");
    MeshArrays a;
    a.positions = {m->positions, m->vertex_count * 3};
    a.face_sizes = {m->face_sizes, m->face_count};
    a.corner_vertices = {m->corner_vertices, m->corner_count};
    a.normal_domain = to_domain(raw(m->normal_domain), "normal");
    a.uv_domain = to_domain(raw(m->uv_domain), "uv");
    a.normals = {m->normals, (a.normal_domain == AttributeDomain::corner ? m->corner_count : m->vertex_count) * 3};
    a.uvs = {m->uvs, (a.uv_domain == AttributeDomain::corner ? m->corner_count : m->vertex_count) * 2};
    return MeshInput::validate(a, ngons);
}

void require_count(size_t got, size_t expected, const char* what)
{
    require(got == expected, std::string(what) + ": expected " + std::to_string(expected) + " elements, got " +
                                 std::to_string(got));
}

int to_threads(uint32_t threads)
{
    require(threads <= 1024, "threads must be at most 1024");
    return int(threads);
}

// The caller's tangents (checked) or freshly generated ones.
std::vector<float> tangents_for(const MeshInput& mesh, const float* tangents, size_t count, int threads)
{
    std::vector<float> t;
    if (tangents) {
        require_count(count, mesh.corner_count() * 4, "tangents");
        t.assign(tangents, tangents + count);
        for (size_t i = 0; i < t.size(); ++i)
            require(std::isfinite(t[i]), "tangent of corner " + std::to_string(i / 4) + " is not finite");
    } else {
        t.resize(mesh.corner_count() * 4);
        generate_tangent_frames(mesh, threads, t, {});
    }
    return t;
}

SpaceSettings to_space(const ndfb_space_options* o)
{
    SpaceSettings s;
    if (!o) return s;
    require_struct_size(o, "space options", sizeof(ndfb_space_options), "ndfb_space_options_init");
    s.padding = o->padding;
    s.threads = to_threads(o->threads);
    require(o->frame_normal == NDFB_FRAME_NORMAL_INTERPOLATED || o->frame_normal == NDFB_FRAME_NORMAL_UNIT,
            "space options frame_normal must be NDFB_FRAME_NORMAL_INTERPOLATED (0) or NDFB_FRAME_NORMAL_UNIT "
            "(1), got " + std::to_string(o->frame_normal));
    s.unit_normal = o->frame_normal == NDFB_FRAME_NORMAL_UNIT;
    return s;
}

void check_image(uint32_t width, uint32_t height, size_t count, const void* in, const void* out)
{
    require(in && out, "normal images must not be null");
    require(width >= 1 && height >= 1 && width <= 65536 && height <= 65536,
            "image size must be 1..65536 per side, got " + std::to_string(width) + "x" + std::to_string(height));
    require_count(count, size_t(width) * height * 3, "normal image floats (width*height*3)");
}

// Both directions of ndfb_object_to_tangent / ndfb_tangent_to_object: check, then convert.
void convert_space(const ndfb_mesh* mesh, const float* tangents, size_t tangent_count, SpaceDirection direction,
                   const float* in, uint32_t width, uint32_t height, size_t count, const ndfb_space_options* options,
                   float* out, uint8_t* coverage)
{
    check_image(width, height, count, in, out);
    const SpaceSettings s = to_space(options);
    const MeshInput m = mesh_input(mesh, NgonPolicy::refuse);
    const std::vector<float> t = tangents_for(m, tangents, tangent_count, s.threads);
    convert_normal_map(m, t, direction, {in, count}, int(width), int(height), s, {out, count},
                       coverage ? std::span<uint8_t>(coverage, size_t(width) * height) : std::span<uint8_t>());
}

}  // namespace

extern "C" {

NDFB_API void ndfb_mesh_init(ndfb_mesh* mesh)
{
    if (!mesh) return;
    *mesh = {};
    mesh->struct_size = sizeof *mesh;
    mesh->normal_domain = NDFB_PER_CORNER;
    mesh->uv_domain = NDFB_PER_CORNER;
}

NDFB_API ndfb_status ndfb_tangents(ndfb_context ctx, const ndfb_mesh* mesh, uint32_t threads, float* tangents,
                                   size_t tangent_count, float* magnitudes, size_t magnitude_count)
{
    return guarded(ctx, [&] {
        require(ctx && tangents, "ndfb_tangents: ctx and tangents must not be null");
        require(magnitudes || magnitude_count == 0, "ndfb_tangents: magnitudes is null but magnitude_count is not 0");
        const MeshInput m = mesh_input(mesh, NgonPolicy::refuse);
        require_count(tangent_count, m.corner_count() * 4, "tangents (4 per corner)");
        if (magnitudes) require_count(magnitude_count, m.corner_count() * 2, "magnitudes (2 per corner)");
        generate_tangent_frames(m, to_threads(threads), {tangents, tangent_count},
                                magnitudes ? std::span<float>(magnitudes, magnitude_count) : std::span<float>());
    });
}

NDFB_API ndfb_status ndfb_split_vertices(ndfb_context ctx, const ndfb_mesh* mesh, const float* tangents,
                                         size_t tangent_count, uint32_t threads, uint32_t* corner_to_vertex,
                                         size_t corner_count, uint32_t* vertex_source, size_t capacity,
                                         ndfb_split_stats* stats)
{
    return guarded(ctx, [&] {
        require(ctx && corner_to_vertex && vertex_source,
                "ndfb_split_vertices: ctx, corner_to_vertex and vertex_source must not be null");
        const MeshInput m = mesh_input(mesh, NgonPolicy::refuse);
        require_count(corner_count, m.corner_count(), "corner_to_vertex (1 per corner)");
        require(capacity >= m.corner_count(), "vertex_source needs room for corner_count (" +
                                                  std::to_string(m.corner_count()) + ") entries, got " +
                                                  std::to_string(capacity));
        const std::vector<float> t = tangents_for(m, tangents, tangent_count, to_threads(threads));
        const SplitStats s = split_vertices(m, t, to_threads(threads), {corner_to_vertex, corner_count},
                                            {vertex_source, capacity});
        if (stats) *stats = {s.input_vertices, s.output_vertices, s.uv_seams, s.hard_edges, s.mirror_seams, s.tangent_splits};
    });
}

NDFB_API ndfb_status ndfb_texel_density(ndfb_context ctx, const ndfb_mesh* mesh, float* face_density,
                                        size_t face_count, double* mesh_density)
{
    return guarded(ctx, [&] {
        require(ctx && face_density, "ndfb_texel_density: ctx and face_density must not be null");
        const MeshInput m = mesh_input(mesh, NgonPolicy::accept);
        require_count(face_count, m.face_count(), "face_density (1 per face)");
        const double total = texel_density(m, {face_density, face_count});
        if (mesh_density) *mesh_density = total;
    });
}

NDFB_API ndfb_status ndfb_mesh_diagnose(ndfb_context ctx, const ndfb_mesh* mesh, ndfb_mesh_report* report,
                                        char* text, size_t capacity, size_t* length)
{
    return guarded(ctx, [&] {
        require(ctx && (text || capacity == 0), "ndfb_mesh_diagnose: ctx must not be null, text only with capacity 0");
        const MeshInput m = mesh_input(mesh, NgonPolicy::accept);
        const MeshReport r = diagnose_mesh(m);
        if (report) {
            *report = {};
            report->faces = r.faces, report->triangles = r.triangles, report->quads = r.quads, report->ngons = r.ngons;
            report->degenerate_triangles = r.degenerate_triangles;
            report->zero_area_uv_triangles = r.zero_area_uv_triangles;
            report->uv_islands = r.uv_islands;
            report->mirrored_islands = r.mirrored_islands;
            report->flipped_islands = r.flipped_islands;
            report->flipped_triangles = r.flipped_triangles;
            report->inverted_normal_faces = r.inverted_normal_faces;
            report->ngon_first = r.ngon_first;
            report->degenerate_first = r.degenerate_first;
            report->zero_area_uv_first = r.zero_area_uv_first;
            report->flipped_first = r.flipped_first;
            report->inverted_normal_first = r.inverted_normal_first;
        }
        const std::string s = describe(r);
        if (length) *length = s.size();
        if (capacity > 0) {
            const size_t n = std::min(capacity - 1, s.size());
            std::memcpy(text, s.data(), n);
            text[n] = '\0';
        }
    });
}

NDFB_API void ndfb_space_options_init(ndfb_space_options* options)
{
    if (!options) return;
    *options = {};
    options->struct_size = sizeof *options;
    options->padding = SpaceSettings{}.padding;
    options->threads = 0;
    options->frame_normal = NDFB_FRAME_NORMAL_INTERPOLATED;
}

NDFB_API ndfb_status ndfb_object_to_tangent(ndfb_context ctx, const ndfb_mesh* mesh, const float* tangents,
                                            size_t tangent_count, const float* object_normals, uint32_t width,
                                            uint32_t height, size_t count, const ndfb_space_options* options,
                                            float* tangent_normals, uint8_t* coverage)
{
    return guarded(ctx, [&] {
        require(ctx != nullptr, "ndfb_object_to_tangent: ctx is null");
        convert_space(mesh, tangents, tangent_count, SpaceDirection::object_to_tangent, object_normals, width, height,
                      count, options, tangent_normals, coverage);
    });
}

NDFB_API ndfb_status ndfb_tangent_to_object(ndfb_context ctx, const ndfb_mesh* mesh, const float* tangents,
                                            size_t tangent_count, const float* tangent_normals, uint32_t width,
                                            uint32_t height, size_t count, const ndfb_space_options* options,
                                            float* object_normals, uint8_t* coverage)
{
    return guarded(ctx, [&] {
        require(ctx != nullptr, "ndfb_tangent_to_object: ctx is null");
        convert_space(mesh, tangents, tangent_count, SpaceDirection::tangent_to_object, tangent_normals, width, height,
                      count, options, object_normals, coverage);
    });
}

}  // extern "C"
