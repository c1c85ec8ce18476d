// What the C API's object files share beyond capi/context.h: the structs behind ndfb_normal_map,
// ndfb_pyramid and ndfb_bake_result, the option structs' translation into the core's settings (defined in
// capi/options.cpp) and the pyramid argument checks. Internal to capi/; calls nothing but the
// core's headers.
#pragma once

#include <cstdint>
#include <string>

#include "bake/bake.h"
#include "capi/context.h"
#include "ndfbake.h"

struct ndfb_normal_map_s {
    ndfbake::DecodeResult decoded;
};

struct ndfb_pyramid_s {
    ndfbake::LobePyramid pyramid;
};

struct ndfb_bake_result_s {
    ndfbake::BakeOutcome outcome;
};

namespace ndfbake {

// Each option struct as the core's settings, its fields checked (NDFB_ERROR_INVALID_ARGUMENT).
// A null decode or write struct means the defaults; a null fit struct is refused.
DecodeOptions to_decode(const ndfb_decode_options* o);
BaseBrdf to_brdf(int brdf, float parameter);
WrapMode to_wrap(int wrap);
PyramidSettings to_pyramid(const ndfb_fit_options* o);
WriteSettings to_write(const ndfb_write_options* o);
// The write settings for a map from memory: its files name "memory" as their source where the
// caller names none (ndfb_bake names the input file instead).
WriteSettings to_memory_write(const ndfb_write_options* o);
// A call's progress callback as the core's (none where it is null).
StageProgress to_progress(ndfb_progress_fn progress, void* user);

inline const LobePyramid& pyramid_of(ndfb_pyramid p)
{
    require(p != nullptr, "pyramid is null");
    return p->pyramid;
}

inline void require_level(const LobePyramid& p, uint32_t level)
{
    require(level < uint32_t(p.level_count()), "level " + std::to_string(level) + " does not exist (the pyramid has " +
                                                   std::to_string(p.level_count()) + ")");
}

}  // namespace ndfbake
