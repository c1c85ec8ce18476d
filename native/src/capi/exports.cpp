// The C API: a thin skin that checks arguments, calls the C++ core and turns exceptions into
// status codes plus last-error text. No exception crosses this file's functions.
#include "ndfbake.h"

#include <algorithm>
#include <cstddef>
#include <cstring>
#include <memory>
#include <new>
#include <string>

#include "bake/bake.h"
#include "bake/level_stats.h"
#include "bake/memory_budget.h"
#include "error.h"
#include "io/image_files.h"
#include "io/normal_encode.h"
#include "math/sphere.h"
#include "ndf/moments.h"
#include "ndf/spherical_em.h"
#include "synth/patterns.h"

#include "capi/context.h"

struct ndfb_normal_map_s {
    ndfbake::DecodeResult decoded;
};

struct ndfb_pyramid_s {
    ndfbake::LobePyramid pyramid;
};

namespace {

using namespace ndfbake;

thread_local std::string g_create_error;

// What each option struct held when ABI 1 first shipped (require_struct_size): ndfb_decode_options
// has never grown; ndfb_fit_options ended at progress_user (max_memory_bytes, max_levels, starts
// and refine came later), ndfb_write_options at source_name (atlas and mipmap came later).
constexpr size_t kDecodeOptionsFirstSize = sizeof(ndfb_decode_options);
constexpr size_t kFitOptionsFirstSize = NDFB_SIZE_THROUGH(ndfb_fit_options, progress_user);
constexpr size_t kWriteOptionsFirstSize = NDFB_SIZE_THROUGH(ndfb_write_options, source_name);

DecodeOptions to_decode(const ndfb_decode_options* o)
{
    DecodeOptions d;
    if (!o) return d;
    require_struct_size(o, "decode options", kDecodeOptionsFirstSize, "ndfb_decode_options_init");
    const int convention = raw(o->convention), srgb = raw(o->srgb);
    require(convention == NDFB_CONVENTION_OPENGL || convention == NDFB_CONVENTION_DIRECTX,
            "decode options: unknown convention " + std::to_string(convention));
    require(srgb == NDFB_SRGB_AS_DATA || srgb == NDFB_SRGB_LINEARIZE,
            "decode options: unknown sRGB policy " + std::to_string(srgb));
    require(o->max_pixels > 0, "decode options: max_pixels must be positive");
    d.convention = convention == NDFB_CONVENTION_DIRECTX ? Convention::directx : Convention::opengl;
    d.srgb = srgb == NDFB_SRGB_LINEARIZE ? SrgbPolicy::linearize : SrgbPolicy::treat_as_data;
    d.max_pixels = o->max_pixels;
    return d;
}

BaseBrdf to_brdf(int brdf, float parameter)
{
    switch (brdf) {
    case NDFB_BRDF_GGX: return BaseBrdf::ggx(parameter);
    case NDFB_BRDF_BLINN_PHONG: return BaseBrdf::blinn_phong(parameter);
    case NDFB_BRDF_LAMBERT: return BaseBrdf::lambert();
    case NDFB_BRDF_BECKMANN: return BaseBrdf::beckmann(parameter);
    }
    throw Error(Status::invalid_argument, "unknown BRDF " + std::to_string(brdf));
}

WrapMode to_wrap(int wrap)
{
    require(wrap == NDFB_WRAP_REPEAT || wrap == NDFB_WRAP_CLAMP, "unknown wrap mode " + std::to_string(wrap));
    return wrap == NDFB_WRAP_CLAMP ? WrapMode::clamp : WrapMode::wrap;
}

PyramidSettings to_pyramid(const ndfb_fit_options* o)
{
    require_struct_size(o, "fit options", kFitOptionsFirstSize, "ndfb_fit_options_init");
    require(o->max_lobes >= 1 && o->max_lobes <= NDFB_MAX_LOBES,
            "max_lobes must be in 1.." + std::to_string(NDFB_MAX_LOBES) + ", got " + std::to_string(o->max_lobes));
    require(o->tolerance >= 0.0f && o->tolerance <= 1.0f,
            "tolerance must be in [0, 1], got " + std::to_string(o->tolerance));
    require(o->alignment_strength >= 0.0f && o->alignment_strength <= 10.0f,
            "alignment_strength must be in [0, 10], got " + std::to_string(o->alignment_strength));
    require(o->max_iterations >= 1 && o->max_iterations <= 1000,
            "max_iterations must be in 1..1000, got " + std::to_string(o->max_iterations));
    require(o->threads <= 1024, "threads must be at most 1024");
    const int method = raw(o->method);
    require(method == NDFB_FIT_PER_LEVEL || method == NDFB_FIT_HIERARCHICAL, "unknown fit method " + std::to_string(method));
    PyramidSettings s;
    s.fit.max_lobes = int(o->max_lobes);
    s.fit.tolerance = o->tolerance;
    s.fit.em.max_iterations = int(o->max_iterations);
    s.brdf = to_brdf(raw(o->brdf), o->brdf_parameter);
    s.wrap = to_wrap(raw(o->wrap));
    s.align = o->align != 0;
    s.alignment_strength = o->alignment_strength;
    s.threads = int(o->threads);
    s.method = method == NDFB_FIT_HIERARCHICAL ? FitMethod::hierarchical : FitMethod::per_level;
    // Added after ABI 1's first release: read only from callers whose struct has them.
    if (o->struct_size >= NDFB_SIZE_THROUGH(ndfb_fit_options, max_memory_bytes))
        s.max_memory_bytes = o->max_memory_bytes;
    if (o->struct_size >= NDFB_SIZE_THROUGH(ndfb_fit_options, max_levels)) {
        require(o->max_levels <= 64, "max_levels must be at most 64 (0: every level), got " + std::to_string(o->max_levels));
        s.max_levels = int(o->max_levels);
    }
    if (o->struct_size >= NDFB_SIZE_THROUGH(ndfb_fit_options, starts)) {
        require(o->starts == 1 || o->starts == 2, "starts must be 1 or 2, got " + std::to_string(o->starts));
        s.fit.two_starts = o->starts == 2;
    }
    if (o->struct_size >= NDFB_SIZE_THROUGH(ndfb_fit_options, refine)) s.refine = o->refine != 0;
    return s;
}

WriteSettings to_write(const ndfb_write_options* o)
{
    WriteSettings w;
    if (!o) return w;
    require_struct_size(o, "write options", kWriteOptionsFirstSize, "ndfb_write_options_init");
    const int precision = raw(o->precision);
    require(precision == NDFB_PRECISION_HALF || precision == NDFB_PRECISION_FLOAT,
            "unknown precision " + std::to_string(precision));
    w.precision = precision == NDFB_PRECISION_FLOAT ? PixelPrecision::single : PixelPrecision::half;
    if (o->color_path) w.color_path = o->color_path;
    if (o->source_name) w.source_name = o->source_name;
    if (o->struct_size >= NDFB_SIZE_THROUGH(ndfb_write_options, atlas)) w.atlas = o->atlas != 0;
    if (o->struct_size >= NDFB_SIZE_THROUGH(ndfb_write_options, mipmap)) w.mipmap = o->mipmap != 0;
    return w;
}

// The write settings for a map from memory: its files name "memory" as their source where the
// caller names none (ndfb_bake names the input file instead).
WriteSettings to_memory_write(const ndfb_write_options* o)
{
    WriteSettings w = to_write(o);
    if (w.source_name.empty()) w.source_name = "memory";
    return w;
}

StageProgress to_progress(const ndfb_fit_options* o)
{
    if (!o || !o->progress) return {};
    return [fn = o->progress, user = o->progress_user](const char* stage, double fraction) {
        return fn(user, stage, float(fraction)) == 0;
    };
}

const LobePyramid& pyramid_of(ndfb_pyramid p)
{
    require(p != nullptr, "pyramid is null");
    return p->pyramid;
}

void require_level(const LobePyramid& p, uint32_t level)
{
    require(level < uint32_t(p.level_count()), "level " + std::to_string(level) + " does not exist (the pyramid has " +
                                                   std::to_string(p.level_count()) + ")");
}

}  // namespace

