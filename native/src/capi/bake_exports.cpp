// C entry points that write a bake's files: a fitted pyramid's (ndfb_pyramid_write) and the whole
// bake from a file or a map (ndfb_bake, ndfb_bake_map). Calls capi/handles.h and bake/bake.h.
#include "capi/handles.h"

using namespace ndfbake;

extern "C" {

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

}  // extern "C"
