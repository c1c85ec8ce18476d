// C entry points of fitting and lobe pyramids (ndfb_pyramid): the fit, the pyramid's levels and
// lobe textures, and the per-level error measure (the per-texel ones: research_exports.cpp).
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

NDFB_API ndfb_status ndfb_fit(ndfb_context ctx, ndfb_normal_map map, const ndfb_fit_options* options,
                              ndfb_progress_fn progress_fn, void* progress_user, ndfb_pyramid* out)
{
    if (out) *out = nullptr;  // before any check: NULL after every failure (ndfbake.h)
    return guarded(ctx, [&] {
        require(ctx && map && out, "ndfb_fit: ctx, map and out must not be null");
        const PyramidSettings settings = to_pyramid(options);
        const StageProgress progress = to_progress(progress_fn, progress_user);
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
        out->mean_error = s.fit.mean;
        out->p95_error = s.fit.p95;
        out->measured_texels = uint32_t(s.measured_texels);
    });
}

NDFB_API ndfb_status ndfb_pyramid_lobe_histogram(ndfb_pyramid p, uint32_t level, uint64_t* counts, size_t count)
{
    if (!p || !counts || level >= uint32_t(p->pyramid.level_count()) || count != size_t(p->pyramid.slots) + 1)
        return NDFB_ERROR_INVALID_ARGUMENT;
    const std::vector<uint64_t> histogram = lobe_histogram(p->pyramid, int(level));
    std::copy(histogram.begin(), histogram.end(), counts);
    return NDFB_OK;
}

}  // extern "C"