extern "C" {

NDFB_API const char* ndfb_version(void) { return NDFBAKE_VERSION_STRING; }
NDFB_API uint32_t ndfb_abi_version(void) { return NDFB_ABI_VERSION; }

NDFB_API int32_t ndfb_has_image_files(void) { return reads_image_files() ? 1 : 0; }

NDFB_API ndfb_status ndfb_context_create(ndfb_context* out)
{
    if (!out) {
        g_create_error = "ndfb_context_create: out is null";
        return NDFB_ERROR_INVALID_ARGUMENT;
    }
    *out = new (std::nothrow) ndfb_context_s;
    if (!*out) {
        g_create_error = "out of memory";
        return NDFB_ERROR_OUT_OF_MEMORY;
    }
    try {
        ContextRegistry::instance().add(*out);
    } catch (...) {
        delete *out;
        *out = nullptr;
        g_create_error = "out of memory";
        return NDFB_ERROR_OUT_OF_MEMORY;
    }
    return NDFB_OK;
}

// A second destroy, or a handle that was never a context, is ignored rather than freed twice.
NDFB_API void ndfb_context_destroy(ndfb_context ctx)
{
    if (ctx && ContextRegistry::instance().remove(ctx)) delete ctx;
}

NDFB_API const char* ndfb_last_error(ndfb_context ctx)
{
    if (!ctx) return g_create_error.c_str();
    if (!ContextRegistry::instance().live(ctx)) return kDeadContextMessage;
    return ctx->last_error.c_str();
}

NDFB_API const char* ndfb_status_name(ndfb_status status)
{
    switch (raw(status)) {
    case NDFB_OK: return "ok";
    case NDFB_ERROR_INVALID_ARGUMENT: return "invalid argument";
    case NDFB_ERROR_FILE_NOT_FOUND: return "file not found";
    case NDFB_ERROR_UNSUPPORTED_FORMAT: return "unsupported format";
    case NDFB_ERROR_CORRUPT_FILE: return "corrupt file";
    case NDFB_ERROR_IO: return "i/o error";
    case NDFB_ERROR_OUT_OF_MEMORY: return "out of memory";
    case NDFB_ERROR_CANCELLED: return "cancelled";
    case NDFB_ERROR_INTERNAL: return "internal error";
    }
    return "unknown status";
}

NDFB_API void ndfb_decode_options_init(ndfb_decode_options* o)
{
    if (!o) return;
    *o = {};
    o->struct_size = sizeof *o;
    o->convention = NDFB_CONVENTION_OPENGL;
    o->srgb = NDFB_SRGB_AS_DATA;
    o->max_pixels = DecodeOptions{}.max_pixels;
}

NDFB_API void ndfb_fit_options_init(ndfb_fit_options* o)
{
    if (!o) return;
    const PyramidSettings d;
    *o = {};
    o->struct_size = sizeof *o;
    o->max_lobes = uint32_t(d.fit.max_lobes);
    o->tolerance = d.fit.tolerance;
    o->brdf = NDFB_BRDF_GGX;
    o->brdf_parameter = d.brdf.parameter();
    o->wrap = NDFB_WRAP_REPEAT;
    o->align = d.align ? 1 : 0;
    o->alignment_strength = d.alignment_strength;
    o->max_iterations = uint32_t(d.fit.em.max_iterations);
    o->method = d.method == FitMethod::hierarchical ? NDFB_FIT_HIERARCHICAL : NDFB_FIT_PER_LEVEL;
    o->threads = 0;
    o->starts = d.fit.two_starts ? 2 : 1;
    o->refine = d.refine ? 1 : 0;
}

NDFB_API void ndfb_write_options_init(ndfb_write_options* o)
{
    if (!o) return;
    *o = {};
    o->struct_size = sizeof *o;
    o->precision = NDFB_PRECISION_HALF;
}

NDFB_API ndfb_status ndfb_normal_map_load(ndfb_context ctx, const char* path, const ndfb_decode_options* options,
                                          ndfb_normal_map* out)
{
    if (out) *out = nullptr;  // before any check: NULL after every failure (ndfbake.h)
    return guarded(ctx, [&] {
        require(ctx && path && out, "ndfb_normal_map_load: ctx, path and out must not be null");
        auto map = std::make_unique<ndfb_normal_map_s>();
        map->decoded = decode_normal_map(path, to_decode(options));
        *out = map.release();
    });
}

NDFB_API ndfb_status ndfb_normal_map_from_pixels(ndfb_context ctx, const float* pixels, size_t count, uint32_t width,
                                                 uint32_t height, uint32_t channels, int32_t signed_encoding,
                                                 const ndfb_decode_options* options, ndfb_normal_map* out)
{
    if (out) *out = nullptr;  // before any check: NULL after every failure (ndfbake.h)
    return guarded(ctx, [&] {
        require(ctx && pixels && out, "ndfb_normal_map_from_pixels: ctx, pixels and out must not be null");
        require(width > 0 && height > 0 && width <= 65536 && height <= 65536,
                "image size must be 1..65536 per side, got " + std::to_string(width) + "x" + std::to_string(height));
        require(count == size_t(width) * height * channels,
                "pixel count " + std::to_string(count) + " does not match " + std::to_string(width) + "x" +
                    std::to_string(height) + "x" + std::to_string(channels));
        auto map = std::make_unique<ndfb_normal_map_s>();
        map->decoded = decode_normal_pixels(pixels, int(width), int(height), int(channels), signed_encoding != 0,
                                            to_decode(options));
        *out = map.release();
    });
}

NDFB_API void ndfb_normal_map_destroy(ndfb_normal_map map) { delete map; }

NDFB_API ndfb_status ndfb_normal_map_size(ndfb_normal_map map, uint32_t* width, uint32_t* height)
{
    if (!map || !width || !height) return NDFB_ERROR_INVALID_ARGUMENT;
    *width = uint32_t(map->decoded.map.width);
    *height = uint32_t(map->decoded.map.height);
    return NDFB_OK;
}

NDFB_API ndfb_status ndfb_normal_map_read(ndfb_normal_map map, float* xyz, size_t count)
{
    if (!map || !xyz || count != map->decoded.map.normals.size() * 3) return NDFB_ERROR_INVALID_ARGUMENT;
    std::memcpy(xyz, map->decoded.map.normals.data(), count * sizeof(float));
    return NDFB_OK;
}

NDFB_API ndfb_status ndfb_normal_map_repairs(ndfb_normal_map map, ndfb_repairs* out)
{
    if (!map || !out) return NDFB_ERROR_INVALID_ARGUMENT;
    const RepairCounts& r = map->decoded.repairs;
    *out = {r.non_finite, r.zero_length, r.renormalized, r.below_horizon};
    return NDFB_OK;
}

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

NDFB_API ndfb_status ndfb_pyramid_write(ndfb_context ctx, ndfb_pyramid p, ndfb_normal_map map, const char* out_dir,
                                        const ndfb_fit_options* fit_options, const ndfb_write_options* options)
{
    return guarded(ctx, [&] {
        require(ctx && map && out_dir, "ndfb_pyramid_write: ctx, map and out_dir must not be null");
        const LobePyramid& pyramid = pyramid_of(p);
        require(pyramid.source.width == map->decoded.map.width && pyramid.source.height == map->decoded.map.height,
                "the pyramid was fitted to a map of another size");
        const WriteSettings write = to_memory_write(options);
        // The files and report describe the fit the pyramid had; fit_options bring the progress
        // callback and the threads.
        PyramidSettings settings = pyramid.settings;
        settings.threads = to_pyramid(fit_options).threads;
        write_pyramid(pyramid, map->decoded, out_dir, settings, write, BakeTimings{}, to_progress(fit_options));
    });
}

NDFB_API ndfb_status ndfb_bake(ndfb_context ctx, const char* input_path, const char* out_dir,
                               const ndfb_decode_options* decode, const ndfb_fit_options* fit,
                               const ndfb_write_options* write)
{
    return guarded(ctx, [&] {
        require(ctx && input_path && out_dir && fit, "ndfb_bake: ctx, input_path, out_dir and fit must not be null");
        bake_file(input_path, out_dir, to_decode(decode), to_pyramid(fit), to_write(write), to_progress(fit));
    });
}

NDFB_API ndfb_status ndfb_bake_map(ndfb_context ctx, ndfb_normal_map map, const char* out_dir,
                                   const ndfb_fit_options* fit, const ndfb_write_options* write)
{
    return guarded(ctx, [&] {
        require(ctx && map && out_dir && fit, "ndfb_bake_map: ctx, map, out_dir and fit must not be null");
        bake_map(map->decoded, out_dir, to_pyramid(fit), to_memory_write(write), to_progress(fit));
    });
}

NDFB_API ndfb_status ndfb_synthesize(ndfb_context ctx, const char* pattern, uint32_t width, uint32_t height,
                                     uint32_t seed, ndfb_normal_map* out)
{
    if (out) *out = nullptr;  // before any check: NULL after every failure (ndfbake.h)
    return guarded(ctx, [&] {
        require(ctx && pattern && out, "ndfb_synthesize: ctx, pattern and out must not be null");
        const auto which = pattern_from_name(pattern);
        require(which.has_value(), std::string("unknown pattern '") + pattern +
                                       "': expected vgroove, bumps, fbm, brushed, scratches or weave");
        require(width >= 1 && height >= 1 && width <= uint32_t(kMaxSynthSide) && height <= uint32_t(kMaxSynthSide),
                "synthetic maps are 1.." + std::to_string(kMaxSynthSide) + " texels per side");
        auto map = std::make_unique<ndfb_normal_map_s>();
        map->decoded.map = synthesize(*which, int(width), int(height), seed);
        map->decoded.format = "synthetic";
        map->decoded.channels = 3;
        map->decoded.signed_encoding = true;
        *out = map.release();
    });
}

NDFB_API ndfb_status ndfb_normal_map_save(ndfb_context ctx, ndfb_normal_map map, const char* path)
{
    return guarded(ctx, [&] {
        require(ctx && map && path, "ndfb_normal_map_save: ctx, map and path must not be null");
        write_normal_map(path, map->decoded.map);
    });
}

NDFB_API ndfb_status ndfb_describe_image(ndfb_context ctx, const char* path, char* text, size_t capacity,
                                         size_t* length)
{
    return guarded(ctx, [&] {
        require(ctx && path && (text || capacity == 0), "ndfb_describe_image: ctx and path must not be null");
        const ImageInfo info = read_image_info(path);
        std::string s = "file: " + std::string(path) + "\nformat: " + info.format + "\nsize: " +
                        std::to_string(info.width) + "x" + std::to_string(info.height) + "\nchannels: " +
                        std::to_string(info.channels) + "\npixel type: " + info.pixel_type + "\n";
        if (info.tile_width > 0)
            s += "tiles: " + std::to_string(info.tile_width) + "x" + std::to_string(info.tile_height) + "\n";
        if (info.mip_levels.size() > 1) {
            s += "MIP levels: " + std::to_string(info.mip_levels.size()) + "\n";
            for (size_t level = 0; level < info.mip_levels.size(); ++level)
                s += "  level " + std::to_string(level) + ": " + std::to_string(info.mip_levels[level].first) + "x" +
                     std::to_string(info.mip_levels[level].second) + "\n";
        }
        std::string lobe, slots, fitted;
        for (const auto& [name, value] : info.attributes) {
            if (name == "ndfbake:lobe") lobe = value;
            if (name == "ndfbake:lobe_slots") slots = value;
            if (name == "ndfbake:fitted_levels") fitted = value;
        }
        if (!lobe.empty() && !slots.empty()) s += "lobe slot: " + lobe + " of " + slots + " (0-based)\n";
        if (!fitted.empty() && info.mip_levels.size() > 1)
            s += "fitted levels: " + fitted + " of " + std::to_string(info.mip_levels.size()) +
                 (std::to_string(info.mip_levels.size()) == fitted ? "" : " (the rest averaged from the last fitted)") +
                 "\n";
        for (const auto& [name, value] : info.attributes) s += name + ": " + value + "\n";
        if (length) *length = s.size();
        if (capacity > 0) {
            const size_t n = std::min(capacity - 1, s.size());
            std::memcpy(text, s.data(), n);
            text[n] = '\0';
        }
    });
}

}  // extern "C"
