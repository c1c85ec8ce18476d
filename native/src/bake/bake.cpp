// The bake's pipeline and its entry points (bake/bake.h): the up-front checks (writable folder,
// memory, colour image), decode, fit, measure, then every file written into a staging folder and
// renamed into place. Calls bake/lobe_files for the image files, bake/report for report.json,
// bake/memory_budget, bake/level_stats, io/, export/lobe_shader and pyramid/.
#include "bake/bake.h"

#include <atomic>
#include <chrono>
#include <filesystem>
#include <set>
#include <string_view>

#include "bake/level_stats.h"
#include "bake/lobe_files.h"
#include "bake/memory_budget.h"
#include "bake/report.h"
#include "error.h"
#include "export/lobe_shader.h"
#include "io/atomic_file.h"
#include "io/color_decode.h"
#include "io/image_files.h"
#include "platform/files.h"
#include "pyramid/parallel.h"

namespace ndfbake {

namespace fs = std::filesystem;

namespace {

double seconds_since(std::chrono::steady_clock::time_point start)
{
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

void check_progress(const StageProgress& progress, const char* stage, double fraction)
{
    if (progress && !progress(stage, fraction)) throw Error(Status::cancelled, "cancelled");
}

fs::path make_staging_dir(const std::string& out_dir)
{
    static std::atomic<unsigned> counter{0};
    const fs::path staging = path_from_utf8(out_dir) / (".ndfbake-staging-" + std::to_string(current_process_id()) +
                                                        "-" + std::to_string(counter.fetch_add(1)));
    std::error_code ec;
    fs::create_directory(staging, ec);
    if (ec) throw Error(Status::io_error, "cannot create '" + path_to_utf8(staging) + "': " + ec.message());
    return staging;
}

// The UTF-8 path of one of the bake's files (ASCII names) in `folder`.
std::string file_in(const fs::path& folder, const std::string& name) { return path_to_utf8(folder / name); }

// The per-lobe colour needs a colour image of the normal map's size (the two arguments disagree).
void require_color_size(const std::string& color_path, int width, int height, int map_width, int map_height)
{
    if (width != map_width || height != map_height)
        throw Error(Status::invalid_argument, "colour image '" + color_path + "' is " + std::to_string(width) + "x" +
                                                  std::to_string(height) + ", the normal map is " +
                                                  std::to_string(map_width) + "x" + std::to_string(map_height));
}

}  // namespace

namespace {

// Consumes `prefix` at `pos` of `name` if it is there.
bool consume(std::string_view name, size_t& pos, std::string_view prefix)
{
    if (name.substr(pos, prefix.size()) != prefix) return false;
    pos += prefix.size();
    return true;
}

// Consumes one or more ASCII digits at `pos`.
bool consume_digits(std::string_view name, size_t& pos)
{
    const size_t start = pos;
    while (pos < name.size() && name[pos] >= '0' && name[pos] <= '9') ++pos;
    return pos > start;
}

}  // namespace

// The names lobe_file_name, color_file_name, atlas_file_name and mip_file_name write:
// level<digits>_lobe<digits>.exr, level<digits>_color<digits>.exr, atlas_lobe<digits>.exr and
// mip_lobe<digits>.exr, besides the shader and the report. Matched by hand, not with std::regex:
// in Blender on Windows (under wine) the add-on library's std::regex matched these names only now
// and then, and a reverted bake's folder stayed behind.
bool is_bake_file(std::string_view name)
{
    if (name == kLobeShaderFileName || name == kReportFileName) return true;
    size_t pos = 0;
    if (consume(name, pos, "level")) {
        if (!consume_digits(name, pos) || !(consume(name, pos, "_lobe") || consume(name, pos, "_color"))) return false;
    } else if (!consume(name, pos, "atlas_lobe") && !consume(name, pos, "mip_lobe")) {
        return false;
    }
    return consume_digits(name, pos) && name.substr(pos) == ".exr";
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
        std::vector<BakeFile> files;
        for (int level = 0; level < pyramid.level_count(); ++level)
            for (int lobe = 0; lobe < pyramid.slots; ++lobe)
                files.push_back({BakeFileKind::lobe, level, lobe, lobe_file_name(level, lobe)});
        const int lobe_jobs = int(files.size());
        if (write.atlas)
            for (int lobe = 0; lobe < pyramid.slots; ++lobe)
                files.push_back({BakeFileKind::atlas, -1, lobe, atlas_file_name(lobe)});
        const int atlas_jobs = int(files.size()) - lobe_jobs;
        if (write.mipmap)
            for (int lobe = 0; lobe < pyramid.slots; ++lobe) files.push_back({BakeFileKind::mip, -1, lobe, mip_file_name(lobe)});
        const AtlasLayout layout = pyramid_atlas_layout(pyramid);
        parallel_rows(int(files.size()), settings.threads, [&](int job) {
            const std::string path = file_in(staging, files[size_t(job)].name);
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
                    files.push_back({BakeFileKind::color, level, lobe, color_file_name(level, lobe)});
                    write_rgba_exr(file_in(staging, files.back().name), size.width, size.height,
                                   textures[size_t(lobe)].data(), write.precision,
                                   file_attributes(pyramid, decoded, settings, write, level, lobe,
                                                   stats[size_t(level)].fit.mean,
                                                   "lobe colour: RGB = alpha * linear colour, A = alpha"));
                }
            }
        }
        files.push_back({BakeFileKind::shader, -1, -1, kLobeShaderFileName});
        write_text_atomic(file_in(staging, files.back().name), lobe_shader_glsl(pyramid.slots, write.precision));
        std::vector<std::string> names;
        for (const BakeFile& file : files) names.push_back(file.name);
        timings.write = seconds_since(start);
        write_text_atomic(file_in(staging, kReportFileName),
                          report_json(pyramid, decoded, settings, write, stats, timings, names));
        check_progress(progress, "write", 1.0);

        // Commit: only renames within one folder, all or nothing (commit_files): an earlier bake's
        // files that this one does not write go, and if any file cannot be moved (on Windows: one
        // open in another program) the folder keeps the earlier bake whole.
        files.push_back({BakeFileKind::report, -1, -1, kReportFileName});
        names.push_back(kReportFileName);
        const std::set<std::string> fresh(names.begin(), names.end());
        std::vector<std::string> retired;
        for (const auto& entry : fs::directory_iterator(path_from_utf8(out_dir))) {
            const std::string name = path_to_utf8(entry.path().filename());
            if (is_bake_file(name) && !fresh.count(name)) retired.push_back(name);
        }
        commit_files(path_to_utf8(staging), out_dir, names, retired);
        for (int level = 0; level < pyramid.level_count(); ++level) outcome.levels.push_back(pyramid.size(level));
        outcome.slots = pyramid.slots;
        outcome.slots_used = pyramid.slots_used();
        if (write.atlas) outcome.atlas = layout;
        outcome.files = std::move(files);
        std::error_code ignored;
        fs::remove_all(staging, ignored);  // empty now; one left behind is not a failed bake
    } catch (const fs::filesystem_error& e) {
        std::error_code ignored;
        fs::remove_all(staging, ignored);
        std::string reason = e.code().message();
        if (!e.path1().empty()) reason += " ('" + path_to_utf8(e.path1()) + "')";
        throw Error(Status::io_error, "cannot write into '" + out_dir + "': " + reason);
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
    if (named.source_name.empty()) named.source_name = path_to_utf8(path_from_utf8(input_path).filename());
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
