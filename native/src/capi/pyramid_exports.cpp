// C entry points of fitting and lobe pyramids (ndfb_pyramid): the fit, the pyramid's levels and
// lobe textures, and the error measures (per level, per texel, the reference effective BRDF).
// Calls capi/handles.h, bake/ (memory budget, level statistics, lobe textures), ndf/ and math/.
#include <algorithm>
#include <cstddef>
#include <memory>
#include <new>
#include <string>
#include <vector>

#include "bake/level_stats.h"
#include "bake/memory_budget.h"
#include "capi/handles.h"
#include "math/sphere.h"
#include "ndf/moments.h"
#include "ndf/spherical_em.h"

using namespace ndfbake;

extern "C" {

NDFB_API ndfb_status ndfb_fit(ndfb_context ctx, ndfb_normal_map map, const ndfb_fit_options* options, ndfb_pyramid* out)
{
    if (out) *out = nullptr;  // before any check: NULL after every failure (ndfbake.h)
    return guarded(ctx, [&] {
        require(ctx && map && out, "ndfb_fit: ctx, map and out must not be null");
        const PyramidSettings settings = to_pyramid(options);
        const StageProgress progress = to_progress(options);
        const NormalMap& m = map->decoded.map;
        check_memory_budget(estimate_bake_memory(m.width, m.height, SourceLayout{}, settings, WriteSettings{}),
                            settings.max_memory_bytes, m.width, m.height, settings.fit.max_lobes, "cannot fit the map");
        auto result = std::make_unique<ndfb_pyramid_s>();
        result->pyramid = build_lobe_pyramid(map->decoded.map, settings, [&](double fraction) {
            return !progress || progress("fit", fraction);
        });
        *out = result.release();
    });
}

NDFB_API void ndfb_pyramid_destroy(ndfb_pyramid pyramid) { delete pyramid; }
NDFB_API uint32_t ndfb_pyramid_level_count(ndfb_pyramid p) { return p ? uint32_t(p->pyramid.level_count()) : 0; }
NDFB_API uint32_t ndfb_pyramid_lobe_slots(ndfb_pyramid p) { return p ? uint32_t(p->pyramid.slots) : 0; }

NDFB_API ndfb_status ndfb_pyramid_level_size(ndfb_pyramid p, uint32_t level, uint32_t* width, uint32_t* height)
{
    if (!p || !width || !height || level >= uint32_t(p->pyramid.level_count())) return NDFB_ERROR_INVALID_ARGUMENT;
    const LevelSize size = p->pyramid.size(int(level));
    *width = uint32_t(size.width);
    *height = uint32_t(size.height);
    return NDFB_OK;
}

NDFB_API ndfb_status ndfb_pyramid_read_lobe(ndfb_pyramid p, uint32_t level, uint32_t lobe, float* rgba, size_t count)
{
    if (!p || !rgba || level >= uint32_t(p->pyramid.level_count()) || lobe >= uint32_t(p->pyramid.slots))
        return NDFB_ERROR_INVALID_ARGUMENT;
    const LevelSize size = p->pyramid.size(int(level));
    if (count != size_t(size.width) * size_t(size.height) * 4) return NDFB_ERROR_INVALID_ARGUMENT;
    // What the lobe file holds, texel for texel. Allocates: a caller's bad_alloc must not escape.
    try {
        const std::vector<float> texture = lobe_texture(p->pyramid, int(level), int(lobe));
        std::copy(texture.begin(), texture.end(), rgba);
    } catch (const std::bad_alloc&) {
        return NDFB_ERROR_OUT_OF_MEMORY;
    }
    return NDFB_OK;
}

NDFB_API ndfb_status ndfb_pyramid_level_stats(ndfb_context ctx, ndfb_pyramid p, uint32_t level, ndfb_brdf brdf,
                                              float brdf_parameter, uint32_t max_texels, ndfb_level_stats* out)
{
    return guarded(ctx, [&] {
        require(ctx && out, "ndfb_pyramid_level_stats: ctx and out must not be null");
        const LobePyramid& pyramid = pyramid_of(p);
        require_level(pyramid, level);
        const LevelStats s = measure_level(pyramid, int(level), to_brdf(raw(brdf), brdf_parameter), int(max_texels),
                                           kReportSampleCap, false);
        *out = {};
        out->width = uint32_t(s.size.width);
        out->height = uint32_t(s.size.height);
        for (int k = 0; k <= NDFB_MAX_LOBES; ++k) out->lobe_histogram[k] = s.lobe_histogram[size_t(k)];
        out->mean_error = s.fit.mean;
        out->p95_error = s.fit.p95;
        out->measured_texels = uint32_t(s.measured_texels);
    });
}

NDFB_API ndfb_status ndfb_effective_brdf_reference(ndfb_context ctx, ndfb_normal_map map, ndfb_wrap wrap,
                                                   uint32_t level, uint32_t x, uint32_t y, ndfb_brdf brdf,
                                                   float brdf_parameter, const float* directions,
                                                   size_t direction_count, float* values)
{
    return guarded(ctx, [&] {
        require(ctx && map && directions && values, "ndfb_effective_brdf_reference: null argument");
        const NormalMap& m = map->decoded.map;
        require(level < uint32_t(level_count(m.width, m.height)), "level " + std::to_string(level) + " does not exist");
        const LevelSize size = level_size(m.width, m.height, int(level));
        require(x < uint32_t(size.width) && y < uint32_t(size.height), "texel outside the level");
        std::vector<Vec3> dirs(direction_count);
        for (size_t i = 0; i < direction_count; ++i)
            dirs[i] = normalize_or({directions[3 * i], directions[3 * i + 1], directions[3 * i + 2]}, {0, 0, 1});
        std::vector<WeightedNormal> samples;
        gather_footprint(m, int(level), int(x), int(y), to_wrap(raw(wrap)), samples);
        reference_effective_brdf(samples, to_brdf(raw(brdf), brdf_parameter), dirs, std::span(values, direction_count));
    });
}

NDFB_API ndfb_status ndfb_texel_error(ndfb_context ctx, ndfb_normal_map map, ndfb_pyramid p,
                                      ndfb_representation representation, ndfb_wrap wrap, uint32_t level, uint32_t x,
                                      uint32_t y, ndfb_brdf brdf, float brdf_parameter, float* error)
{
    return guarded(ctx, [&] {
        require(ctx && map && error, "ndfb_texel_error: ctx, map and error must not be null");
        const NormalMap& m = map->decoded.map;
        require(level < uint32_t(level_count(m.width, m.height)), "level " + std::to_string(level) + " does not exist");
        const LevelSize size = level_size(m.width, m.height, int(level));
        require(x < uint32_t(size.width) && y < uint32_t(size.height), "texel outside the level");
        const BaseBrdf base = to_brdf(raw(brdf), brdf_parameter);
        std::vector<WeightedNormal> samples;
        gather_footprint(m, int(level), int(x), int(y), to_wrap(raw(wrap)), samples);
        const std::vector<Vec3> directions = fibonacci_hemisphere(error_direction_count(base));
        const TexelErrorMeter meter(samples, base, directions);
        std::vector<VmfLobe> lobes;
        switch (raw(representation)) {
        case NDFB_REPR_VMF_MIXTURE: {
            const LobePyramid& pyramid = pyramid_of(p);
            require(pyramid.source.width == m.width && pyramid.source.height == m.height,
                    "the pyramid was fitted to a map of another size");
            require_level(pyramid, level);
            lobes = pyramid.texel_lobes(int(level), int(x), int(y));
            break;
        }
        case NDFB_REPR_SINGLE_VMF: lobes = {single_vmf_lobe(samples)}; break;
        case NDFB_REPR_TOKSVIG: lobes = {toksvig_lobe(samples)}; break;
        default: throw Error(Status::invalid_argument, "unknown representation");
        }
        *error = meter.error(lobes);
    });
}

}  // extern "C"
