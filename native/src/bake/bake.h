// The whole bake: decode a normal map, fit its lobe pyramid, write lobe textures and a report.
// The C API, the command line and the Blender add-on all run this one path.
#pragma once

#include <functional>
#include <string>
#include <string_view>
#include <vector>

#include "bake/lobe_atlas.h"
#include "bake/write_settings.h"
#include "io/lobe_exr.h"
#include "io/normal_decode.h"
#include "pyramid/lobe_pyramid.h"

namespace ndfbake {

// Progress of a bake: stage name and fraction of the stage; return false to cancel.
using StageProgress = std::function<bool(const char* stage, double fraction)>;

struct BakeTimings {
    double decode = 0.0, fit = 0.0, measure = 0.0, write = 0.0;  // seconds
};

enum class BakeFileKind { lobe, color, atlas, mip, shader, report };

// One file a bake wrote: its kind, the level and slot it holds (-1: not one level's or slot's)
// and its name in the bake's folder.
struct BakeFile {
    BakeFileKind kind = BakeFileKind::lobe;
    int level = -1;
    int slot = -1;
    std::string name;
};

// What a bake wrote: its levels and slots, the slots any texel uses, the atlas layout (empty where
// no atlas was written) and its files, report.json last.
struct BakeOutcome {
    std::vector<LevelSize> levels;
    int slots = 0;
    std::vector<bool> slots_used;
    AtlasLayout atlas;
    std::vector<BakeFile> files;
    BakeTimings timings;
};

// Whether `name` (no folder) is one of the files a bake writes.
bool is_bake_file(std::string_view name);

// The texels of slot `slot` of a level as its lobe texture stores them: R = α, GBA = α·r, with
// |r| the mean resultant length of the lobe's κ (1 at the κ cap).
std::vector<float> lobe_texture(const LobePyramid& pyramid, int level, int slot);

// Lobe texture file name for a level and slot: "level03_lobe1.exr".
std::string lobe_file_name(int level, int lobe);
std::string color_file_name(int level, int lobe);
// The MIP-mapped file of a slot (write option mipmap): "mip_lobe1.exr".
std::string mip_file_name(int lobe);

// Writes the pyramid's files into out_dir. Everything goes to a staging folder inside out_dir
// first and is renamed into place only once all of it is written, so a failure or a cancel leaves
// out_dir exactly as it was (an earlier bake stays whole); stale files of an earlier bake with
// more levels or lobes are removed at that point.
BakeOutcome write_pyramid(const LobePyramid& pyramid, const DecodeResult& decoded, const std::string& out_dir,
                          const PyramidSettings& settings, const WriteSettings& write, BakeTimings timings,
                          const StageProgress& progress);

// Fits a decoded map and writes its files into out_dir: what bake_file does after decoding, with
// the same up-front checks (writable out_dir, memory, colour image) and progress stages ("fit",
// "measure", "write"). The files name write.source_name as their source.
BakeOutcome bake_map(const DecodeResult& decoded, const std::string& out_dir, const PyramidSettings& settings,
                     const WriteSettings& write, const StageProgress& progress);

// Decodes the image at input_path, then bakes it as bake_map does (with a "decode" stage first).
BakeOutcome bake_file(const std::string& input_path, const std::string& out_dir, const DecodeOptions& decode,
                      const PyramidSettings& settings, const WriteSettings& write, const StageProgress& progress);

}  // namespace ndfbake
