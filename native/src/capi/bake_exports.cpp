// C entry points that write a bake's files: a fitted pyramid's (ndfb_pyramid_write) and the whole
// bake from a file or a map (ndfb_bake, ndfb_bake_map), each handing back what it wrote as an
// ndfb_bake_result (capi/bake_result_exports.cpp reads it). Calls capi/handles.h and bake/bake.h.
#include <memory>

#include "capi/handles.h"

using namespace ndfbake;

namespace {

// Runs a bake and, where the caller asked for it, keeps its outcome in a new result handle. The
// handle is allocated before the bake, so that no bake's files are left without one to say so.
template <typename Bake>
void bake_into_result(ndfb_bake_result* out, Bake&& bake)
{
    auto result = out ? std::make_unique<ndfb_bake_result_s>() : nullptr;
    BakeOutcome outcome = bake();
    if (result) {
        result->outcome = std::move(outcome);
        *out = result.release();
    }
}

}  // namespace

extern "C" {

NDFB_API ndfb_status ndfb_pyramid_write(ndfb_context ctx, ndfb_pyramid p, ndfb_normal_map map, const char* out_dir,
                                        const ndfb_write_options* options, ndfb_progress_fn progress,
                                        void* progress_user, ndfb_bake_result* out)
{
    if (out) *out = nullptr;
    return guarded(ctx, [&] {
        require(ctx && map && out_dir, "ndfb_pyramid_write: ctx, map and out_dir must not be null");
        const LobePyramid& pyramid = pyramid_of(p);
        require(pyramid.source.width == map->decoded.map.width && pyramid.source.height == map->decoded.map.height,
                "the pyramid was fitted to a map of another size");
        const WriteSettings write = to_memory_write(options);
        bake_into_result(out, [&] {
            return write_pyramid(pyramid, map->decoded, out_dir, pyramid.settings, write, BakeTimings{},
                                 to_progress(progress, progress_user));
        });
    });
}

NDFB_API ndfb_status ndfb_bake(ndfb_context ctx, const char* input_path, const char* out_dir,
                               const ndfb_decode_options* decode, const ndfb_fit_options* fit,
                               const ndfb_write_options* write, ndfb_progress_fn progress, void* progress_user,
                               ndfb_bake_result* out)
{
    if (out) *out = nullptr;
    return guarded(ctx, [&] {
        require(ctx && input_path && out_dir && fit, "ndfb_bake: ctx, input_path, out_dir and fit must not be null");
        bake_into_result(out, [&] {
            return bake_file(input_path, out_dir, to_decode(decode), to_pyramid(fit), to_write(write),
                             to_progress(progress, progress_user));
        });
    });
}

NDFB_API ndfb_status ndfb_bake_map(ndfb_context ctx, ndfb_normal_map map, const char* out_dir,
                                   const ndfb_fit_options* fit, const ndfb_write_options* write,
                                   ndfb_progress_fn progress, void* progress_user, ndfb_bake_result* out)
{
    if (out) *out = nullptr;
    return guarded(ctx, [&] {
        require(ctx && map && out_dir && fit, "ndfb_bake_map: ctx, map, out_dir and fit must not be null");
        bake_into_result(out, [&] {
            return bake_map(map->decoded, out_dir, to_pyramid(fit), to_memory_write(write),
                            to_progress(progress, progress_user));
        });
    });
}

}  // extern "C"
