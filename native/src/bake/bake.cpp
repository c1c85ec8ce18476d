#include "bake/bake.h"

#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <regex>
#include <set>

#include "bake/level_stats.h"
#include "bake/lobe_atlas.h"
#include "bake/memory_budget.h"
#include "error.h"
#include "export/lobe_shader.h"
#include "io/atomic_file.h"
#include "io/color_decode.h"
#include "io/image_files.h"
#include "io/json_writer.h"
#include "ndf/spherical_em.h"
#include "pyramid/parallel.h"

namespace ndfbake {

namespace fs = std::filesystem;

namespace {

constexpr int kFileFormatVersion = 1;

double seconds_since(std::chrono::steady_clock::time_point start)
{
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

void check_progress(const StageProgress& progress, const char* stage, double fraction)
{
    if (progress && !progress(stage, fraction)) throw Error(Status::cancelled, "cancelled");
}

// Lobe texture texel: R = α, GBA = α·r with |r| the resultant whose Banerjee κ is the lobe's.
void encode_lobe(const VmfLobe& lobe, float* rgba)
{
    if (!(lobe.alpha > 0.0f)) {
        rgba[0] = rgba[1] = rgba[2] = rgba[3] = 0.0f;
        return;
    }
    const float r = float(lobe_resultant(lobe.kappa));  // 1 at the κ cap: a single direction
    rgba[0] = lobe.alpha;
    rgba[1] = lobe.alpha * r * lobe.mu.x;
    rgba[2] = lobe.alpha * r * lobe.mu.y;
    rgba[3] = lobe.alpha * r * lobe.mu.z;
}

// Per-lobe colour (eq. 22): y_j = Σ ⟨z_ij⟩ w_i y_i / Σ ⟨z_ij⟩ w_i over the texel's fine texels;
// stored as RGB = α_j y_j, A = α_j so that it filters linearly like the lobe textures.
std::vector<std::vector<float>> color_textures(const LobePyramid& pyramid, const ColorImage& color, int level)
{
    const LevelSize size = pyramid.size(level);
    const int slots = pyramid.slots;
    std::vector<std::vector<float>> textures(size_t(slots),
                                             std::vector<float>(size_t(size.width) * size_t(size.height) * 4, 0.0f));
    // Colours travel with the normals: gather the footprint of a colour "map" alongside.
    NormalMap rgb;
    rgb.width = color.width;
    rgb.height = color.height;
    const size_t n = size_t(color.width) * size_t(color.height);
    rgb.normals.resize(n);
    for (size_t p = 0; p < n; ++p) rgb.normals[p] = {color.rgb[p * 3], color.rgb[p * 3 + 1], color.rgb[p * 3 + 2]};

    std::vector<WeightedNormal> samples, colors;
    std::vector<float> z;
    std::vector<VmfLobe> lobes(static_cast<size_t>(slots));
    for (int y = 0; y < size.height; ++y)
        for (int x = 0; x < size.width; ++x) {
            gather_footprint(pyramid.source, level, x, y, pyramid.settings.wrap, samples);
            gather_footprint(rgb, level, x, y, pyramid.settings.wrap, colors);
            pyramid.texel(level, x, y, lobes);
            vmf_responsibilities(samples, lobes, z);
            for (int j = 0; j < slots; ++j) {
                if (!(lobes[size_t(j)].alpha > 0.0f)) continue;
                Vec3d sum;
                double weight = 0.0;
                for (size_t i = 0; i < samples.size(); ++i) {
                    const double w = double(samples[i].weight) * z[i * size_t(slots) + size_t(j)];
                    sum.add(colors[i].n, w);
                    weight += w;
                }
                float* out = &textures[size_t(j)][(size_t(y) * size_t(size.width) + size_t(x)) * 4];
                const float alpha = lobes[size_t(j)].alpha;
                const Vec3 mean = weight > 0.0 ? sum.to_float() / float(weight) : Vec3{};
                out[0] = alpha * mean.x;
                out[1] = alpha * mean.y;
                out[2] = alpha * mean.z;
                out[3] = alpha;
            }
        }
    return textures;
}

AtlasLayout pyramid_atlas_layout(const LobePyramid& pyramid)
{
    std::vector<LevelSize> sizes;
    for (int level = 0; level < pyramid.level_count(); ++level) sizes.push_back(pyramid.size(level));
    return atlas_layout(sizes);
}

std::string hex64(uint64_t value)
{
    char buffer[17];
    std::snprintf(buffer, sizeof buffer, "%016llx", static_cast<unsigned long long>(value));
    return buffer;
}

std::vector<ExrAttribute> file_attributes(const LobePyramid& pyramid, const DecodeResult& decoded,
                                          const PyramidSettings& settings, const WriteSettings& write,
                                          int level, int lobe, float level_error, const char* content)
{
    return {
        {"ndfbake:format_version", kFileFormatVersion},
        {"ndfbake:content", std::string(content)},
        {"ndfbake:level", level},
        {"ndfbake:lobe", lobe},
        {"ndfbake:lobe_slots", pyramid.slots},
        {"ndfbake:level_count", pyramid.level_count()},
        {"ndfbake:source", write.source_name},
        {"ndfbake:source_hash", hex64(decoded.source_hash)},
        {"ndfbake:source_width", pyramid.source.width},
        {"ndfbake:source_height", pyramid.source.height},
        {"ndfbake:convention", std::string("opengl tangent space, +Z out, +Y up V")},
        {"ndfbake:wrap", std::string(settings.wrap == WrapMode::wrap ? "repeat" : "clamp")},
        {"ndfbake:brdf", settings.brdf.to_string()},
        {"ndfbake:tolerance", settings.fit.tolerance},
        {"ndfbake:aligned", settings.align ? 1 : 0},
        {"ndfbake:refined_for_brdf", settings.refine ? 1 : 0},
        {"ndfbake:kappa_max", kKappaMax},
        {"ndfbake:fit_error", level_error},
        {"ndfbake:version", std::string(NDFBAKE_VERSION_STRING)},
    };
}

// Every level of lobe slot `lobe` in one image (write option `atlas`, see ndfbake.h).
void write_atlas(const LobePyramid& pyramid, const DecodeResult& decoded, const PyramidSettings& settings,
                 const WriteSettings& write, const AtlasLayout& layout, int lobe, const std::string& path)
{
    std::string places;
    for (const AtlasLevel& l : layout.levels) {
        if (!places.empty()) places += ';';
        for (int v : {l.x, l.y, l.width, l.height}) places.append(std::to_string(v)).push_back(',');
        places.pop_back();
    }
    std::vector<float> atlas(size_t(layout.width) * size_t(layout.height) * 4, 0.0f);
    for (int level = 0; level < pyramid.level_count(); ++level)
        place_atlas_level(layout, level, lobe_texture(pyramid, level, lobe).data(), pyramid.settings.wrap, atlas);
    std::vector<ExrAttribute> attributes = file_attributes(pyramid, decoded, settings, write, -1, lobe, -1.0f,
                                                           "mip atlas of a vmf lobe slot: R = alpha, GBA = alpha * r");
    attributes.push_back({"ndfbake:atlas_levels", places});
    write_rgba_exr(path, layout.width, layout.height, atlas.data(), write.precision, attributes);
}

// Level `level` + 1 of a slot's texture from level `level` (w × h, RGBA): each texel the mean of
// the texels below it (two by two, fewer at an odd edge) weighted by their footprints, which
// averages their distributions as the linear encoding does under hardware filtering. For the
// levels of a MIP file beyond the fitted ones (--levels N): an estimate, not a fit.
std::vector<float> averaged_coarser_level(const std::vector<float>& rgba, const NormalMap& source, int level,
                                          WrapMode wrap)
{
    const LevelSize fine = level_size(source.width, source.height, level);
    const LevelSize coarse = level_size(source.width, source.height, level + 1);
    std::vector<float> out(size_t(coarse.width) * size_t(coarse.height) * 4, 0.0f);
    for (int y = 0; y < coarse.height; ++y)
        for (int x = 0; x < coarse.width; ++x) {
            double sum[4] = {0, 0, 0, 0}, weight = 0;
            for (int cy = 2 * y; cy < std::min(2 * y + 2, fine.height); ++cy)
                for (int cx = 2 * x; cx < std::min(2 * x + 2, fine.width); ++cx) {
                    const double w = footprint_weight(source.width, source.height, level, cx, cy, wrap);
                    const float* texel = &rgba[(size_t(cy) * size_t(fine.width) + size_t(cx)) * 4];
                    for (int c = 0; c < 4; ++c) sum[c] += w * double(texel[c]);
                    weight += w;
                }
            for (int c = 0; c < 4; ++c)
                out[(size_t(y) * size_t(coarse.width) + size_t(x)) * 4 + size_t(c)] =
                    weight > 0 ? float(sum[c] / weight) : 0.0f;
        }
    return out;
}

// Lobe slot `lobe` as one MIP-mapped file (write option `mipmap`, see ndfbake.h): its levels are
// the fitted levels, then (if fewer were fitted than the chain has) averaged ones down to 1×1.
void write_mip_file(const LobePyramid& pyramid, const DecodeResult& decoded, const PyramidSettings& settings,
                    const WriteSettings& write, const std::vector<LevelStats>& stats, int lobe,
                    const std::string& path)
{
    const int chain = mip_level_count(pyramid.source.width, pyramid.source.height);
    std::vector<std::vector<float>> textures;
    for (int level = 0; level < chain; ++level)
        textures.push_back(level < pyramid.level_count()
                               ? lobe_texture(pyramid, level, lobe)
                               : averaged_coarser_level(textures.back(), pyramid.source, level - 1, settings.wrap));
    std::vector<RgbaLevel> levels;
    std::string errors;
    for (int level = 0; level < chain; ++level) {
        const LevelSize size = level_size(pyramid.source.width, pyramid.source.height, level);
        levels.push_back({size.width, size.height, textures[size_t(level)].data()});
        if (level < pyramid.level_count())
            errors += (errors.empty() ? "" : ";") + std::to_string(stats[size_t(level)].fit.mean);
    }
    std::vector<ExrAttribute> attributes = file_attributes(
        pyramid, decoded, settings, write, -1, lobe, -1.0f,
        "mip-mapped vmf lobe slot: R = alpha, GBA = alpha * r; MIP level L is fitted level L (the first "
        "ndfbake:fitted_levels; the rest averaged)");
    attributes.push_back({"ndfbake:mip_levels", chain});
    attributes.push_back({"ndfbake:fitted_levels", pyramid.level_count()});
    attributes.push_back({"ndfbake:mip_rounding", std::string("up: level L is ceil(w / 2^L) x ceil(h / 2^L)")});
    attributes.push_back({"ndfbake:level_errors", errors});
    write_mip_rgba_exr(path, levels, write.precision, attributes);
}

void write_summary(JsonWriter& json, const char* key, const ErrorSummary& summary)
{
    json.begin_object(key).value("mean", summary.mean).value("p95", summary.p95).end_object();
}

// The layout of the file a map was decoded from (none for pixels from memory or synthesized).
SourceLayout source_layout(const DecodeResult& decoded)
{
    if (decoded.format == "memory" || decoded.format == "synthetic" || decoded.bits_per_channel <= 0) return {};
    return {decoded.channels, std::max(1, decoded.bits_per_channel / 8), decoded.float_data};
}

std::string report_json(const LobePyramid& pyramid, const DecodeResult& decoded, const PyramidSettings& settings,
                        const WriteSettings& write, const std::vector<LevelStats>& stats,
                        const BakeTimings& timings, const std::vector<std::string>& files)
{
    const MemoryEstimate memory = estimate_bake_memory(pyramid.source.width, pyramid.source.height,
                                                       source_layout(decoded), settings, write);
    JsonWriter json;
    json.begin_object();
    json.value("format_version", kFileFormatVersion).value("ndfbake_version", NDFBAKE_VERSION_STRING);
    json.begin_object("input")
        .value("source", write.source_name)
        .value("width", pyramid.source.width)
        .value("height", pyramid.source.height)
        .value("format", decoded.format)
        .value("bits_per_channel", decoded.bits_per_channel)
        .value("channels", decoded.channels)
        .value("srgb_tagged", decoded.srgb_tagged)
        .value("signed_encoding", decoded.signed_encoding)
        .value("source_hash", hex64(decoded.source_hash));
    json.begin_array("assumptions");
    for (const std::string& a : decoded.assumptions) json.value(nullptr, a);
    json.end_array().end_object();

    json.begin_object("settings")
        .value("method", settings.method == FitMethod::hierarchical ? "hierarchical" : "per-level")
        .value("max_lobes", settings.fit.max_lobes)
        .value("max_iterations", settings.fit.em.max_iterations)
        .value("tolerance", settings.fit.tolerance)
        .value("brdf", settings.brdf.to_string())
        .value("refined_for_brdf", settings.refine)
        .value("wrap", settings.wrap == WrapMode::wrap ? "repeat" : "clamp")
        .value("aligned", settings.align)
        .value("alignment_strength", settings.alignment_strength)
        .value("precision", write.precision == PixelPrecision::half ? "half" : "float")
        .value("per_lobe_color", !write.color_path.empty())
        .end_object();

    json.begin_object("repairs")
        .value("non_finite", decoded.repairs.non_finite)
        .value("zero_length", decoded.repairs.zero_length)
        .value("renormalized", decoded.repairs.renormalized)
        .value("below_horizon", decoded.repairs.below_horizon)
        .value("rule", "non-finite or shorter than 0.01: +Z; z < 0: z = -z; then normalized")
        .end_object();

    json.begin_object("error_measure")
        .value("what", "relative L2 distance to the exact effective BRDF (Han 2007 eq. 4) over a fixed "
                       "Fibonacci set of hemisphere directions")
        .value("directions", error_direction_count(settings.brdf))
        .value("texels_per_level", kReportTexelsPerLevel)
        .value("fine_normals_per_texel", kReportSampleCap)
        .value("without_alignment", "error_without_alignment is an independent refit of the same texels, "
                                    "alignment_cost the error minus its mean; measured above level 0 when lobes "
                                    "are pulled into alignment (aligned, alignment_strength > 0), null otherwise")
        .end_object();

    // Slots with no lobe at any level (possible with a tolerance): their textures are all zero.
    json.begin_array("slots_used");
    for (bool used : pyramid.slots_used()) json.value(nullptr, used);
    json.end_array();

    json.begin_array("levels");
    for (const LevelStats& s : stats) {
        json.begin_object()
            .value("level", s.level)
            .value("width", s.size.width)
            .value("height", s.size.height);
        json.begin_array("lobe_histogram");
        for (int k = 0; k <= pyramid.slots; ++k) json.value(nullptr, s.lobe_histogram[size_t(k)]);
        json.end_array();
        json.value("measured_texels", s.measured_texels);
        write_summary(json, "error", s.fit);
        // Not measured (see "error_measure"): null, never a made-up 0 beside the real error.
        if (s.independent_fit) {
            write_summary(json, "error_without_alignment", *s.independent_fit);
            json.value("alignment_cost", double(s.fit.mean) - double(s.independent_fit->mean));
        } else {
            json.null("error_without_alignment").null("alignment_cost");
        }
        write_summary(json, "error_naive", s.naive);
        write_summary(json, "error_single_vmf", s.single_vmf);
        write_summary(json, "error_toksvig", s.toksvig);
        json.end_object();
    }
    json.end_array();

    json.begin_object("timings_seconds")
        .value("decode", timings.decode)
        .value("fit", timings.fit)
        .value("measure", timings.measure)
        .value("write", timings.write)
        .end_object();
    // Measured: the process's peak resident memory so far (getrusage), which includes the host
    // application's own; estimated: this bake's peak as checked against the limit before it ran.
    json.value("peak_memory_bytes", process_peak_memory())
        .value("estimated_memory_bytes", memory.peak())
        .value("memory_limit_bytes", effective_memory_limit(settings.max_memory_bytes));
    if (write.atlas) {
        const AtlasLayout layout = pyramid_atlas_layout(pyramid);
        json.begin_object("atlas").value("width", layout.width).value("height", layout.height).begin_array("levels");
        for (const AtlasLevel& l : layout.levels)
            json.begin_object().value("x", l.x).value("y", l.y).value("width", l.width).value("height", l.height).end_object();
        json.end_array().end_object();
    }
    if (write.mipmap)
        json.begin_object("mipmap")
            .value("levels", mip_level_count(pyramid.source.width, pyramid.source.height))
            .value("fitted_levels", pyramid.level_count())
            .value("rounding", "up: level L is ceil(w / 2^L) x ceil(h / 2^L), as the fitted levels")
            .value("tile", kMipTileSize)
            .end_object();
    json.begin_array("files");
    for (const std::string& f : files) json.value(nullptr, fs::path(f).filename().string());
    json.value(nullptr, "report.json");
    json.end_array();
    json.end_object();
    return json.str();
}

bool is_bake_file(const std::string& name)
{
    static const std::regex pattern(R"(level\d+_(lobe|color)\d+\.exr|(atlas|mip)_lobe\d+\.exr)");
    return name == kLobeShaderFileName || std::regex_match(name, pattern);
}

fs::path make_staging_dir(const fs::path& out_dir)
{
    static std::atomic<unsigned> counter{0};
    const fs::path staging = out_dir / (".ndfbake-staging-" + std::to_string(::getpid()) + "-" +
                                        std::to_string(counter.fetch_add(1)));
    std::error_code ec;
    fs::create_directory(staging, ec);
    if (ec) throw Error(Status::io_error, "cannot create '" + staging.string() + "': " + ec.message());
    return staging;
}

// The per-lobe colour needs a colour image of the normal map's size (the two arguments disagree).
void require_color_size(const std::string& color_path, int width, int height, int map_width, int map_height)
{
    if (width != map_width || height != map_height)
        throw Error(Status::invalid_argument, "colour image '" + color_path + "' is " + std::to_string(width) + "x" +
                                                  std::to_string(height) + ", the normal map is " +
                                                  std::to_string(map_width) + "x" + std::to_string(map_height));
}

}  // namespace

std::vector<float> lobe_texture(const LobePyramid& pyramid, int level, int slot)
{
    const LevelSize size = pyramid.size(level);
    std::vector<float> rgba(size_t(size.width) * size_t(size.height) * 4);
    std::vector<VmfLobe> lobes(static_cast<size_t>(pyramid.slots));
    for (int y = 0; y < size.height; ++y)
        for (int x = 0; x < size.width; ++x) {
            pyramid.texel(level, x, y, lobes);
            encode_lobe(lobes[size_t(slot)], &rgba[(size_t(y) * size_t(size.width) + size_t(x)) * 4]);
        }
    return rgba;
}

std::string lobe_file_name(int level, int lobe)
{
    char buffer[48];
    std::snprintf(buffer, sizeof buffer, "level%02d_lobe%d.exr", level, lobe);
    return buffer;
}

std::string atlas_file_name(int lobe)
{
    char buffer[48];
    std::snprintf(buffer, sizeof buffer, "atlas_lobe%d.exr", lobe);
    return buffer;
}

std::string mip_file_name(int lobe)
{
    char buffer[48];
    std::snprintf(buffer, sizeof buffer, "mip_lobe%d.exr", lobe);
    return buffer;
}

std::string color_file_name(int level, int lobe)
{
    char buffer[48];
    std::snprintf(buffer, sizeof buffer, "level%02d_color%d.exr", level, lobe);
    return buffer;
}

BakeOutcome write_pyramid_into(const LobePyramid& pyramid, const DecodeResult& decoded, const std::string& out_dir,
                               const PyramidSettings& settings, const WriteSettings& write, BakeTimings timings,
                               const StageProgress& progress)
{
    ensure_writable_directory(out_dir);

    ColorImage color;
    if (!write.color_path.empty()) {
        color = decode_color_image(write.color_path);
        require_color_size(write.color_path, color.width, color.height, pyramid.source.width, pyramid.source.height);
    }

    auto start = std::chrono::steady_clock::now();
    // Levels are measured on every core, each from its own sample of texels.
    std::vector<LevelStats> stats(size_t(pyramid.level_count()));
    parallel_rows(pyramid.level_count(), settings.threads, [&](int level) {
        stats[size_t(level)] = measure_level(pyramid, level, settings.brdf, kReportTexelsPerLevel,
                                             kReportSampleCap, settings.align && settings.alignment_strength > 0.0f);
    }, [&](double fraction) { return !progress || progress("measure", fraction); });
    timings.measure = seconds_since(start);

    start = std::chrono::steady_clock::now();
    const fs::path staging = make_staging_dir(out_dir);
    BakeOutcome outcome;
    try {
        // One job per file, on every core: compressing the level-0 textures is most of the cost.
        // Jobs [0, lobe_jobs) are the (level, slot) textures, level 0 first so that the largest
        // files start together; then one atlas per slot, then one MIP file per slot.
        std::vector<std::string> names;
        for (int level = 0; level < pyramid.level_count(); ++level)
            for (int lobe = 0; lobe < pyramid.slots; ++lobe) names.push_back(lobe_file_name(level, lobe));
        const int lobe_jobs = int(names.size());
        if (write.atlas)
            for (int lobe = 0; lobe < pyramid.slots; ++lobe) names.push_back(atlas_file_name(lobe));
        const int atlas_jobs = int(names.size()) - lobe_jobs;
        if (write.mipmap)
            for (int lobe = 0; lobe < pyramid.slots; ++lobe) names.push_back(mip_file_name(lobe));
        const AtlasLayout layout = pyramid_atlas_layout(pyramid);
        parallel_rows(int(names.size()), settings.threads, [&](int job) {
            const std::string path = (staging / names[size_t(job)]).string();
            if (job >= lobe_jobs + atlas_jobs) {
                write_mip_file(pyramid, decoded, settings, write, stats, job - lobe_jobs - atlas_jobs, path);
                return;
            }
            if (job >= lobe_jobs) {
                write_atlas(pyramid, decoded, settings, write, layout, job - lobe_jobs, path);
                return;
            }
            const int level = job / pyramid.slots, lobe = job % pyramid.slots;
            const LevelSize size = pyramid.size(level);
            const std::vector<float> rgba = lobe_texture(pyramid, level, lobe);
            write_rgba_exr(path, size.width, size.height, rgba.data(), write.precision,
                           file_attributes(pyramid, decoded, settings, write, level, lobe, stats[size_t(level)].fit.mean,
                                           "vmf lobe: R = alpha, GBA = alpha * r"),
                           level == 0 ? ExrCompression::run_length : ExrCompression::zlib);
        }, [&](double fraction) { return !progress || progress("write", fraction); });
        if (!write.color_path.empty()) {
            for (int level = 0; level < pyramid.level_count(); ++level) {
                const LevelSize size = pyramid.size(level);
                const auto textures = color_textures(pyramid, color, level);
                for (int lobe = 0; lobe < pyramid.slots; ++lobe) {
                    names.push_back(color_file_name(level, lobe));
                    write_rgba_exr((staging / names.back()).string(), size.width, size.height,
                                   textures[size_t(lobe)].data(), write.precision,
                                   file_attributes(pyramid, decoded, settings, write, level, lobe,
                                                   stats[size_t(level)].fit.mean,
                                                   "lobe colour: RGB = alpha * linear colour, A = alpha"));
                }
            }
        }
        names.push_back(kLobeShaderFileName);
        write_text_atomic((staging / names.back()).string(), lobe_shader_glsl(pyramid.slots, write.precision));
        timings.write = seconds_since(start);
        write_text_atomic((staging / "report.json").string(),
                          report_json(pyramid, decoded, settings, write, stats, timings, names));
        check_progress(progress, "write", 1.0);

        // Commit: from here on only renames within one folder.
        const std::set<std::string> fresh(names.begin(), names.end());
        for (const auto& entry : fs::directory_iterator(out_dir)) {
            const std::string name = entry.path().filename().string();
            if (is_bake_file(name) && !fresh.count(name)) fs::remove(entry.path());
        }
        names.push_back("report.json");
        for (const std::string& name : names) {
            fs::rename(staging / name, fs::path(out_dir) / name);
            outcome.files.push_back((fs::path(out_dir) / name).string());
        }
        fs::remove(staging);
    } catch (const fs::filesystem_error& e) {
        std::error_code ignored;
        fs::remove_all(staging, ignored);
        throw Error(Status::io_error, std::string("cannot write into '") + out_dir + "': " + e.what());
    } catch (...) {
        std::error_code ignored;
        fs::remove_all(staging, ignored);
        throw;
    }
    outcome.timings = timings;
    return outcome;
}

namespace {

// The per-lobe colour's image, checked from its header before any fitting: present, readable,
// of the map's size.
void check_color_image(const WriteSettings& write, int map_width, int map_height)
{
    if (write.color_path.empty()) return;
    const ImageLayout color = read_image_layout(write.color_path);
    require_color_size(write.color_path, color.width, color.height, map_width, map_height);
}

// What every bake does once it has the map: fit its pyramid, then measure and write it.
BakeOutcome fit_and_write(const DecodeResult& decoded, const std::string& out_dir, const PyramidSettings& settings,
                          const WriteSettings& write, BakeTimings timings, const StageProgress& progress)
{
    const auto start = std::chrono::steady_clock::now();
    const LobePyramid pyramid = build_lobe_pyramid(decoded.map, settings, [&](double fraction) {
        return !progress || progress("fit", fraction);
    });
    timings.fit = seconds_since(start);
    return write_pyramid_into(pyramid, decoded, out_dir, settings, write, timings, progress);
}

BakeOutcome bake_file_into(const std::string& input_path, const std::string& out_dir, const DecodeOptions& decode,
                           const PyramidSettings& settings, const WriteSettings& write, const StageProgress& progress)
{
    // Fail on an unwritable output before spending minutes on the fit.
    ensure_writable_directory(out_dir);
    // And on a map too large for the memory allowed, from its header alone. A header the decoder
    // refuses anyway (no pixels, wrong channel count, over max_pixels) gets the decoder's error.
    const ImageLayout header = read_image_layout(input_path);
    if (header.width > 0 && header.height > 0 && header.channels >= 2 && header.channels <= 4 &&
        uint64_t(header.width) * uint64_t(header.height) <= decode.max_pixels) {
        const SourceLayout layout{header.channels, header.bytes_per_sample, header.float_samples};
        check_memory_budget(estimate_bake_memory(header.width, header.height, layout, settings, write),
                            settings.max_memory_bytes, header.width, header.height, settings.fit.max_lobes,
                            "cannot bake '" + input_path + "'");
    }
    // And on a colour image that is missing, unreadable or of another size.
    check_color_image(write, header.width, header.height);

    BakeTimings timings;
    const auto start = std::chrono::steady_clock::now();
    check_progress(progress, "decode", 0.0);
    const DecodeResult decoded = decode_normal_map(input_path, decode);
    timings.decode = seconds_since(start);

    WriteSettings named = write;
    if (named.source_name.empty()) named.source_name = fs::path(input_path).filename().string();
    return fit_and_write(decoded, out_dir, settings, named, timings, progress);
}

BakeOutcome bake_map_into(const DecodeResult& decoded, const std::string& out_dir, const PyramidSettings& settings,
                          const WriteSettings& write, const StageProgress& progress)
{
    // The checks of bake_file_into, on the map in memory.
    ensure_writable_directory(out_dir);
    const NormalMap& map = decoded.map;
    check_memory_budget(estimate_bake_memory(map.width, map.height, SourceLayout{}, settings, write),
                        settings.max_memory_bytes, map.width, map.height, settings.fit.max_lobes,
                        "cannot bake '" + write.source_name + "'");
    check_color_image(write, map.width, map.height);
    return fit_and_write(decoded, out_dir, settings, write, BakeTimings{}, progress);
}

}  // namespace

BakeOutcome write_pyramid(const LobePyramid& pyramid, const DecodeResult& decoded, const std::string& out_dir,
                          const PyramidSettings& settings, const WriteSettings& write, BakeTimings timings,
                          const StageProgress& progress)
{
    return removing_new_folders_on_failure(out_dir, [&] {
        return write_pyramid_into(pyramid, decoded, out_dir, settings, write, timings, progress);
    });
}

BakeOutcome bake_map(const DecodeResult& decoded, const std::string& out_dir, const PyramidSettings& settings,
                     const WriteSettings& write, const StageProgress& progress)
{
    return removing_new_folders_on_failure(out_dir, [&] {
        return bake_map_into(decoded, out_dir, settings, write, progress);
    });
}

BakeOutcome bake_file(const std::string& input_path, const std::string& out_dir, const DecodeOptions& decode,
                      const PyramidSettings& settings, const WriteSettings& write, const StageProgress& progress)
{
    return removing_new_folders_on_failure(out_dir, [&] {
        return bake_file_into(input_path, out_dir, decode, settings, write, progress);
    });
}

}  // namespace ndfbake
