// The `ndfbake` command line: a client of the public C API, like the Blender add-on.
#if defined(_WIN32)
#include <io.h>
#include <process.h>
#else
#include <unistd.h>
#endif

#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <string>
#include <vector>

#include "ndfbake_research.h"  // ndfbake.h and the ground truth, the benchmark

namespace {

// The two POSIX calls the command line makes, under their Windows C runtime names there.
bool stderr_is_terminal()
{
#if defined(_WIN32)
    return _isatty(_fileno(stderr)) != 0;
#else
    return isatty(fileno(stderr)) != 0;
#endif
}

long process_id()
{
#if defined(_WIN32)
    return long(_getpid());
#else
    return long(::getpid());
#endif
}

// Paths are UTF-8 strings, as the C API takes them (a char path would be read in the ANSI code
// page on Windows).
std::filesystem::path path_from_utf8(const std::string& utf8)
{
    return std::filesystem::path(std::u8string(utf8.begin(), utf8.end()));
}

std::string path_to_utf8(const std::filesystem::path& path)
{
    const std::u8string utf8 = path.u8string();
    return std::string(utf8.begin(), utf8.end());
}

const char* const kUsage = R"(ndfbake — normal-map NDF filtering (Han et al. 2007)

usage:
  ndfbake bake INPUT --out DIR [options]   fit lobes per MIP texel; write lobe EXRs, report.json, ndfbake.glsl
  ndfbake synth PATTERN --size N [--height H] [--seed S] --out FILE
                                           write a synthetic tileable normal map
                                           (vgroove, bumps, fbm, brushed, scratches, weave)
  ndfbake info FILE                        describe an image and its ndfbake attributes
  ndfbake bench [MAP...] --out DIR [options]
                                           every representation on the six synthetic patterns
                                           and the given maps: time, storage, error (CSV, Markdown,
                                           heat maps; examples/plot_bench.py draws the chart)
  ndfbake --help | --version

bake options:
  --max-lobes N        most vMF lobes per texel, 1..8 (default 4)
  --tolerance T        use fewer lobes in a texel while its relative effective-BRDF error
                       stays at most T (default 0: --max-lobes wherever the normals differ)
  --brdf SPEC          base BRDF the tolerance is measured with: ggx:ROUGHNESS (Blender's
                       roughness, default ggx:0.5), blinn-phong:EXPONENT,
                       beckmann:SLOPE, or lambert
  --convention C       opengl (+Y, Blender) or directx (-Y) input (default opengl)
  --wrap W             repeat (tiling texture, default) or clamp
  --srgb P             data (default: an sRGB tag is ignored, values are the normal) or linearize
  --color FILE         base-colour image of the same size: also write per-lobe colour EXRs
  --precision P        half (default) or float EXR pixels
  --levels N           fit and write levels 0..N-1 only (default 0: every level down to 1x1)
  --atlas              also write atlas_lobeJ.exr: every level of lobe slot J in one image
                       (for renderers without MIP levels; layout in report.json)
  --mipmap             also write mip_lobeJ.exr: lobe slot J as one tiled MIP-mapped EXR whose
                       levels are the fitted levels (OpenImageIO's texture system, OSL, engines)
  --method M           hierarchical (default: every level from the binned normals of the level
                       below) or per-level (every level from all its fine normals: Han's
                       reference, 4-5x slower)
  --iterations N       EM iterations per texel at most (default 10; the hierarchical fit runs
                       one k-means step at levels 2-3, at most 3 iterations at levels 4-5 and
                       5 above)
  --starts N           2 (default): EM from the finer level's lobes and from the farthest
                       samples, keeping the likelier (the hierarchical fit: above level 5);
                       1: from the finer level's lobes (Han 7.1)
  --refine             after EM, refine every texel's lobes against the effective BRDF of
                       --brdf (lower error for that BRDF; 100-300x the fitting time). EM then
                       fits every level in full (no k-means; one start only up to 64 samples)
  --no-align           fit texels independently (no lobe alignment across texels and levels)
  --threads N          worker threads (default: all cores)
  --max-memory SIZE    refuse a map whose bake would need more memory than SIZE bytes (K, M,
                       G: binary multiples; default: the physical memory)
  --quiet              no progress output

bench options:
  --size N             side of the synthetic patterns (default 256; 0 leaves them out)
  --methods LIST       comma-separated: bake-default, vmf-1 … vmf-8, vmf-4-per-level,
                       vmf-4-refined (bake --refine, fitted for each BRDF measured), naive,
                       toksvig, single-vmf, lean, xu-1x1, xu-1x4, xu-2x4, xu-adaptive, sh-2 … sh-8
                       (default: all)
  --brdfs LIST         comma-separated BRDF specs as for bake (default ggx:0.3,ggx:0.6)
  --levels LIST        comma-separated MIP levels (default 2,4,6)
  --texels N           texels measured per level (default 64)
  --threads N

Exit status: 0 on success; 1 bad usage; 2 bad input; 3 cannot write output; 4 other failure;
130 interrupted (no output is left behind).
)";

volatile std::sig_atomic_t g_interrupted = 0;
void on_interrupt(int) { g_interrupted = 1; }

struct Args {
    std::vector<std::string> positional;
    std::vector<std::pair<std::string, std::string>> options;  // name → value ("" for flags)
};

bool is_flag(const std::string& name)
{
    return name == "--no-align" || name == "--quiet" || name == "--atlas" || name == "--refine" ||
           name == "--mipmap";
}

bool parse_args(int argc, char** argv, int first, Args& args, std::string& error)
{
    for (int i = first; i < argc; ++i) {
        const std::string a = argv[i];
        if (a.rfind("--", 0) != 0) {
            args.positional.push_back(a);
            continue;
        }
        if (is_flag(a)) {
            args.options.emplace_back(a, "");
            continue;
        }
        if (i + 1 >= argc) {
            error = "option " + a + " needs a value";
            return false;
        }
        args.options.emplace_back(a, argv[++i]);
    }
    return true;
}

int fail(int code, const std::string& message)
{
    std::fprintf(stderr, "ndfbake: %s\n", message.c_str());
    return code;
}

int exit_code_for(ndfb_status status)
{
    switch (status) {
    case NDFB_OK: return 0;
    case NDFB_ERROR_INVALID_ARGUMENT: return 1;
    case NDFB_ERROR_FILE_NOT_FOUND:
    case NDFB_ERROR_UNSUPPORTED_FORMAT:
    case NDFB_ERROR_CORRUPT_FILE:
    case NDFB_ERROR_OUT_OF_MEMORY: return 2;
    case NDFB_ERROR_IO: return 3;
    case NDFB_ERROR_CANCELLED: return 130;
    default: return 4;
    }
}

int fail_status(ndfb_context ctx, ndfb_status status)
{
    if (status == NDFB_ERROR_CANCELLED) return fail(130, "interrupted; no output was written");
    return fail(exit_code_for(status), std::string(ndfb_status_name(status)) + ": " + ndfb_last_error(ctx));
}

bool parse_number(const std::string& text, double& out)
{
    char* end = nullptr;
    out = std::strtod(text.c_str(), &end);
    return !text.empty() && end && *end == '\0';
}

// A byte count, optionally with a binary K, M or G suffix: "512M", "8G", "1000000".
bool parse_bytes(const std::string& text, uint64_t& out)
{
    if (text.empty()) return false;
    const char suffix = text.back();
    const int shift = suffix == 'K' ? 10 : suffix == 'M' ? 20 : suffix == 'G' ? 30 : 0;
    double number = 0.0;
    if (!parse_number(shift ? text.substr(0, text.size() - 1) : text, number) || !(number >= 1.0)) return false;
    const double bytes = std::ldexp(number, shift);
    if (!(bytes < 1.8e19)) return false;  // past uint64_t
    out = uint64_t(bytes);
    return true;
}

bool parse_brdf(const std::string& spec, ndfb_fit_options& fit)
{
    if (spec == "lambert") {
        fit.brdf = NDFB_BRDF_LAMBERT;
        return true;
    }
    const auto colon = spec.find(':');
    double value = 0.0;
    if (colon == std::string::npos || !parse_number(spec.substr(colon + 1), value)) return false;
    const std::string name = spec.substr(0, colon);
    if (name == "ggx") fit.brdf = NDFB_BRDF_GGX;
    else if (name == "blinn-phong") fit.brdf = NDFB_BRDF_BLINN_PHONG;
    else if (name == "beckmann") fit.brdf = NDFB_BRDF_BECKMANN;
    else return false;
    fit.brdf_parameter = float(value);
    return true;
}

struct ProgressState {
    bool quiet = false;
    bool terminal = false;  // redraw one line in place; logs get a line per 10%
    int last_percent = -1;
    std::string last_stage;
};

int print_progress(void* user, const char* stage, float fraction)
{
    auto* state = static_cast<ProgressState*>(user);
    if (!state->quiet) {
        const int step = state->terminal ? 1 : 10;
        const int percent = int(fraction * 100.0f) / step * step;
        if (percent != state->last_percent || state->last_stage != stage) {
            if (state->terminal) {
                std::fprintf(stderr, "\r%-8s %3d%%", stage, percent);
                if (percent >= 100) std::fputc('\n', stderr);
            } else {
                std::fprintf(stderr, "%s %d%%\n", stage, percent);
            }
            std::fflush(stderr);
            state->last_percent = percent;
            state->last_stage = stage;
        }
    }
    return g_interrupted ? 1 : 0;
}

int run_bake(ndfb_context ctx, const Args& args)
{
    if (args.positional.size() != 1) return fail(1, "bake needs exactly one INPUT (see --help)");
    ndfb_decode_options decode;
    ndfb_fit_options fit;
    ndfb_write_options write;
    ndfb_decode_options_init(&decode);
    ndfb_fit_options_init(&fit);
    ndfb_write_options_init(&write);
    std::string out_dir, color;
    ProgressState progress;
    for (const auto& [name, value] : args.options) {
        double number = 0.0;
        const bool numeric = parse_number(value, number);
        if (name == "--out") out_dir = value;
        else if (name == "--max-lobes" && numeric && number >= 0 && number == double(int(number))) fit.max_lobes = uint32_t(number);
        else if (name == "--tolerance" && numeric) fit.tolerance = float(number);
        else if (name == "--threads" && numeric && number >= 0) fit.threads = uint32_t(number);
        else if (name == "--levels" && numeric && number >= 0 && number == double(int(number))) fit.max_levels = uint32_t(number);
        else if (name == "--max-memory" && parse_bytes(value, fit.max_memory_bytes)) {}
        else if (name == "--brdf" && parse_brdf(value, fit)) {}
        else if (name == "--convention" && (value == "opengl" || value == "directx"))
            decode.convention = value == "opengl" ? NDFB_CONVENTION_OPENGL : NDFB_CONVENTION_DIRECTX;
        else if (name == "--wrap" && (value == "repeat" || value == "clamp"))
            fit.wrap = value == "repeat" ? NDFB_WRAP_REPEAT : NDFB_WRAP_CLAMP;
        else if (name == "--srgb" && (value == "data" || value == "linearize"))
            decode.srgb = value == "data" ? NDFB_SRGB_AS_DATA : NDFB_SRGB_LINEARIZE;
        else if (name == "--precision" && (value == "half" || value == "float"))
            write.precision = value == "half" ? NDFB_PRECISION_HALF : NDFB_PRECISION_FLOAT;
        else if (name == "--color") color = value;
        else if (name == "--method" && (value == "per-level" || value == "hierarchical"))
            fit.method = value == "per-level" ? NDFB_FIT_PER_LEVEL : NDFB_FIT_HIERARCHICAL;
        else if (name == "--iterations" && numeric && number >= 1 && number == double(int(number)))
            fit.max_iterations = uint32_t(number);
        else if (name == "--starts" && (value == "1" || value == "2")) fit.starts = uint32_t(number);
        else if (name == "--no-align") fit.align = 0;
        else if (name == "--refine") fit.refine = 1;
        else if (name == "--quiet") progress.quiet = true;
        else if (name == "--atlas") write.atlas = 1;
        else if (name == "--mipmap") write.mipmap = 1;
        else return fail(1, "bad option " + name + (value.empty() ? "" : " " + value) + " (see --help)");
    }
    if (out_dir.empty()) return fail(1, "bake needs --out DIR");
    if (!color.empty()) write.color_path = color.c_str();
    progress.terminal = stderr_is_terminal();

    std::signal(SIGINT, on_interrupt);
    std::signal(SIGTERM, on_interrupt);
    ndfb_bake_result result = nullptr;
    const ndfb_status status = ndfb_bake(ctx, args.positional[0].c_str(), out_dir.c_str(), &decode, &fit, &write,
                                         print_progress, &progress, &result);
    if (status != NDFB_OK) {
        // Wipe an unfinished progress line so the reason stands on a line of its own.
        if (!progress.quiet && progress.terminal && progress.last_percent >= 0 && progress.last_percent < 100)
            std::fputs("\r              \r", stderr);
        return fail_status(ctx, status);
    }
    std::printf("wrote %u files into %s: %u levels of %u lobe slots, ndfbake.glsl and report.json\n",
                ndfb_bake_result_file_count(result), out_dir.c_str(), ndfb_bake_result_level_count(result),
                ndfb_bake_result_lobe_slots(result));
    ndfb_bake_result_destroy(result);
    return 0;
}

int run_synth(ndfb_context ctx, const Args& args)
{
    if (args.positional.size() != 1) return fail(1, "synth needs exactly one PATTERN (see --help)");
    double width = 256, height = -1, seed = 1;
    std::string out;
    for (const auto& [name, value] : args.options) {
        double number = 0.0;
        const bool numeric = parse_number(value, number);
        if (name == "--out") out = value;
        else if (name == "--size" && numeric) width = number;
        else if (name == "--height" && numeric) height = number;
        else if (name == "--seed" && numeric && number >= 0) seed = number;
        else return fail(1, "bad option " + name + " " + value + " (see --help)");
    }
    if (out.empty()) return fail(1, "synth needs --out FILE");
    if (height < 0) height = width;
    if (!(width >= 1 && height >= 1 && width <= 16384 && height <= 16384))
        return fail(1, "--size and --height must be 1..16384");

    // Ctrl-C as in bake: exit 130 and no file left, an earlier --out kept as it was. Neither call
    // takes a progress callback, so an interrupt is noted by the handler and acted on between
    // them: the map is saved under a hidden name beside --out (atomically, by the library) and
    // renamed to --out only if no interrupt came meanwhile.
    std::signal(SIGINT, on_interrupt);
    std::signal(SIGTERM, on_interrupt);
    ndfb_normal_map map = nullptr;
    ndfb_status status = ndfb_synthesize(ctx, args.positional[0].c_str(), uint32_t(width), uint32_t(height),
                                         uint32_t(seed), &map);
    if (status != NDFB_OK) return fail_status(ctx, status);
    if (g_interrupted) {
        ndfb_normal_map_destroy(map);
        return fail_status(ctx, NDFB_ERROR_CANCELLED);
    }
    const std::filesystem::path target = path_from_utf8(out);
    const std::filesystem::path staged =
        target.parent_path() / path_from_utf8("." + path_to_utf8(target.stem()) + ".synth-" +
                                              std::to_string(process_id()) + path_to_utf8(target.extension()));
    const std::string staging = path_to_utf8(staged);
    status = ndfb_normal_map_save(ctx, map, staging.c_str());
    ndfb_normal_map_destroy(map);
    if (status != NDFB_OK) {
        // The library names the file it was asked to write: name the user's instead.
        std::string message = ndfb_last_error(ctx);
        for (size_t at; (at = message.find(staging)) != std::string::npos;) message.replace(at, staging.size(), out);
        return fail(exit_code_for(status), std::string(ndfb_status_name(status)) + ": " + message);
    }
    std::error_code ignored;
    if (g_interrupted) {
        std::filesystem::remove(staged, ignored);
        return fail_status(ctx, NDFB_ERROR_CANCELLED);
    }
    std::error_code renamed;  // replaces an earlier --out, on Windows too (std::rename does not there)
    std::filesystem::rename(staged, target, renamed);
    if (renamed) {
        std::filesystem::remove(staged, ignored);
        return fail(3, "i/o error: cannot write '" + out + "': " + renamed.message());
    }
    return 0;
}

int print_bench_line(void*, const char* line, float)
{
    std::fprintf(stderr, "%s\n", line);
    return g_interrupted ? 1 : 0;
}

int run_bench(ndfb_context ctx, const Args& args)
{
    ndfb_bench_options bench;
    ndfb_bench_options_init(&bench);
    std::string out_dir, methods, brdfs, levels;
    for (const auto& [name, value] : args.options) {
        double number = 0.0;
        const bool numeric = parse_number(value, number) && number >= 0 && number == double(int(number));
        if (name == "--out") out_dir = value;
        else if (name == "--size" && numeric) bench.synthetic_size = uint32_t(number);
        else if (name == "--texels" && numeric) bench.texels_per_level = uint32_t(number);
        else if (name == "--threads" && numeric) bench.threads = uint32_t(number);
        else if (name == "--methods") methods = value;
        else if (name == "--brdfs") brdfs = value;
        else if (name == "--levels") levels = value;
        else return fail(1, "bad option " + name + " " + value + " (see --help)");
    }
    if (out_dir.empty()) return fail(1, "bench needs --out DIR");
    std::vector<const char*> paths;
    for (const std::string& p : args.positional) paths.push_back(p.c_str());
    bench.map_paths = paths.data();
    bench.map_count = paths.size();
    if (!methods.empty()) bench.methods = methods.c_str();
    if (!brdfs.empty()) bench.brdfs = brdfs.c_str();
    if (!levels.empty()) bench.levels = levels.c_str();
    std::signal(SIGINT, on_interrupt);
    const ndfb_status status = ndfb_bench(ctx, &bench, out_dir.c_str(), print_bench_line, nullptr);
    if (status != NDFB_OK) return fail_status(ctx, status);
    std::printf("wrote %s/bench.csv, bench.md and heat maps\n", out_dir.c_str());
    return 0;
}

int run_info(ndfb_context ctx, const Args& args)
{
    if (args.positional.size() != 1 || !args.options.empty()) return fail(1, "info takes exactly one FILE");
    size_t length = 0;
    ndfb_status status = ndfb_describe_image(ctx, args.positional[0].c_str(), nullptr, 0, &length);
    if (status != NDFB_OK) return fail_status(ctx, status);
    std::string text(length + 1, '\0');
    status = ndfb_describe_image(ctx, args.positional[0].c_str(), text.data(), text.size(), nullptr);
    if (status != NDFB_OK) return fail_status(ctx, status);
    std::fputs(text.c_str(), stdout);
    return 0;
}

}  // namespace

