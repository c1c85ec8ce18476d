// The C API of the benchmark: parses the option lists and runs bench/benchmark.
#include <algorithm>
#include <cstdlib>
#include <sstream>

#include "bench/benchmark.h"
#include "capi/context.h"
#include "io/image_files.h"
#include "io/normal_decode.h"
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

NDFB_API ndfb_status ndfb_bench(ndfb_context ctx, const ndfb_bench_options* options, const char* out_dir)
{
    return guarded(ctx, [&] {
        require(ctx && out_dir, "ndfb_bench: ctx and out_dir must not be null");
        // Refused before minutes of measuring: the run ends by writing PNG heat maps.
        if (!reads_image_files()) refuse_image_files("ndfb_bench");
        const BenchSettings settings = to_bench(options);
        const size_t total = settings.maps.size() * (settings.methods.empty() ? bench_method_names().size()
                                                                              : settings.methods.size());
        size_t done = 0;
        run_benchmark(settings, out_dir, [&](const std::string& line) {
            ++done;
            return !options->progress || options->progress(options->progress_user, line.c_str(), float(done) / float(total)) == 0;
        });
    });
}

}  // extern "C"
