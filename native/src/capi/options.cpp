// The option structs of the C API: their *_init functions and their translation into the core's
// settings (declared in capi/handles.h), with every field checked. Calls capi/context.h's checks
// and the core's settings types; no other entry point.
#include <cstddef>
#include <string>

#include "capi/handles.h"

namespace ndfbake {

namespace {

// What each option struct held in minor version 0 of ABI 2 (require_struct_size): every field so
// far. A field a later minor version adds is read only where struct_size covers it
// (NDFB_SIZE_THROUGH).
constexpr size_t kDecodeOptionsFirstSize = sizeof(ndfb_decode_options);
constexpr size_t kFitOptionsFirstSize = sizeof(ndfb_fit_options);
constexpr size_t kWriteOptionsFirstSize = sizeof(ndfb_write_options);

}  // namespace

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
    require(o->max_lobes >= 1 && o->max_lobes <= uint32_t(kMaxLobes),
            "max_lobes must be in 1.." + std::to_string(kMaxLobes) + ", got " + std::to_string(o->max_lobes));
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
    s.max_memory_bytes = o->max_memory_bytes;
    require(o->max_levels <= 64, "max_levels must be at most 64 (0: every level), got " + std::to_string(o->max_levels));
    s.max_levels = int(o->max_levels);
    require(o->starts == 1 || o->starts == 2, "starts must be 1 or 2, got " + std::to_string(o->starts));
    s.fit.two_starts = o->starts == 2;
    s.refine = o->refine != 0;
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
    w.atlas = o->atlas != 0;
    w.mipmap = o->mipmap != 0;
    return w;
}

WriteSettings to_memory_write(const ndfb_write_options* o)
{
    WriteSettings w = to_write(o);
    if (w.source_name.empty()) w.source_name = "memory";
    return w;
}

StageProgress to_progress(ndfb_progress_fn progress, void* user)
{
    if (!progress) return {};
    return [progress, user](const char* stage, double fraction) { return progress(user, stage, float(fraction)) == 0; };
}

}  // namespace ndfbake

using namespace ndfbake;

extern "C" {

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

NDFB_API ndfb_status ndfb_fit_options_check(ndfb_context ctx, const ndfb_fit_options* options)
{
    return guarded(ctx, [&] {
        require(ctx, "ndfb_fit_options_check: ctx must not be null");
        to_pyramid(options);
    });
}

NDFB_API void ndfb_write_options_init(ndfb_write_options* o)
{
    if (!o) return;
    *o = {};
    o->struct_size = sizeof *o;
    o->precision = NDFB_PRECISION_HALF;
}

}  // extern "C"
