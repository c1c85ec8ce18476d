// `ndfbake bench`: every representation on the same maps, footprints and error measure, in one
// run: build time, storage per texel, and effective-BRDF error (mean and 95th percentile).
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "math/brdf.h"
#include "normal_map.h"

namespace ndfbake {

struct BenchSettings {
    std::vector<std::pair<std::string, NormalMap>> maps;  // name, map
    std::vector<std::string> methods;                     // empty: every method (bench_method_names)
    std::vector<BaseBrdf> brdfs;
    std::vector<int> levels;
    int texels_per_level = 64;  // measured texels per level, spread evenly
    int threads = 0;
    std::string heatmap_map;    // the map whose per-level error heat maps are written ("" = first)
};

struct BenchRow {
    std::string map, method, brdf;
    int level = 0;
    double build_seconds = 0.0;
    double floats_per_texel = 0.0;
    double mean_error = 0.0, p95_error = 0.0;
};

// "bake-default" (what `ndfbake bake` runs), "vmf-1" … "vmf-8" (fixed lobe counts),
// "vmf-4-per-level", and every baseline of baselines/registry.h.
std::vector<std::string> bench_method_names();

// Runs the benchmark and writes into out_dir: bench.csv (one row per map, method, BRDF and level),
// bench.md (means over maps and levels per method and BRDF, Pareto-optimal rows marked) and
// heatmap_<method>_level<L>.png (per-texel error of the default bake and Toksvig, for one map).
// `progress` gets a line per finished (map, method), one per BRDF for methods fitted to it.
// Returns the rows.
std::vector<BenchRow> run_benchmark(const BenchSettings& settings, const std::string& out_dir,
                                    const std::function<bool(const std::string& line)>& progress);

}  // namespace ndfbake