int main(int argc, char** argv)
{
    if (argc < 2 || !std::strcmp(argv[1], "--help") || !std::strcmp(argv[1], "-h") || !std::strcmp(argv[1], "help")) {
        std::fputs(kUsage, argc < 2 ? stderr : stdout);
        return argc < 2 ? 1 : 0;
    }
    if (!std::strcmp(argv[1], "--version")) {
        std::printf("ndfbake %s\n", ndfb_version());
        return 0;
    }
    for (int i = 2; i < argc; ++i)  // `ndfbake bake --help`: the same usage, for every command
        if (!std::strcmp(argv[i], "--help") || !std::strcmp(argv[i], "-h")) {
            std::fputs(kUsage, stdout);
            return 0;
        }
    Args args;
    std::string error;
    if (!parse_args(argc, argv, 2, args, error)) return fail(1, error);

    ndfb_context ctx = nullptr;
    if (ndfb_context_create(&ctx) != NDFB_OK) return fail(4, ndfb_last_error(nullptr));
    int code;
    const std::string command = argv[1];
    if (command == "bake") code = run_bake(ctx, args);
    else if (command == "synth") code = run_synth(ctx, args);
    else if (command == "info") code = run_info(ctx, args);
    else if (command == "bench") code = run_bench(ctx, args);
    else code = fail(1, "unknown command '" + command + "' (see --help)");
    ndfb_context_destroy(ctx);
    return code;
}
