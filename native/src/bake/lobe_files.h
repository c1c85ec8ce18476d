// What each image file of a bake holds, apart from writing them into place: the texel encodings
// of the lobe and colour textures, their EXR attributes, the atlas and MIP-mapped files. Internal
// to bake/: bake.cpp writes these files, report.cpp describes them. Calls io/ (EXR writing),
// ndf/, pyramid/ and bake/lobe_atlas; nothing here touches a folder but the path it is given.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "bake/bake.h"
#include "bake/level_stats.h"
#include "bake/lobe_atlas.h"
#include "io/color_decode.h"

namespace ndfbake {

inline constexpr int kFileFormatVersion = 1;

// Per-lobe colour textures of a level, one per slot (RGB = α·colour, A = α).
std::vector<std::vector<float>> color_textures(const LobePyramid& pyramid, const ColorImage& color, int level);

// Where each fitted level sits in an atlas of the pyramid.
AtlasLayout pyramid_atlas_layout(const LobePyramid& pyramid);

// A 64-bit value as 16 lower-case hex digits.
std::string hex64(uint64_t value);

// The ndfbake:* attributes every file of a bake carries (level and lobe -1 where not one).
std::vector<ExrAttribute> file_attributes(const LobePyramid& pyramid, const DecodeResult& decoded,
                                          const PyramidSettings& settings, const WriteSettings& write,
                                          int level, int lobe, float level_error, const char* content);

// The atlas file of a slot (write option atlas): "atlas_lobe1.exr".
std::string atlas_file_name(int lobe);

void write_atlas(const LobePyramid& pyramid, const DecodeResult& decoded, const PyramidSettings& settings,
                 const WriteSettings& write, const AtlasLayout& layout, int lobe, const std::string& path);

void write_mip_file(const LobePyramid& pyramid, const DecodeResult& decoded, const PyramidSettings& settings,
                    const WriteSettings& write, const std::vector<LevelStats>& stats, int lobe,
                    const std::string& path);

}  // namespace ndfbake
