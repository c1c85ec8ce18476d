// report.json: what a bake read, how it fitted, how well (per level, against the baselines), what
// it cost and which files it wrote. Internal to bake/: bake.cpp calls it; it calls bake/lobe_files,
// bake/memory_budget and io/json_writer, and writes nothing itself.
#pragma once

#include <string>
#include <vector>

#include "bake/bake.h"
#include "bake/level_stats.h"

namespace ndfbake {

inline constexpr const char* kReportFileName = "report.json";

// The report's text; `files` are the bake's files (paths or names) other than report.json.
std::string report_json(const LobePyramid& pyramid, const DecodeResult& decoded, const PyramidSettings& settings,
                        const WriteSettings& write, const std::vector<LevelStats>& stats,
                        const BakeTimings& timings, const std::vector<std::string>& files);

}  // namespace ndfbake
