// The C API of ndfbake_research.h: the ground truth (a texel's exact effective BRDF, a
// representation's error against it) and the benchmark (parses the option lists, runs
// bench/benchmark). Built into the full library only.
#include <algorithm>
#include <cstdlib>
#include <sstream>
#include <string>
#include <vector>

#include "ndfbake_research.h"

#include "bake/level_stats.h"
#include "bench/benchmark.h"
#include "capi/context.h"
#include "capi/handles.h"
#include "io/normal_decode.h"
#include "math/sphere.h"
#include "ndf/moments.h"
#include "platform/files.h"
#include "synth/patterns.h"

namespace {

using namespace ndfbake;

std::vector<std::string> split_list(const char* text)
{
    std::vector<std::string> items;
    if (!text) return items;
    std::stringstream stream(text);
    std::string item;
    while (std::getline(stream, item, ','))
        if (!item.empty()) items.push_back(item);
    return items;
}

BenchSettings to_bench(const ndfb_bench_options* o)
{
    // ndfb_bench_options has not grown since ABI 1 first shipped: every field is read.
    require_struct_size(o, "bench options", sizeof(ndfb_bench_options), "ndfb_bench_options_init");
    require(o->map_count == 0 || o->map_paths, "bench: map_paths is null");
    require(o->synthetic_size <= 4096, "bench: synthetic_size must be at most 4096");
    BenchSettings s;
    if (o->synthetic_size > 0)
        for (Pattern p : all_patterns())
            s.maps.emplace_back(pattern_name(p), synthesize(p, int(o->synthetic_size), int(o->synthetic_size)));
    for (size_t i = 0; i < o->map_count; ++i) {
        require(o->map_paths[i], "bench: map path is null");
        s.maps.emplace_back(path_to_utf8(path_from_utf8(o->map_paths[i]).stem()),
                            decode_normal_map(o->map_paths[i], DecodeOptions{}).map);
    }
    require(!s.maps.empty(), "bench: no maps (synthetic_size is 0 and no paths)");

    const std::vector<std::string> known = bench_method_names();
    s.methods = split_list(o->methods);
    for (const std::string& m : s.methods)
        require(std::find(known.begin(), known.end(), m) != known.end() || m.rfind("sh-", 0) == 0,
                "bench: unknown method '" + m + "'");
    for (const std::string& b : o->brdfs ? split_list(o->brdfs) : std::vector<std::string>{"ggx:0.3", "ggx:0.6"})
        s.brdfs.push_back(BaseBrdf::parse(b));
    for (const std::string& l : o->levels ? split_list(o->levels) : std::vector<std::string>{"2", "4", "6"}) {
        char* end = nullptr;
        const long level = std::strtol(l.c_str(), &end, 10);
        require(*end == '\0' && level >= 0 && level <= 16, "bench: bad level '" + l + "'");
        s.levels.push_back(int(level));
    }
    s.texels_per_level = o->texels_per_level > 0 ? int(o->texels_per_level) : 64;
    s.threads = int(o->threads);
    return s;
}

}  // namespace

extern "C" {

NDFB_API void ndfb_bench_options_init(ndfb_bench_options* o)
{
    if (!o) return;
    *o = {};
    o->struct_size = sizeof *o;
    o->synthetic_size = 256;
    o->texels_per_level = 64;
}

NDFB_API ndfb_status ndfb_bench(ndfb_context ctx, const ndfb_bench_options* options, const char* out_dir,
                                ndfb_progress_fn progress, void* progress_user)
{
    return guarded(ctx, [&] {
        require(ctx && out_dir, "ndfb_bench: ctx and out_dir must not be null");
        const BenchSettings settings = to_bench(options);
        const size_t total = settings.maps.size() * (settings.methods.empty() ? bench_method_names().size()
                                                                              : settings.methods.size());
        size_t done = 0;
        run_benchmark(settings, out_dir, [&](const std::string& line) {
            ++done;
            return !progress || progress(progress_user, line.c_str(), float(done) / float(total)) == 0;
        });
    });
}

NDFB_API ndfb_status ndfb_effective_brdf_reference(ndfb_context ctx, ndfb_normal_map map, ndfb_wrap wrap,
                                                   uint32_t level, uint32_t x, uint32_t y, ndfb_brdf brdf,
                                                   float brdf_parameter, const float* directions,
                                                   size_t direction_count, float* values)
{
    return guarded(ctx, [&] {
        require(ctx && map && directions && values, "ndfb_effective_brdf_reference: null argument");
        const NormalMap& m = map->decoded.map;
        require(level < uint32_t(level_count(m.width, m.height)), "level " + std::to_string(level) + " does not exist");
        const LevelSize size = level_size(m.width, m.height, int(level));
        require(x < uint32_t(size.width) && y < uint32_t(size.height), "texel outside the level");
        std::vector<Vec3> dirs(direction_count);
        for (size_t i = 0; i < direction_count; ++i)
            dirs[i] = normalize_or({directions[3 * i], directions[3 * i + 1], directions[3 * i + 2]}, {0, 0, 1});
        std::vector<WeightedNormal> samples;
        gather_footprint(m, int(level), int(x), int(y), to_wrap(raw(wrap)), samples);
        reference_effective_brdf(samples, to_brdf(raw(brdf), brdf_parameter), dirs, std::span(values, direction_count));
    });
}

NDFB_API ndfb_status ndfb_texel_error(ndfb_context ctx, ndfb_normal_map map, ndfb_pyramid p,
                                      ndfb_representation representation, ndfb_wrap wrap, uint32_t level, uint32_t x,
                                      uint32_t y, ndfb_brdf brdf, float brdf_parameter, float* error)
{
    return guarded(ctx, [&] {
        require(ctx && map && error, "ndfb_texel_error: ctx, map and error must not be null");
        const NormalMap& m = map->decoded.map;
        require(level < uint32_t(level_count(m.width, m.height)), "level " + std::to_string(level) + " does not exist");
        const LevelSize size = level_size(m.width, m.height, int(level));
        require(x < uint32_t(size.width) && y < uint32_t(size.height), "texel outside the level");
        const BaseBrdf base = to_brdf(raw(brdf), brdf_parameter);
        std::vector<WeightedNormal> samples;
        gather_footprint(m, int(level), int(x), int(y), to_wrap(raw(wrap)), samples);
        const std::vector<Vec3> directions = fibonacci_hemisphere(error_direction_count(base));
        const TexelErrorMeter meter(samples, base, directions);
        std::vector<VmfLobe> lobes;
        switch (raw(representation)) {
        case NDFB_REPR_VMF_MIXTURE: {
            const LobePyramid& pyramid = pyramid_of(p);
            require(pyramid.source.width == m.width && pyramid.source.height == m.height,
                    "the pyramid was fitted to a map of another size");
            require_level(pyramid, level);
            lobes = pyramid.texel_lobes(int(level), int(x), int(y));
            break;
        }
        case NDFB_REPR_SINGLE_VMF: lobes = {single_vmf_lobe(samples)}; break;
        case NDFB_REPR_TOKSVIG: lobes = {toksvig_lobe(samples)}; break;
        default: throw Error(Status::invalid_argument, "unknown representation");
        }
        *error = meter.error(lobes);
    });
}

}  // extern "C"
