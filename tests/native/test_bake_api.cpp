// The C API and the command line end to end: files and attributes written, specific errors for
// bad input with nothing left behind, cancellation, and DirectX input equal to its OpenGL twin.
#include <gtest/gtest.h>

#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cstring>
#include <cstdio>
#include <fstream>
#include <set>
#include <thread>

#include <OpenImageIO/imageio.h>

#include "io/image_files.h"
#include "io/lobe_exr.h"
#include "io/normal_encode.h"
#include "ndfbake.h"
#include "synth/patterns.h"
#include "test_support.h"

namespace ndfbake {
namespace {

class BakeApi : public testing_support::CApiTest {};

TEST_F(BakeApi, WritesSelfDescribingLobeTexturesAndAReport)
{
    const std::string input = synth_file(Pattern::bumps, 32, 16, "bumps.png");
    const std::string out = path("out");
    ASSERT_EQ(ndfb_bake(ctx_, input.c_str(), out.c_str(), &decode_, &fit_, &write_, nullptr, nullptr, nullptr), NDFB_OK) << ndfb_last_error(ctx_);
    for (int level = 0; level < 6; ++level)
        for (int lobe = 0; lobe < 4; ++lobe) {
            char file[32];
            std::snprintf(file, sizeof file, "/level%02d_lobe%d.exr", level, lobe);
            const std::string name = out + file;
            const ImageInfo info = read_image_info(name);
            EXPECT_EQ(info.width, std::max(1, 32 >> level));
            EXPECT_EQ(info.channels, 4);
            EXPECT_EQ(info.pixel_type, "half");
            bool found_level = false, found_lobe = false;
            for (const auto& [key, value] : info.attributes) {
                if (key == "ndfbake:level") { found_level = true; EXPECT_EQ(value, std::to_string(level)); }
                if (key == "ndfbake:lobe") { found_lobe = true; EXPECT_EQ(value, std::to_string(lobe)); }
            }
            EXPECT_TRUE(found_level && found_lobe) << name;
            int w = 0, h = 0;
            for (float v : read_rgba_exr(name, w, h)) ASSERT_TRUE(std::isfinite(v));
        }
    std::ifstream report(out + "/report.json");
    const std::string text((std::istreambuf_iterator<char>(report)), std::istreambuf_iterator<char>());
    for (const char* key : {"\"levels\"", "\"lobe_histogram\"", "\"error_toksvig\"", "\"error_naive\"", "\"timings_seconds\"", "\"repairs\""})
        EXPECT_NE(text.find(key), std::string::npos) << key;
    // Only our files: no staging folder or temporary left.
    for (const std::string& entry : listing(out)) EXPECT_EQ(entry.find(".ndfbake"), std::string::npos) << entry;
}

TEST_F(BakeApi, TheResultNamesEveryFileTheBakeWroteAndNothingElse)
{
    // What ndfb_bake hands back against the folder itself and the files' own headers: the same
    // files, each of the kind, level and slot its name and ndfbake:* attributes say; the levels'
    // sizes as the lobe files have them; the atlas frames inside the atlas image.
    const std::string input = synth_file(Pattern::bumps, 24, 16, "bumps.png");
    const std::string color = synth_file(Pattern::fbm, 24, 16, "color.png");
    const std::string out = path("out");
    write_.atlas = 1;
    write_.mipmap = 1;
    write_.color_path = color.c_str();
    fit_.max_lobes = 3;
    ndfb_bake_result result = nullptr;
    ASSERT_EQ(ndfb_bake(ctx_, input.c_str(), out.c_str(), &decode_, &fit_, &write_, nullptr, nullptr, &result), NDFB_OK)
        << ndfb_last_error(ctx_);
    ASSERT_NE(result, nullptr);
    const uint32_t levels = ndfb_bake_result_level_count(result), slots = ndfb_bake_result_lobe_slots(result);
    EXPECT_EQ(levels, 6u);  // 24x16, 12x8, 6x4, 3x2, 2x1, 1x1
    EXPECT_EQ(slots, 3u);
    std::vector<std::string> named;
    int lobes = 0, colors = 0, atlases = 0, mips = 0, shaders = 0, reports = 0;
    for (uint32_t i = 0; i < ndfb_bake_result_file_count(result); ++i) {
        ndfb_bake_file file{};
        ASSERT_EQ(ndfb_bake_result_file(result, i, &file), NDFB_OK);
        named.push_back(file.name);
        EXPECT_EQ(ndfb_is_bake_file(file.name), 1) << file.name;
        char expected[32] = "";
        switch (file.kind) {
        case NDFB_FILE_LOBE: ++lobes; std::snprintf(expected, sizeof expected, "level%02d_lobe%d.exr", file.level, file.slot); break;
        case NDFB_FILE_COLOR: ++colors; std::snprintf(expected, sizeof expected, "level%02d_color%d.exr", file.level, file.slot); break;
        case NDFB_FILE_ATLAS: ++atlases; std::snprintf(expected, sizeof expected, "atlas_lobe%d.exr", file.slot); break;
        case NDFB_FILE_MIP: ++mips; std::snprintf(expected, sizeof expected, "mip_lobe%d.exr", file.slot); break;
        case NDFB_FILE_SHADER: ++shaders; std::snprintf(expected, sizeof expected, "ndfbake.glsl"); break;
        case NDFB_FILE_REPORT: ++reports; std::snprintf(expected, sizeof expected, "report.json"); break;
        }
        EXPECT_EQ(std::string(file.name), expected);
        if (file.kind == NDFB_FILE_LOBE) {
            uint32_t w = 0, h = 0;
            ASSERT_EQ(ndfb_bake_result_level_size(result, uint32_t(file.level), &w, &h), NDFB_OK);
            const ImageInfo info = read_image_info(out + "/" + file.name);
            EXPECT_EQ(uint32_t(info.width), w) << file.name;
            EXPECT_EQ(uint32_t(info.height), h) << file.name;
            for (const auto& [key, value] : info.attributes) {
                if (key == "ndfbake:level") EXPECT_EQ(value, std::to_string(file.level)) << file.name;
                if (key == "ndfbake:lobe") EXPECT_EQ(value, std::to_string(file.slot)) << file.name;
            }
        }
    }
    EXPECT_EQ(lobes, int(levels * slots));
    EXPECT_EQ(colors, int(levels * slots));
    EXPECT_EQ(atlases, int(slots));
    EXPECT_EQ(mips, int(slots));
    EXPECT_EQ(shaders, 1);
    EXPECT_EQ(reports, 1);
    EXPECT_EQ(named.back(), "report.json");
    std::set<std::string> paths;
    for (const std::string& name : named) paths.insert(out + "/" + name);
    EXPECT_EQ(paths.size(), named.size());
    EXPECT_EQ(paths, listing(out));

    std::vector<uint8_t> used(slots);
    ASSERT_EQ(ndfb_bake_result_slots_used(result, used.data(), used.size()), NDFB_OK);
    EXPECT_EQ(used, (std::vector<uint8_t>{1, 1, 1}));  // no tolerance: every slot holds lobes
    uint32_t atlas_width = 0, atlas_height = 0;
    ASSERT_EQ(ndfb_bake_result_atlas_size(result, &atlas_width, &atlas_height), NDFB_OK);
    const ImageInfo atlas = read_image_info(out + "/atlas_lobe0.exr");
    EXPECT_EQ(uint32_t(atlas.width), atlas_width);
    EXPECT_EQ(uint32_t(atlas.height), atlas_height);
    for (uint32_t level = 0; level < levels; ++level) {
        ndfb_atlas_frame frame{};
        uint32_t w = 0, h = 0;
        ASSERT_EQ(ndfb_bake_result_atlas_frame(result, level, &frame), NDFB_OK);
        ASSERT_EQ(ndfb_bake_result_level_size(result, level, &w, &h), NDFB_OK);
        EXPECT_EQ(frame.width, w);
        EXPECT_EQ(frame.height, h);
        EXPECT_LE(frame.x + frame.width + 2, atlas_width) << level;
        EXPECT_LE(frame.y + frame.height + 2, atlas_height) << level;
    }
    ndfb_atlas_frame frame{};
    EXPECT_EQ(ndfb_bake_result_atlas_frame(result, levels, &frame), NDFB_ERROR_INVALID_ARGUMENT);
    ndfb_bake_file file{};
    EXPECT_EQ(ndfb_bake_result_file(result, ndfb_bake_result_file_count(result), &file), NDFB_ERROR_INVALID_ARGUMENT);
    EXPECT_EQ(ndfb_bake_result_slots_used(result, used.data(), used.size() + 1), NDFB_ERROR_INVALID_ARGUMENT);
    ndfb_bake_result_destroy(result);

    for (const char* other : {"notes.txt", "level00_lobe0.exr.tmp", "Level00_lobe0.exr", "report.json.bak", "",
                              "level_lobe0.exr", "level00_lobe.exr", "level00_colour0.exr", "mip_lobe1.EXR",
                              "atlas_lobe0exr", "xlevel00_lobe0.exr"})
        EXPECT_EQ(ndfb_is_bake_file(other), 0) << other;
    for (const char* name : {"level123_lobe7.exr", "level00_color10.exr", "mip_lobe0.exr", "atlas_lobe12.exr"})
        EXPECT_EQ(ndfb_is_bake_file(name), 1) << name;
    EXPECT_EQ(ndfb_is_bake_file(nullptr), 0);
    EXPECT_EQ(ndfb_bake_result_file_count(nullptr), 0u);
}

TEST_F(BakeApi, AFailedBakeHandsBackNoResult)
{
    const std::string input = synth_file(Pattern::bumps, 16, 16, "bumps.png");
    fit_.max_lobes = ndfb_max_lobes() + 1;
    ndfb_bake_result result = reinterpret_cast<ndfb_bake_result>(&fit_);  // garbage the call must clear
    EXPECT_EQ(ndfb_bake(ctx_, input.c_str(), path("out").c_str(), &decode_, &fit_, &write_, nullptr, nullptr, &result),
              NDFB_ERROR_INVALID_ARGUMENT);
    EXPECT_EQ(result, nullptr);
    EXPECT_NE(std::string(ndfb_last_error(ctx_)).find("1.." + std::to_string(ndfb_max_lobes())), std::string::npos)
        << ndfb_last_error(ctx_);
}

TEST_F(BakeApi, FitOptionsAreCheckedAsTheBakeChecksThem)
{
    // ndfb_fit_options_check says what ndfb_bake would say about the same options, before any work.
    const std::string input = synth_file(Pattern::bumps, 8, 8, "bumps.png");
    EXPECT_EQ(ndfb_fit_options_check(ctx_, &fit_), NDFB_OK) << ndfb_last_error(ctx_);
    for (const uint32_t lobes : {0u, ndfb_max_lobes() + 1}) {
        fit_.max_lobes = lobes;
        EXPECT_EQ(ndfb_fit_options_check(ctx_, &fit_), NDFB_ERROR_INVALID_ARGUMENT) << lobes;
        const std::string checked = ndfb_last_error(ctx_);
        EXPECT_NE(checked.find("max_lobes must be in 1.." + std::to_string(ndfb_max_lobes())), std::string::npos) << checked;
        EXPECT_EQ(ndfb_bake(ctx_, input.c_str(), path("out").c_str(), &decode_, &fit_, &write_, nullptr, nullptr, nullptr),
                  NDFB_ERROR_INVALID_ARGUMENT);
        EXPECT_EQ(checked, ndfb_last_error(ctx_));
    }
    fit_.max_lobes = ndfb_max_lobes();
    fit_.tolerance = 2.0f;
    EXPECT_EQ(ndfb_fit_options_check(ctx_, &fit_), NDFB_ERROR_INVALID_ARGUMENT);
    EXPECT_NE(std::string(ndfb_last_error(ctx_)).find("tolerance"), std::string::npos) << ndfb_last_error(ctx_);
    EXPECT_EQ(ndfb_fit_options_check(ctx_, nullptr), NDFB_ERROR_INVALID_ARGUMENT);
    EXPECT_FALSE(std::filesystem::exists(path("out")));
}

TEST_F(BakeApi, BakeMapWritesWhatBakeWritesForTheSamePixels)
{
    // The same normals as a float EXR file and as pixels in memory (0.5 n + 0.5, as the file
    // stores them): ndfb_bake and ndfb_bake_map write the same lobe texels.
    ndfb_normal_map synthetic = nullptr;
    ASSERT_EQ(ndfb_synthesize(ctx_, "bumps", 16, 8, 3, &synthetic), NDFB_OK);
    const std::string input = path("bumps.exr");
    ASSERT_EQ(ndfb_normal_map_save(ctx_, synthetic, input.c_str()), NDFB_OK) << ndfb_last_error(ctx_);
    std::vector<float> pixels(16 * 8 * 3);
    ASSERT_EQ(ndfb_normal_map_read(synthetic, pixels.data(), pixels.size()), NDFB_OK);
    for (float& v : pixels) v = 0.5f * v + 0.5f;
    ndfb_normal_map_destroy(synthetic);
    ndfb_normal_map map = nullptr;
    ASSERT_EQ(ndfb_normal_map_from_pixels(ctx_, pixels.data(), pixels.size(), 16, 8, 3, 0, &decode_, &map), NDFB_OK);

    std::vector<std::string> stages;
    const ndfb_progress_fn note_stage = [](void* user, const char* stage, float) {
        auto& seen = *static_cast<std::vector<std::string>*>(user);
        if (seen.empty() || seen.back() != stage) seen.push_back(stage);
        return 0;
    };
    ASSERT_EQ(ndfb_bake(ctx_, input.c_str(), path("from_file").c_str(), &decode_, &fit_, &write_, nullptr, nullptr, nullptr), NDFB_OK)
        << ndfb_last_error(ctx_);
    ASSERT_EQ(ndfb_bake_map(ctx_, map, path("from_pixels").c_str(), &fit_, &write_, note_stage, &stages, nullptr), NDFB_OK)
        << ndfb_last_error(ctx_);
    ndfb_normal_map_destroy(map);
    EXPECT_EQ(stages, (std::vector<std::string>{"fit", "measure", "write"}));
    for (const char* file : {"/level00_lobe0.exr", "/level02_lobe3.exr", "/level04_lobe1.exr"}) {
        int w = 0, h = 0, w2 = 0, h2 = 0;
        EXPECT_EQ(read_rgba_exr(path("from_file") + file, w, h), read_rgba_exr(path("from_pixels") + file, w2, h2))
            << file;
    }
    std::ifstream report(path("from_pixels") + "/report.json");
    const std::string text((std::istreambuf_iterator<char>(report)), std::istreambuf_iterator<char>());
    for (const char* recorded : {"\"source\": \"memory\"", "\"format\": \"memory\"", "\"repairs\"", "\"assumptions\""})
        EXPECT_NE(text.find(recorded), std::string::npos) << recorded << " not in " << text;
}

TEST_F(BakeApi, TheFullLibraryReadsImageFiles) { EXPECT_EQ(ndfb_has_image_files(), 1); }

TEST_F(BakeApi, WrittenFilesRecordTheFitThePyramidHad)
{
    // Fitted with clamp and 2 lobes, written with the default options: the files say clamp and 2.
    ndfb_normal_map map = nullptr;
    ASSERT_EQ(ndfb_synthesize(ctx_, "fbm", 16, 16, 1, &map), NDFB_OK);
    ndfb_fit_options fitted = fit_;
    fitted.wrap = NDFB_WRAP_CLAMP;
    fitted.max_lobes = 2;
    ndfb_pyramid pyramid = nullptr;
    ASSERT_EQ(ndfb_fit(ctx_, map, &fitted, nullptr, nullptr, &pyramid), NDFB_OK) << ndfb_last_error(ctx_);
    ASSERT_EQ(ndfb_pyramid_write(ctx_, pyramid, map, path("out").c_str(), &write_, nullptr, nullptr, nullptr), NDFB_OK)
        << ndfb_last_error(ctx_);
    std::ifstream report(path("out") + "/report.json");
    const std::string text((std::istreambuf_iterator<char>(report)), std::istreambuf_iterator<char>());
    for (const char* recorded : {"\"wrap\": \"clamp\"", "\"max_lobes\": 2"})
        EXPECT_NE(text.find(recorded), std::string::npos) << recorded << " not in " << text;
    std::string wrap;
    for (const auto& [key, value] : read_image_info(path("out") + "/level01_lobe0.exr").attributes)
        if (key == "ndfbake:wrap") wrap = value;
    EXPECT_EQ(wrap, "clamp");
    ndfb_pyramid_destroy(pyramid);
    ndfb_normal_map_destroy(map);
}

TEST_F(BakeApi, ReadLobeReturnsWhatTheLobeFilesHold)
{
    // Level 0 holds single normals (κ at the cap): both must store them as |r| = 1.
    ndfb_normal_map map = nullptr;
    ASSERT_EQ(ndfb_synthesize(ctx_, "weave", 8, 8, 1, &map), NDFB_OK);
    ndfb_pyramid pyramid = nullptr;
    ASSERT_EQ(ndfb_fit(ctx_, map, &fit_, nullptr, nullptr, &pyramid), NDFB_OK) << ndfb_last_error(ctx_);
    write_.precision = NDFB_PRECISION_FLOAT;
    ASSERT_EQ(ndfb_pyramid_write(ctx_, pyramid, map, path("out").c_str(), &write_, nullptr, nullptr, nullptr), NDFB_OK)
        << ndfb_last_error(ctx_);
    for (uint32_t level = 0; level < ndfb_pyramid_level_count(pyramid); ++level)
        for (uint32_t lobe = 0; lobe < ndfb_pyramid_lobe_slots(pyramid); ++lobe) {
            char name[48];
            std::snprintf(name, sizeof name, "/level%02u_lobe%u.exr", level, lobe);
            int w = 0, h = 0;
            const std::vector<float> file = read_rgba_exr(path("out") + name, w, h);
            std::vector<float> read(file.size());
            ASSERT_EQ(ndfb_pyramid_read_lobe(pyramid, level, lobe, read.data(), read.size()), NDFB_OK);
            EXPECT_EQ(read, file) << name;
        }
    ndfb_pyramid_destroy(pyramid);
    ndfb_normal_map_destroy(map);
}

TEST_F(BakeApi, MaxLevelsFitsAndWritesOnlyTheLevelsAsked)
{
    const std::string input = synth_file(Pattern::fbm, 32, 32, "fbm.png");
    const std::string all = path("all"), three = path("three");
    ASSERT_EQ(ndfb_bake(ctx_, input.c_str(), all.c_str(), &decode_, &fit_, &write_, nullptr, nullptr, nullptr), NDFB_OK) << ndfb_last_error(ctx_);
    fit_.max_levels = 3;
    ASSERT_EQ(ndfb_bake(ctx_, input.c_str(), three.c_str(), &decode_, &fit_, &write_, nullptr, nullptr, nullptr), NDFB_OK) << ndfb_last_error(ctx_);
    // report.json, ndfbake.glsl and 3 levels × 4 lobes; the full bake has 6 levels (32² → 1²).
    EXPECT_EQ(listing(three).size(), 2u + 3u * 4u);
    EXPECT_EQ(listing(all).size(), 2u + 6u * 4u);
    // Levels 1 and 2 are fitted alike (alignment may order the slots differently): same texel sums.
    for (int level = 1; level < 3; ++level) {
        std::vector<float> sum_all, sum_three;
        for (int lobe = 0; lobe < 4; ++lobe) {
            char file[32];
            std::snprintf(file, sizeof file, "/level%02d_lobe%d.exr", level, lobe);
            int w = 0, h = 0;
            const std::vector<float> a = read_rgba_exr(all + file, w, h), b = read_rgba_exr(three + file, w, h);
            sum_all.resize(a.size());
            sum_three.resize(b.size());
            for (size_t i = 0; i < a.size(); i += 4) sum_all[i] += a[i];  // Σ α = 1 per texel in both
            for (size_t i = 0; i < b.size(); i += 4) sum_three[i] += b[i];
        }
        for (size_t i = 0; i < sum_all.size(); i += 4) EXPECT_NEAR(sum_all[i], sum_three[i], 2e-3f);
    }
    char file[32];
    std::snprintf(file, sizeof file, "/level%02d_lobe0.exr", 3);
    EXPECT_FALSE(std::filesystem::exists(three + file));
    fit_.max_levels = 65;
    EXPECT_EQ(ndfb_bake(ctx_, input.c_str(), path("bad").c_str(), &decode_, &fit_, &write_, nullptr, nullptr, nullptr), NDFB_ERROR_INVALID_ARGUMENT);
    EXPECT_NE(std::string(ndfb_last_error(ctx_)).find("max_levels"), std::string::npos);
}

TEST_F(BakeApi, StartsAreOneOrTwoAndTheDefaultIsTheHierarchicalFitWithTwo)
{
    EXPECT_EQ(fit_.method, NDFB_FIT_HIERARCHICAL);
    EXPECT_EQ(fit_.starts, 2u);
    const std::string input = synth_file(Pattern::fbm, 16, 16, "fbm.png");
    fit_.starts = 3;
    EXPECT_EQ(ndfb_bake(ctx_, input.c_str(), path("bad").c_str(), &decode_, &fit_, &write_, nullptr, nullptr, nullptr), NDFB_ERROR_INVALID_ARGUMENT);
    EXPECT_NE(std::string(ndfb_last_error(ctx_)).find("starts"), std::string::npos);
    EXPECT_FALSE(std::filesystem::exists(path("bad")));
    fit_.starts = 1;
    fit_.method = NDFB_FIT_PER_LEVEL;
    EXPECT_EQ(ndfb_bake(ctx_, input.c_str(), path("reference").c_str(), &decode_, &fit_, &write_, nullptr, nullptr, nullptr), NDFB_OK)
        << ndfb_last_error(ctx_);
}

// The fit_error attribute of a level's lobe-0 texture: the level's mean error under the bake's BRDF.
float level_fit_error(const std::string& folder, int level)
{
    char file[32];
    std::snprintf(file, sizeof file, "/level%02d_lobe0.exr", level);
    for (const auto& [key, value] : read_image_info(folder + file).attributes)
        if (key == "ndfbake:fit_error") return std::stof(value);
    ADD_FAILURE() << "no ndfbake:fit_error in " << folder << file;
    return -1.0f;
}

TEST_F(BakeApi, RefiningForTheBrdfLowersEveryLevelsErrorAndSaysSo)
{
    const std::string input = synth_file(Pattern::fbm, 64, 64, "fbm.png");
    fit_.brdf = NDFB_BRDF_BLINN_PHONG;
    fit_.brdf_parameter = 128.0f;
    const std::string em = path("em"), refined = path("refined");
    ASSERT_EQ(ndfb_bake(ctx_, input.c_str(), em.c_str(), &decode_, &fit_, &write_, nullptr, nullptr, nullptr), NDFB_OK) << ndfb_last_error(ctx_);
    fit_.refine = 1;
    ASSERT_EQ(ndfb_bake(ctx_, input.c_str(), refined.c_str(), &decode_, &fit_, &write_, nullptr, nullptr, nullptr), NDFB_OK)
        << ndfb_last_error(ctx_);
    // Level 1 holds each texel's four normals exactly (nothing to refine); above, every level is
    // lower and their mean by at least a fifth. (Not a tenth at every level: at the 1×1 top, where
    // the fit has one texel of 4096 normals, EM from k-means-fitted lower levels comes within 5%.)
    double em_sum = 0.0, refined_sum = 0.0;
    for (int level = 2; level < 7; ++level) {
        EXPECT_LT(level_fit_error(refined, level), level_fit_error(em, level)) << "level " << level;
        em_sum += level_fit_error(em, level);
        refined_sum += level_fit_error(refined, level);
    }
    EXPECT_LT(refined_sum, 0.8 * em_sum);
    std::string attribute = "(none)";
    for (const auto& [key, value] : read_image_info(refined + "/level03_lobe0.exr").attributes)
        if (key == "ndfbake:refined_for_brdf") attribute = value;
    EXPECT_EQ(attribute, "1");
    std::ifstream report(refined + "/report.json");
    std::string text((std::istreambuf_iterator<char>(report)), std::istreambuf_iterator<char>());
    std::erase_if(text, [](char c) { return std::isspace(static_cast<unsigned char>(c)); });
    EXPECT_NE(text.find("\"refined_for_brdf\":true"), std::string::npos);
    EXPECT_NE(text.find("\"brdf\":\"blinn-phong:128\""), std::string::npos);
}

// Occurrences of `needle` in `text`.
size_t count_of(const std::string& text, const std::string& needle)
{
    size_t n = 0;
    for (size_t at = text.find(needle); at != std::string::npos; at = text.find(needle, at + needle.size())) ++n;
    return n;
}

// The error without alignment is measured (an independent refit) only where lobes are pulled
// into alignment, and only above level 0. Elsewhere the report says null, not an error of 0 and
// an alignment cost equal to the whole error.
TEST_F(BakeApi, TheReportGivesNoErrorWithoutAlignmentItDidNotMeasure)
{
    const std::string input = synth_file(Pattern::fbm, 32, 32, "fbm.png");
    const auto report_of = [&](const std::string& out) {
        EXPECT_EQ(ndfb_bake(ctx_, input.c_str(), out.c_str(), &decode_, &fit_, &write_, nullptr, nullptr, nullptr), NDFB_OK) << ndfb_last_error(ctx_);
        std::ifstream file(out + "/report.json");
        std::string text((std::istreambuf_iterator<char>(file)), std::istreambuf_iterator<char>());
        std::erase_if(text, [](char c) { return std::isspace(static_cast<unsigned char>(c)); });
        return text;
    };
    const std::string unmeasured = "\"error_without_alignment\":null,\"alignment_cost\":null";
    const std::string measured = "\"error_without_alignment\":{\"mean\":";

    ASSERT_EQ(fit_.alignment_strength, 0.0f);  // the default: slots reordered, lobes not pulled
    const std::string plain = report_of(path("default"));
    EXPECT_EQ(count_of(plain, "\"level\":"), 6u);
    EXPECT_EQ(count_of(plain, unmeasured), 6u) << plain;
    EXPECT_EQ(count_of(plain, measured), 0u) << plain;

    fit_.alignment_strength = 0.5f;
    const std::string pulled = report_of(path("pulled"));
    EXPECT_EQ(count_of(pulled, unmeasured), 1u) << pulled;  // level 0
    EXPECT_EQ(count_of(pulled, measured), 5u) << pulled;
    EXPECT_EQ(count_of(pulled, measured + "0,"), 0u) << pulled;  // fbm: no level fits exactly
}

TEST_F(BakeApi, TheReportNamesTheSlotsNoTexelUsesAndTheirTexturesAreZero)
{
    const std::string input = synth_file(Pattern::bumps, 32, 32, "bumps.png");
    const std::string out = path("out");
    fit_.tolerance = 1.0f;  // any error is tolerated: one lobe per texel
    ASSERT_EQ(ndfb_bake(ctx_, input.c_str(), out.c_str(), &decode_, &fit_, &write_, nullptr, nullptr, nullptr), NDFB_OK) << ndfb_last_error(ctx_);
    std::ifstream report(out + "/report.json");
    std::string text((std::istreambuf_iterator<char>(report)), std::istreambuf_iterator<char>());
    std::erase_if(text, [](char c) { return std::isspace(static_cast<unsigned char>(c)); });
    ASSERT_NE(text.find("\"slots_used\":[true,false,false,false]"), std::string::npos);
    for (int level = 0; level < 6; ++level)
        for (int lobe = 1; lobe < 4; ++lobe) {
            char file[32];
            std::snprintf(file, sizeof file, "/level%02d_lobe%d.exr", level, lobe);
            int w = 0, h = 0;
            for (float v : read_rgba_exr(out + file, w, h)) ASSERT_EQ(v, 0.0f) << file;
        }
}

TEST_F(BakeApi, DirectXInputBakesExactlyLikeItsOpenGLTwin)
{
    NormalMap map = synthesize(Pattern::fbm, 16, 16);
    write_normal_map(path("gl.png"), map);
    for (Vec3& n : map.normals) n.y = -n.y;
    write_normal_map(path("dx.png"), map);
    ndfb_normal_map gl = nullptr, dx = nullptr;
    ASSERT_EQ(ndfb_normal_map_load(ctx_, path("gl.png").c_str(), &decode_, &gl), NDFB_OK);
    decode_.convention = NDFB_CONVENTION_DIRECTX;
    ASSERT_EQ(ndfb_normal_map_load(ctx_, path("dx.png").c_str(), &decode_, &dx), NDFB_OK);
    std::vector<float> a(16 * 16 * 3), b(16 * 16 * 3);
    ASSERT_EQ(ndfb_normal_map_read(gl, a.data(), a.size()), NDFB_OK);
    ASSERT_EQ(ndfb_normal_map_read(dx, b.data(), b.size()), NDFB_OK);
    EXPECT_EQ(a, b);
    ndfb_normal_map_destroy(gl);
    ndfb_normal_map_destroy(dx);
}

TEST_F(BakeApi, NanAndZeroPixelsAreRepairedCountedAndFitFinite)
{
    std::vector<float> pixels(4 * 4 * 3, 0.0f);  // signed encoding: all zero-length
    pixels[3] = std::nanf("");
    pixels[6] = 0.0f, pixels[7] = 0.0f, pixels[8] = -1.0f;  // below the horizon
    ndfb_normal_map map = nullptr;
    ASSERT_EQ(ndfb_normal_map_from_pixels(ctx_, pixels.data(), pixels.size(), 4, 4, 3, 1, &decode_, &map), NDFB_OK);
    ndfb_repairs repairs{};
    ASSERT_EQ(ndfb_normal_map_repairs(map, &repairs), NDFB_OK);
    EXPECT_EQ(repairs.non_finite, 1u);
    EXPECT_EQ(repairs.below_horizon, 1u);
    EXPECT_EQ(repairs.zero_length, 14u);
    ndfb_pyramid pyramid = nullptr;
    ASSERT_EQ(ndfb_fit(ctx_, map, &fit_, nullptr, nullptr, &pyramid), NDFB_OK);
    for (uint32_t level = 0; level < ndfb_pyramid_level_count(pyramid); ++level) {
        uint32_t w = 0, h = 0;
        ndfb_pyramid_level_size(pyramid, level, &w, &h);
        std::vector<float> rgba(size_t(w) * h * 4);
        for (uint32_t lobe = 0; lobe < ndfb_pyramid_lobe_slots(pyramid); ++lobe) {
            ASSERT_EQ(ndfb_pyramid_read_lobe(pyramid, level, lobe, rgba.data(), rgba.size()), NDFB_OK);
            for (float v : rgba) ASSERT_TRUE(std::isfinite(v));
        }
    }
    ndfb_pyramid_destroy(pyramid);
    ndfb_normal_map_destroy(map);
}

TEST_F(BakeApi, PerLobeColourFollowsTheNormalsItBelongsTo)
{
    // A V-groove whose facets tilted towards +X are red and the others blue (linear float EXR,
    // so no sRGB decoding is involved): every lobe must carry the colour of its facet (eq. 22).
    const NormalMap map = synthesize(Pattern::vgroove, 16, 16);
    write_normal_map(path("groove.png"), map);
    std::vector<float> rgba(map.normals.size() * 4);
    for (size_t i = 0; i < map.normals.size(); ++i) {
        const bool red = map.normals[i].x > 0.0f;
        rgba[i * 4 + 0] = red ? 1.0f : 0.0f;
        rgba[i * 4 + 2] = red ? 0.0f : 1.0f;
        rgba[i * 4 + 3] = 1.0f;
    }
    write_rgba_exr(path("color.exr"), 16, 16, rgba.data(), PixelPrecision::single, {});
    const std::string color = path("color.exr");
    write_.color_path = color.c_str();
    write_.precision = NDFB_PRECISION_FLOAT;
    ASSERT_EQ(ndfb_bake(ctx_, path("groove.png").c_str(), path("out").c_str(), &decode_, &fit_, &write_, nullptr, nullptr, nullptr), NDFB_OK)
        << ndfb_last_error(ctx_);
    int checked = 0;
    for (int level = 1; level <= 3; ++level)
        for (int lobe = 0; lobe < 4; ++lobe) {
            char name[48];
            std::snprintf(name, sizeof name, "/level%02d_", level);
            int w = 0, h = 0;
            const auto lobes = read_rgba_exr(path("out") + name + "lobe" + std::to_string(lobe) + ".exr", w, h);
            const auto colors = read_rgba_exr(path("out") + name + "color" + std::to_string(lobe) + ".exr", w, h);
            for (int t = 0; t < w * h; ++t) {
                const float alpha = lobes[size_t(t) * 4];
                EXPECT_NEAR(colors[size_t(t) * 4 + 3], alpha, 1e-5f);
                if (alpha < 0.1f) continue;
                const bool tilted_right = lobes[size_t(t) * 4 + 1] > 0.0f;  // α r_x
                EXPECT_NEAR(colors[size_t(t) * 4 + 0] / alpha, tilted_right ? 1.0f : 0.0f, 1e-3f);
                EXPECT_NEAR(colors[size_t(t) * 4 + 2] / alpha, tilted_right ? 0.0f : 1.0f, 1e-3f);
                ++checked;
            }
        }
    EXPECT_GT(checked, 40);
}

TEST_F(BakeApi, GreyAndAlphaColourImageGivesGreyLobes)
{
    // A two-channel colour image is grey and alpha: the lobes' colour is the grey, never the alpha.
    const NormalMap map = synthesize(Pattern::bumps, 16, 16);
    write_normal_map(path("bumps.png"), map);
    std::vector<float> grey_alpha(map.normals.size() * 2);
    for (size_t i = 0; i < map.normals.size(); ++i) {
        grey_alpha[i * 2 + 0] = 0.25f;
        grey_alpha[i * 2 + 1] = 1.0f;
    }
    {
        const std::string file = path("grey.tif");  // float: no sRGB decoding
        auto out = OIIO::ImageOutput::create(file);
        ASSERT_TRUE(out && out->open(file, OIIO::ImageSpec(16, 16, 2, OIIO::TypeDesc::FLOAT)));
        ASSERT_TRUE(out->write_image(OIIO::TypeDesc::FLOAT, grey_alpha.data()) && out->close());
    }
    const std::string color = path("grey.tif");
    write_.color_path = color.c_str();
    write_.precision = NDFB_PRECISION_FLOAT;
    ASSERT_EQ(ndfb_bake(ctx_, path("bumps.png").c_str(), path("out").c_str(), &decode_, &fit_, &write_, nullptr, nullptr, nullptr), NDFB_OK)
        << ndfb_last_error(ctx_);
    int w = 0, h = 0;
    const auto colors = read_rgba_exr(path("out") + "/level02_color0.exr", w, h);
    ASSERT_EQ(w * h, 16);
    for (int t = 0; t < w * h; ++t) {
        const float alpha = colors[size_t(t) * 4 + 3];
        ASSERT_GT(alpha, 0.0f);
        for (int c = 0; c < 3; ++c) EXPECT_NEAR(colors[size_t(t) * 4 + size_t(c)] / alpha, 0.25f, 1e-4f) << c;
    }
}

TEST_F(BakeApi, ABadColourImageFailsBeforeTheFit)
{
    const std::string input = synth_file(Pattern::bumps, 16, 16, "bumps.png");
    const std::string small = synth_file(Pattern::bumps, 8, 8, "small.png"), missing = path("missing.png");
    const ndfb_progress_fn note_stage = +[](void* stages, const char* stage, float) -> int {
        static_cast<std::vector<std::string>*>(stages)->push_back(stage);
        return 0;
    };
    for (const auto& [color, expected] : {std::pair{small, NDFB_ERROR_INVALID_ARGUMENT},
                                          std::pair{missing, NDFB_ERROR_FILE_NOT_FOUND}}) {
        std::vector<std::string> stages;
        write_.color_path = color.c_str();
        EXPECT_EQ(ndfb_bake(ctx_, input.c_str(), path("out").c_str(), &decode_, &fit_, &write_, note_stage, &stages, nullptr),
                  expected) << color;
        EXPECT_NE(std::string(ndfb_last_error(ctx_)).find(color), std::string::npos) << ndfb_last_error(ctx_);
        EXPECT_TRUE(stages.empty()) << color << ": reached stage " << stages.front();
        EXPECT_FALSE(std::filesystem::exists(path("out")));
    }
}

struct BadInput {
    const char* name;
    std::string contents;  // written to the input file unless `missing`
    bool missing;
    ndfb_status expected;
};

TEST_F(BakeApi, BadInputsGetSpecificErrorsAndLeaveNoOutput)
{
    const std::string good_png = synth_file(Pattern::fbm, 16, 16, "good.png");
    std::ifstream in(good_png, std::ios::binary);
    const std::string png((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    const BadInput cases[] = {
        {"missing.png", "", true, NDFB_ERROR_FILE_NOT_FOUND},
        {"empty.png", "", false, NDFB_ERROR_CORRUPT_FILE},
        {"corrupt.png", std::string(200, '\x5a'), false, NDFB_ERROR_CORRUPT_FILE},
        {"truncated.png", png.substr(0, png.size() / 2), false, NDFB_ERROR_CORRUPT_FILE},
        {"notes.txt", "not an image", false, NDFB_ERROR_UNSUPPORTED_FORMAT},
    };
    for (const BadInput& c : cases) {
        const std::string input = path(c.name), out = path(std::string("out-") + c.name);
        if (!c.missing) std::ofstream(input, std::ios::binary) << c.contents;
        const ndfb_status status = ndfb_bake(ctx_, input.c_str(), out.c_str(), &decode_, &fit_, &write_, nullptr, nullptr, nullptr);
        EXPECT_EQ(status, c.expected) << c.name << ": " << ndfb_last_error(ctx_);
        EXPECT_NE(std::string(ndfb_last_error(ctx_)).find(c.name), std::string::npos) << ndfb_last_error(ctx_);
        EXPECT_FALSE(std::filesystem::exists(out)) << c.name << ": a failed bake left its output folder";
    }
    // Nor the parents a nested output folder needed.
    const std::string nested = path("a") + "/b/c/";
    EXPECT_EQ(ndfb_bake(ctx_, path("missing.png").c_str(), nested.c_str(), &decode_, &fit_, &write_, nullptr, nullptr, nullptr),
              NDFB_ERROR_FILE_NOT_FOUND);
    EXPECT_FALSE(std::filesystem::exists(path("a"))) << "a failed bake left the parents of its output folder";
    // An output folder that cannot exist (under a regular file): an i/o error, before any work.
    const std::string out = good_png + "/out";
    EXPECT_EQ(ndfb_bake(ctx_, good_png.c_str(), out.c_str(), &decode_, &fit_, &write_, nullptr, nullptr, nullptr), NDFB_ERROR_IO);
    EXPECT_NE(std::string(ndfb_last_error(ctx_)).find("not writable"), std::string::npos) << ndfb_last_error(ctx_);
}

TEST_F(BakeApi, OptionsOutOfRangeAreRejected)
{
    const std::string input = synth_file(Pattern::fbm, 8, 8, "in.png");
    auto bake_with = [&](auto change) {
        ndfb_fit_options fit;
        ndfb_fit_options_init(&fit);
        change(fit);
        return ndfb_bake(ctx_, input.c_str(), path("out").c_str(), &decode_, &fit, &write_, nullptr, nullptr, nullptr);
    };
    EXPECT_EQ(bake_with([](ndfb_fit_options& f) { f.max_lobes = 0; }), NDFB_ERROR_INVALID_ARGUMENT);
    EXPECT_EQ(bake_with([](ndfb_fit_options& f) { f.max_lobes = 1000; }), NDFB_ERROR_INVALID_ARGUMENT);
    EXPECT_EQ(bake_with([](ndfb_fit_options& f) { f.tolerance = -0.1f; }), NDFB_ERROR_INVALID_ARGUMENT);
    EXPECT_EQ(bake_with([](ndfb_fit_options& f) { f.brdf_parameter = 7.0f; }), NDFB_ERROR_INVALID_ARGUMENT);
    EXPECT_EQ(bake_with([](ndfb_fit_options& f) { f.struct_size = 0; }), NDFB_ERROR_INVALID_ARGUMENT);
    EXPECT_TRUE(listing(path("out")).empty());
}

TEST_F(BakeApi, CancelLeavesAnEarlierBakeUntouched)
{
    const std::string input = synth_file(Pattern::weave, 64, 64, "weave.png");
    const std::string out = path("out");
    ASSERT_EQ(ndfb_bake(ctx_, input.c_str(), out.c_str(), &decode_, &fit_, &write_, nullptr, nullptr, nullptr), NDFB_OK);
    const auto before = listing(out);
    std::ifstream report_before(out + "/report.json");
    const std::string text_before((std::istreambuf_iterator<char>(report_before)), std::istreambuf_iterator<char>());

    for (const char* cancel_at : {"fit", "measure", "write"}) {
        const ndfb_progress_fn cancel = +[](void* user, const char* stage, float) -> int {
            return std::strcmp(stage, static_cast<const char*>(user)) == 0 ? 1 : 0;
        };
        fit_.max_lobes = 3;  // a different bake, so a partial commit would show
        ndfb_bake_result result = nullptr;
        EXPECT_EQ(ndfb_bake(ctx_, input.c_str(), out.c_str(), &decode_, &fit_, &write_, cancel, const_cast<char*>(cancel_at),
                            &result),
                  NDFB_ERROR_CANCELLED) << cancel_at;
        EXPECT_EQ(result, nullptr);
        EXPECT_EQ(listing(out), before) << cancel_at;
        std::ifstream report_after(out + "/report.json");
        EXPECT_EQ(std::string((std::istreambuf_iterator<char>(report_after)), std::istreambuf_iterator<char>()), text_before);
    }
}

TEST_F(BakeApi, CancelReachesTheFitOfAOneTexelMap)
{
    // A 1×1 map has no level to fit: its only progress call is the fit's last, which may cancel too.
    const float pixel[3] = {0.5f, 0.5f, 1.0f};
    ndfb_normal_map map = nullptr;
    ASSERT_EQ(ndfb_normal_map_from_pixels(ctx_, pixel, 3, 1, 1, 3, 0, &decode_, &map), NDFB_OK)
        << ndfb_last_error(ctx_);
    const ndfb_progress_fn cancel = +[](void*, const char*, float) -> int { return 1; };
    ndfb_pyramid pyramid = nullptr;
    EXPECT_EQ(ndfb_fit(ctx_, map, &fit_, cancel, nullptr, &pyramid), NDFB_ERROR_CANCELLED);
    EXPECT_EQ(pyramid, nullptr);
    ndfb_normal_map_destroy(map);
}

TEST_F(BakeApi, NullHandlesAndMismatchedSizesAreErrorsNotCrashes)
{
    EXPECT_EQ(ndfb_context_create(nullptr), NDFB_ERROR_INVALID_ARGUMENT);
    EXPECT_NE(std::string(ndfb_last_error(nullptr)), "");
    ndfb_normal_map map = nullptr;
    EXPECT_EQ(ndfb_normal_map_load(ctx_, nullptr, &decode_, &map), NDFB_ERROR_INVALID_ARGUMENT);
    float pixels[12] = {};
    EXPECT_EQ(ndfb_normal_map_from_pixels(ctx_, pixels, 12, 3, 3, 3, 0, &decode_, &map), NDFB_ERROR_INVALID_ARGUMENT);
    EXPECT_EQ(ndfb_fit(ctx_, nullptr, &fit_, nullptr, nullptr, nullptr), NDFB_ERROR_INVALID_ARGUMENT);
    EXPECT_EQ(ndfb_pyramid_read_lobe(nullptr, 0, 0, pixels, 4), NDFB_ERROR_INVALID_ARGUMENT);
    EXPECT_EQ(ndfb_pyramid_level_count(nullptr), 0u);
}

// ---- the command line ----------------------------------------------------------------------

struct CliResult {
    int exit_code;
    std::string err;
};

CliResult run_cli(const std::string& args, const std::string& err_file)
{
    const std::string command = std::string(NDFBAKE_CLI_PATH) + " " + args + " >/dev/null 2>" + err_file;
    const int status = std::system(command.c_str());
    std::ifstream in(err_file);
    return {WIFEXITED(status) ? WEXITSTATUS(status) : -1,
            std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>())};
}

TEST_F(BakeApi, CommandLineReportsFailuresInOneLineWithAnExitCode)
{
    const std::string err = path("stderr.txt");
    EXPECT_EQ(run_cli("--help", err).exit_code, 0);
    EXPECT_EQ(run_cli("bake --help", err).exit_code, 0);
    EXPECT_EQ(run_cli("bench --help", err).exit_code, 0);
    EXPECT_EQ(run_cli("synth weave --size 32 --out " + path("w.png"), err).exit_code, 0);
    EXPECT_EQ(run_cli("bake " + path("w.png") + " --out " + path("out") + " --quiet", err).exit_code, 0);
    EXPECT_EQ(run_cli("info " + path("out/level01_lobe0.exr"), err).exit_code, 0);
    const CliResult refined = run_cli("bake " + path("w.png") + " --out " + path("refined") + " --refine --brdf ggx:0.3 --quiet", err);
    EXPECT_EQ(refined.exit_code, 0) << refined.err;

    CliResult r = run_cli("bake " + path("nope.png") + " --out " + path("out2"), err);
    EXPECT_EQ(r.exit_code, 2);
    // Progress lines may come first; the reason is the last line, whole.
    ASSERT_FALSE(r.err.empty());
    EXPECT_EQ(r.err.back(), '\n');
    const std::string last_line = r.err.substr(r.err.rfind('\n', r.err.size() - 2) + 1);
    EXPECT_EQ(last_line.rfind("ndfbake: file not found: cannot read", 0), 0u) << r.err;
    r = run_cli("bake " + path("w.png") + " --out " + path("w.png") + "/x", err);
    EXPECT_EQ(r.exit_code, 3) << r.err;
    r = run_cli("bake " + path("w.png") + " --out " + path("o") + " --max-lobes 9", err);
    EXPECT_EQ(r.exit_code, 1) << r.err;
    r = run_cli("bake " + path("w.png") + " --out " + path("o") + " --max-memory 64K", err);
    EXPECT_EQ(r.exit_code, 2) << r.err;  // over the memory allowed: a bad input for this machine
    EXPECT_NE(r.err.find("--max-memory"), std::string::npos) << r.err;
    EXPECT_EQ(run_cli("bake " + path("w.png") + " --out " + path("o") + " --max-memory 1G --quiet", err).exit_code, 0);
    EXPECT_EQ(run_cli("bake " + path("w.png") + " --out " + path("o") + " --max-memory 12X", err).exit_code, 1);
    r = run_cli("frobnicate", err);
    EXPECT_EQ(r.exit_code, 1);
    EXPECT_FALSE(std::filesystem::exists(path("out2")) && !listing(path("out2")).empty());
}

TEST_F(BakeApi, InterruptingALargeBakeLeavesNoFiles)
{
    const std::string input = path("big.png"), out = path("out");
    ASSERT_EQ(run_cli("synth fbm --size 2048 --out " + input, path("synth.err")).exit_code, 0);
    const std::string err = path("bake.err");
    const pid_t child = fork();
    ASSERT_GE(child, 0);
    if (child == 0) {
        freopen(err.c_str(), "w", stderr);
        execl(NDFBAKE_CLI_PATH, NDFBAKE_CLI_PATH, "bake", input.c_str(), "--out", out.c_str(), nullptr);
        _exit(127);
    }
    // Wait until it reports fitting progress, then interrupt it as Ctrl-C would.
    bool fitting = false;
    for (int i = 0; i < 600 && !fitting; ++i) {
        std::this_thread::sleep_for(std::chrono::milliseconds(50));
        std::ifstream in(err);
        fitting = std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>()).find("fit") !=
                  std::string::npos;
    }
    EXPECT_TRUE(fitting) << "no progress was printed";
    kill(child, SIGINT);
    int status = 0;
    waitpid(child, &status, 0);
    ASSERT_TRUE(WIFEXITED(status));
    EXPECT_EQ(WEXITSTATUS(status), 130);
    EXPECT_TRUE(listing(out).empty());
}

// The same for synth, interrupted while it writes the image (its temporary file is there): exit
// 130, no temporary left, and the file an earlier run wrote under that name kept as it was.
TEST_F(BakeApi, InterruptingSynthLeavesNoFilesAndKeepsTheEarlierOne)
{
    const std::string folder = path("maps"), out = folder + "/fbm.png";
    std::filesystem::create_directories(folder);
    ASSERT_EQ(run_cli("synth fbm --size 8 --out " + out, path("small.err")).exit_code, 0);
    const auto read_all = [](const std::string& file) {
        std::ifstream in(file, std::ios::binary);
        return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    };
    const std::string earlier = read_all(out);
    const std::string err = path("synth.err");
    const pid_t child = fork();
    ASSERT_GE(child, 0);
    if (child == 0) {
        freopen(err.c_str(), "w", stderr);
        execl(NDFBAKE_CLI_PATH, NDFBAKE_CLI_PATH, "synth", "fbm", "--size", "2048", "--out", out.c_str(), nullptr);
        _exit(127);
    }
    // Wait until the image is being written (a second file in the folder), then Ctrl-C.
    bool writing = false;
    for (int i = 0; i < 60000 && !writing; ++i) {
        std::this_thread::sleep_for(std::chrono::milliseconds(1));
        writing = listing(folder).size() > 1;
    }
    EXPECT_TRUE(writing) << "no temporary file appeared";
    kill(child, SIGINT);
    int status = 0;
    waitpid(child, &status, 0);
    EXPECT_TRUE(WIFEXITED(status)) << "ended by signal " << (WIFSIGNALED(status) ? WTERMSIG(status) : 0);
    EXPECT_EQ(WIFEXITED(status) ? WEXITSTATUS(status) : -1, 130) << read_all(err);
    EXPECT_EQ(listing(folder), std::set<std::string>{out});  // no temporary left
    EXPECT_TRUE(read_all(out) == earlier) << "the earlier file changed";
}

}  // namespace
}  // namespace ndfbake
