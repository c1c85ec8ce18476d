// C entry points that read an ndfb_bake_result (what a bake wrote: levels, slots, atlas layout,
// files) and name a bake's files. Plain reads of the outcome bake/bake.h describes: no context, a
// bad handle or index is NDFB_ERROR_INVALID_ARGUMENT. Calls capi/handles.h and bake/bake.h.
#include <cstddef>
#include <cstdint>

#include "capi/handles.h"

using namespace ndfbake;

namespace {

ndfb_file_kind to_file_kind(BakeFileKind kind)
{
    switch (kind) {
    case BakeFileKind::lobe: return NDFB_FILE_LOBE;
    case BakeFileKind::color: return NDFB_FILE_COLOR;
    case BakeFileKind::atlas: return NDFB_FILE_ATLAS;
    case BakeFileKind::mip: return NDFB_FILE_MIP;
    case BakeFileKind::shader: return NDFB_FILE_SHADER;
    case BakeFileKind::report: return NDFB_FILE_REPORT;
    }
    return NDFB_FILE_REPORT;
}

}  // namespace

extern "C" {

NDFB_API void ndfb_bake_result_destroy(ndfb_bake_result result) { delete result; }

NDFB_API uint32_t ndfb_bake_result_level_count(ndfb_bake_result r)
{
    return r ? uint32_t(r->outcome.levels.size()) : 0;
}

NDFB_API ndfb_status ndfb_bake_result_level_size(ndfb_bake_result r, uint32_t level, uint32_t* width, uint32_t* height)
{
    if (!r || !width || !height || level >= r->outcome.levels.size()) return NDFB_ERROR_INVALID_ARGUMENT;
    *width = uint32_t(r->outcome.levels[level].width);
    *height = uint32_t(r->outcome.levels[level].height);
    return NDFB_OK;
}

NDFB_API uint32_t ndfb_bake_result_lobe_slots(ndfb_bake_result r) { return r ? uint32_t(r->outcome.slots) : 0; }

NDFB_API ndfb_status ndfb_bake_result_slots_used(ndfb_bake_result r, uint8_t* used, size_t count)
{
    if (!r || !used || count != r->outcome.slots_used.size()) return NDFB_ERROR_INVALID_ARGUMENT;
    for (size_t j = 0; j < count; ++j) used[j] = r->outcome.slots_used[j] ? 1 : 0;
    return NDFB_OK;
}

NDFB_API ndfb_status ndfb_bake_result_atlas_size(ndfb_bake_result r, uint32_t* width, uint32_t* height)
{
    if (!r || !width || !height) return NDFB_ERROR_INVALID_ARGUMENT;
    *width = uint32_t(r->outcome.atlas.width);
    *height = uint32_t(r->outcome.atlas.height);
    return NDFB_OK;
}

NDFB_API ndfb_status ndfb_bake_result_atlas_frame(ndfb_bake_result r, uint32_t level, ndfb_atlas_frame* out)
{
    if (!r || !out || level >= r->outcome.atlas.levels.size()) return NDFB_ERROR_INVALID_ARGUMENT;
    const AtlasLevel& frame = r->outcome.atlas.levels[level];
    *out = {uint32_t(frame.x), uint32_t(frame.y), uint32_t(frame.width), uint32_t(frame.height)};
    return NDFB_OK;
}

NDFB_API uint32_t ndfb_bake_result_file_count(ndfb_bake_result r) { return r ? uint32_t(r->outcome.files.size()) : 0; }

NDFB_API ndfb_status ndfb_bake_result_file(ndfb_bake_result r, uint32_t index, ndfb_bake_file* out)
{
    if (!r || !out || index >= r->outcome.files.size()) return NDFB_ERROR_INVALID_ARGUMENT;
    const BakeFile& file = r->outcome.files[index];
    *out = {to_file_kind(file.kind), int32_t(file.level), int32_t(file.slot), file.name.c_str()};
    return NDFB_OK;
}

NDFB_API int32_t ndfb_is_bake_file(const char* name)
{
    return name && is_bake_file(name) ? 1 : 0;
}

}  // extern "C"
