// C entry points of normal maps (ndfb_normal_map): loading, from pixels, synthesizing, reading
// back, saving, and describing an image file. Calls capi/handles.h, io/ and synth/.
#include <algorithm>
#include <cstddef>
#include <cstring>
#include <memory>
#include <string>

#include "capi/handles.h"
#include "io/image_files.h"
#include "io/normal_encode.h"
#include "synth/patterns.h"

using namespace ndfbake;

extern "C" {

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
