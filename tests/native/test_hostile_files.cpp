// Hostile input files through the public C API (issue 6): headers that claim huge sizes, bakes over
// the memory limit, empty and truncated files, NaN/Inf/huge EXR values, normals at the horizon,
// wrong channel counts, paths with spaces and non-ASCII characters. Each gets a specific status and
// a one-line message naming the problem, and no bake leaves a file behind.

#include <gtest/gtest.h>

#include "hostile_fixtures.h"

namespace ndfbake {
namespace {

using namespace hostile_inputs;

// ---- sizes and memory ------------------------------------------------------------------------

TEST_F(HostileInputs, HeadersClaimingHugeImagesAreRefusedBeforeAnyPixelIsRead)
{
    // 10^10 pixels: over max_pixels (2^28 by default), refused from the header alone; reading
    // would instead find the pixel data missing (corrupt file).
    write_bytes(path("huge.png"), png_claiming(100000, 100000));
    write_bytes(path("huge.exr"), exr_claiming(100000, 100000));
    for (const char* name : {"huge.png", "huge.exr"}) {
        const std::string file = path(name);
        expect_load_error(file, NDFB_ERROR_OUT_OF_MEMORY,
                          {file, "100000 x 100000 = 10000000000 pixels", "over the limit of 268435456"}, name);
        expect_bake_error(file, NDFB_ERROR_OUT_OF_MEMORY, {file, "100000 x 100000"}, name);
    }
    // TGA headers stop at 65535.
    const unsigned char tga[18] = {0, 0, 2, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0xff, 0xff, 0xff, 0xff, 24, 0x20};
    write_bytes(path("huge.tga"), std::string(reinterpret_cast<const char*>(tga), 18));
    expect_bake_error(path("huge.tga"), NDFB_ERROR_OUT_OF_MEMORY, {"65535 x 65535"}, "huge.tga");

    // The caller's own pixel limit.
    decode_.max_pixels = 1000;
    const std::string small = synth_png("small.png", 64);
    expect_bake_error(small, NDFB_ERROR_OUT_OF_MEMORY, {"64 x 64 = 4096 pixels", "over the limit of 1000"},
                      "max_pixels");
}

TEST_F(HostileInputs, ABakeOverTheMemoryLimitIsRefusedUpFrontWithTheEstimate)
{
    // A header alone (no pixel data) claiming 4096 x 4096: refused for memory, not found
    // truncated, so the check ran before decoding.
    write_bytes(path("big.png"), png_claiming(4096, 4096));
    fit_.max_memory_bytes = 64ull << 20;
    fit_.max_lobes = 4;
    expect_bake_error(path("big.png"), NDFB_ERROR_OUT_OF_MEMORY,
                      {path("big.png"), "4096 x 4096 map with 4 lobe slots needs an estimated",
                       "over the memory limit of 67108864 bytes (64.0 MiB)", "max_memory_bytes"},
                      "memory limit");

    // ndfb_fit checks the same budget for a map already in memory.
    ndfb_normal_map map = nullptr;
    ASSERT_EQ(ndfb_synthesize(ctx_, "bumps", 512, 512, 1, &map), NDFB_OK);
    fit_.max_memory_bytes = 1ull << 20;
    ndfb_pyramid pyramid = reinterpret_cast<ndfb_pyramid>(0x1);
    expect_error(ndfb_fit(ctx_, map, &fit_, nullptr, nullptr, &pyramid), NDFB_ERROR_OUT_OF_MEMORY,
                 {"cannot fit the map", "512 x 512", "over the memory limit of 1048576 bytes"}, "fit limit");
    EXPECT_EQ(pyramid, nullptr);
    ndfb_normal_map_destroy(map);

    // Within the limit: the bake runs and its report gives the estimate and the measured peak.
    fit_.max_memory_bytes = 1ull << 30;
    const std::string input = synth_png("ok.png", 32);
    ASSERT_EQ(ndfb_bake(ctx_, input.c_str(), path("ok").c_str(), &decode_, &fit_, &write_, nullptr, nullptr, nullptr), NDFB_OK) << error();
    const std::string report = read_bytes(path("ok/report.json"));
    for (const char* key : {"\"peak_memory_bytes\": ", "\"estimated_memory_bytes\": ", "\"memory_limit_bytes\": 1073741824"})
        EXPECT_NE(report.find(key), std::string::npos) << key;
    EXPECT_EQ(report.find("\"peak_memory_bytes\": 0,"), std::string::npos);
}

// ---- damaged files ---------------------------------------------------------------------------

TEST_F(HostileInputs, ZeroLengthFilesAreCorrupt)
{
    for (const char* name : {"empty.png", "empty.exr", "empty.tga", "empty.tif", "empty.jpg", "empty"}) {
        write_bytes(path(name), "");
        expect_load_error(path(name), NDFB_ERROR_CORRUPT_FILE, {path(name), "file is empty (0 bytes)"}, name);
        expect_bake_error(path(name), NDFB_ERROR_CORRUPT_FILE, {path(name), "file is empty (0 bytes)"}, name);
    }
}

TEST_F(HostileInputs, TruncatedFilesAreCorrupt)
{
    const NormalMap map = synthesize(Pattern::bumps, 64, 64);
    std::vector<float> rgb(map.normals.size() * 3);
    for (size_t i = 0; i < map.normals.size(); ++i)
        for (int c = 0; c < 3; ++c) rgb[i * 3 + size_t(c)] = 0.5f + 0.5f * map.normals[i][c];
    write_image(path("full.png"), 64, 64, 3, OIIO::TypeDesc::UINT8, rgb);
    write_image(path("full.tga"), 64, 64, 3, OIIO::TypeDesc::UINT8, rgb);
    write_image(path("full.tif"), 64, 64, 3, OIIO::TypeDesc::UINT16, rgb);
    write_image(path("full.jpg"), 64, 64, 3, OIIO::TypeDesc::UINT8, rgb);
    write_image(path("full.exr"), 64, 64, 3, OIIO::TypeDesc::HALF, rgb);
    for (const std::string ext : {"png", "tga", "tif", "jpg", "exr"}) {
        const std::string bytes = read_bytes(path("full." + ext));
        // Cut inside the pixel data: the header reads, the pixels do not.
        const std::string half = path("half." + ext);
        write_bytes(half, bytes.substr(0, bytes.size() / 2));
        expect_load_error(half, NDFB_ERROR_CORRUPT_FILE, {half, "truncated"}, "half " + ext);
        expect_bake_error(half, NDFB_ERROR_CORRUPT_FILE, {half, "truncated"}, "half " + ext);
        // Cut inside the header: the file does not open as its format.
        const std::string stub = path("stub." + ext);
        write_bytes(stub, bytes.substr(0, 12));
        expect_load_error(stub, NDFB_ERROR_CORRUPT_FILE, {stub, "damaged, or not really a ." + ext + " file"},
                          "stub " + ext);
        expect_bake_error(stub, NDFB_ERROR_CORRUPT_FILE, {stub}, "stub " + ext);
    }
}

TEST_F(HostileInputs, ExrWithNanInfNegativeAndHugeValuesIsRepairedAndCounted)
{
    // Such values are a documented input, not an error: each texel is repaired (docs/lobe-format.md: NaN/Inf
    // or too short -> +Z, z < 0 -> -z, then normalized), counted, and the bake's output is finite.
    const float inf = std::numeric_limits<float>::infinity(), nan = std::numeric_limits<float>::quiet_NaN();
    std::vector<float> rgb(8 * 8 * 3);
    for (size_t i = 0; i < rgb.size(); i += 3) rgb[i] = 0.0f, rgb[i + 1] = 0.0f, rgb[i + 2] = 1.0f;
    const std::vector<std::vector<float>> special = {
        {nan, 0.0f, 1.0f},          // non-finite
        {inf, 0.0f, 1.0f},          // non-finite
        {0.0f, -inf, 1.0f},         // non-finite
        {0.6f, 0.0f, -0.8f},        // below the horizon (unit length)
        {1e30f, 0.0f, 1e30f},       // huge: renormalized
        {-FLT_MAX, FLT_MAX, FLT_MAX},  // huge and negative: renormalized
        {1e-30f, 1e-30f, 1e-30f},   // too short: +Z
        {3.0f, 0.0f, 4.0f},         // length 5: renormalized
    };
    for (size_t k = 0; k < special.size(); ++k)
        for (int c = 0; c < 3; ++c) rgb[k * 3 + size_t(c)] = special[k][size_t(c)];
    write_image(path("float.exr"), 8, 8, 3, OIIO::TypeDesc::FLOAT, rgb);

    ndfb_normal_map map = nullptr;
    ASSERT_EQ(ndfb_normal_map_load(ctx_, path("float.exr").c_str(), &decode_, &map), NDFB_OK) << error();
    ndfb_repairs repairs{};
    ASSERT_EQ(ndfb_normal_map_repairs(map, &repairs), NDFB_OK);
    EXPECT_EQ(repairs.non_finite, 3u);
    EXPECT_EQ(repairs.zero_length, 1u);
    EXPECT_EQ(repairs.below_horizon, 1u);
    EXPECT_EQ(repairs.renormalized, 3u);
    std::vector<float> normals(8 * 8 * 3);
    ASSERT_EQ(ndfb_normal_map_read(map, normals.data(), normals.size()), NDFB_OK);
    for (size_t i = 0; i < normals.size(); i += 3) {
        const float len = std::sqrt(normals[i] * normals[i] + normals[i + 1] * normals[i + 1] +
                                    normals[i + 2] * normals[i + 2]);
        EXPECT_TRUE(std::isfinite(len) && std::abs(len - 1.0f) < 1e-5f && normals[i + 2] >= 0.0f) << i / 3;
    }
    ndfb_normal_map_destroy(map);

    // Half EXR: Inf, the largest half, NaN; and a 2-channel float file whose z is rebuilt.
    std::vector<float> half(4 * 4 * 3, 0.5f);
    half[0] = inf, half[4] = 65504.0f, half[8] = nan, half[9] = -65504.0f;
    write_image(path("half.exr"), 4, 4, 3, OIIO::TypeDesc::HALF, half);
    std::vector<float> xy(4 * 4 * 2, 0.0f);
    xy[0] = nan, xy[3] = 1e30f, xy[4] = -inf;
    write_image(path("xy.exr"), 4, 4, 2, OIIO::TypeDesc::FLOAT, xy);

    for (const char* name : {"float.exr", "half.exr", "xy.exr"}) {
        const std::string out = path(std::string("out-") + name);
        ASSERT_EQ(ndfb_bake(ctx_, path(name).c_str(), out.c_str(), &decode_, &fit_, &write_, nullptr, nullptr, nullptr), NDFB_OK)
            << name << ": " << error();
        const std::string report = read_bytes(out + "/report.json");
        EXPECT_EQ(report.find("\"non_finite\": 0,"), std::string::npos) << name << ": repairs not reported";
        for (const auto& entry : fs::directory_iterator(out)) {
            if (entry.path().extension() != ".exr") continue;
            auto in = OIIO::ImageInput::open(entry.path().string());
            ASSERT_TRUE(in);
            std::vector<float> pixels(size_t(in->spec().image_pixels()) * size_t(in->spec().nchannels));
            ASSERT_TRUE(in->read_image(0, 0, 0, in->spec().nchannels, OIIO::TypeDesc::FLOAT, pixels.data()));
            for (float v : pixels) ASSERT_TRUE(std::isfinite(v)) << entry.path();
        }
    }
}

TEST_F(HostileInputs, HorizonNormalsGiveFiniteErrorsUnderEveryBrdf)
{
    // Found by fuzz_bake (corpus/bake/beckmann_horizon_nan): a 13 x 16 map of +Z with texels on
    // the horizon (as the repair leaves x = +-1 texels) gave lobes whose Beckmann-convolved
    // distribution was evaluated just above the horizon, where exp() and c^4 both underflow:
    // 0/0 = NaN in the texel errors, the lobe budget and report.json.
    std::vector<float> pixels(13 * 16 * 3, 0.0f);
    for (size_t i = 2; i < pixels.size(); i += 3) pixels[i] = 1.0f;
    const struct {
        int texel;
        float x, y;
    } horizon[] = {{15, 1, 0},   {29, 6.47306442e-05f, 1}, {37, 0, -1},  {44, 1, 0},   {52, 0, -1},  {59, 1, 0},
                   {60, 0, -1},  {66, 1, 0},   {67, -1, 0},  {74, 0, 1},   {81, 1, 0},   {82, -1, 0},  {104, 1, 0},
                   {118, 6.47306442e-05f, 1}, {126, 0, -1}, {133, 1, 0},  {141, 0, -1}, {148, 1, 0},  {149, 0, -1},
                   {155, 1, 0},  {156, -1, 0}, {163, 0, 1},  {170, 1, 0},  {171, -1, 0}, {193, 1, 0},
                   {207, 6.47306442e-05f, 1}};
    for (const auto& h : horizon) {
        pixels[size_t(h.texel) * 3 + 0] = h.x;
        pixels[size_t(h.texel) * 3 + 1] = h.y;
        pixels[size_t(h.texel) * 3 + 2] = 0.0f;
    }
    ndfb_normal_map map = nullptr;
    ASSERT_EQ(ndfb_normal_map_from_pixels(ctx_, pixels.data(), pixels.size(), 13, 16, 3, 1, &decode_, &map), NDFB_OK);
    const struct {
        ndfb_brdf brdf;
        float parameter;
    } brdfs[] = {{NDFB_BRDF_BECKMANN, 1.0f}, {NDFB_BRDF_BECKMANN, 0.0001f}, {NDFB_BRDF_GGX, 1.0f},
                 {NDFB_BRDF_GGX, 0.01f}, {NDFB_BRDF_BLINN_PHONG, 1.0f}, {NDFB_BRDF_BLINN_PHONG, 10000.0f},
                 {NDFB_BRDF_LAMBERT, 0.0f}};
    for (const auto& b : brdfs) {
        fit_.brdf = b.brdf;
        fit_.brdf_parameter = b.parameter;
        fit_.max_lobes = 8;
        fit_.max_iterations = 16;
        ndfb_pyramid pyramid = nullptr;
        ASSERT_EQ(ndfb_fit(ctx_, map, &fit_, nullptr, nullptr, &pyramid), NDFB_OK) << error();
        for (uint32_t level = 1; level < ndfb_pyramid_level_count(pyramid); ++level) {
            float value = -1.0f;
            ASSERT_EQ(ndfb_texel_error(ctx_, map, pyramid, NDFB_REPR_VMF_MIXTURE, NDFB_WRAP_REPEAT, level, 0, 0,
                                       b.brdf, b.parameter, &value),
                      NDFB_OK);
            EXPECT_TRUE(std::isfinite(value) && value >= 0.0f) << int(b.brdf) << " " << b.parameter << " level "
                                                               << level << ": " << value;
            ndfb_level_stats stats;
            ASSERT_EQ(ndfb_pyramid_level_stats(ctx_, pyramid, level, b.brdf, b.parameter, 0, &stats), NDFB_OK);
            EXPECT_TRUE(std::isfinite(stats.mean_error) && std::isfinite(stats.p95_error)) << level;
        }
        ndfb_pyramid_destroy(pyramid);
    }
    ndfb_normal_map_destroy(map);
}

TEST_F(HostileInputs, OneOrFiveAndMoreChannelsAreUnsupported)
{
    write_image(path("grey.png"), 8, 8, 1, OIIO::TypeDesc::UINT8, std::vector<float>(64, 0.5f));
    write_image(path("grey.exr"), 8, 8, 1, OIIO::TypeDesc::HALF, std::vector<float>(64, 0.5f));
    write_image(path("five.tif"), 8, 8, 5, OIIO::TypeDesc::UINT8, std::vector<float>(8 * 8 * 5, 0.5f));
    write_image(path("six.exr"), 8, 8, 6, OIIO::TypeDesc::FLOAT, std::vector<float>(8 * 8 * 6, 0.5f));
    const struct {
        const char* name;
        const char* says;
    } cases[] = {{"grey.png", "1 channel;"}, {"grey.exr", "1 channel;"}, {"five.tif", "5 channels;"},
                 {"six.exr", "6 channels;"}};
    for (const auto& c : cases) {
        const std::string file = path(c.name);
        expect_load_error(file, NDFB_ERROR_UNSUPPORTED_FORMAT,
                          {file, c.says, "a normal map needs 2 (XY), 3 (XYZ) or 4 (XYZ + alpha)"}, c.name);
        expect_bake_error(file, NDFB_ERROR_UNSUPPORTED_FORMAT, {file, c.says}, c.name);
    }
    // The same from memory, and no channels at all.
    const std::vector<float> pixels(4 * 4 * 5, 0.5f);
    for (uint32_t channels : {0u, 1u, 5u}) {
        ndfb_normal_map map = nullptr;
        expect_error(ndfb_normal_map_from_pixels(ctx_, pixels.data(), 16 * size_t(channels), 4, 4, channels, 0,
                                                 &decode_, &map),
                     NDFB_ERROR_UNSUPPORTED_FORMAT,
                     {"in-memory pixels", std::to_string(channels) + (channels == 1 ? " channel;" : " channels;")},
                     std::to_string(channels) + " channels in memory");
        EXPECT_EQ(map, nullptr);
    }
}

// ---- paths -----------------------------------------------------------------------------------

TEST_F(HostileInputs, PathsWithSpacesAndNonAsciiCharactersWork)
{
    const std::string folder = path("maps with spaces/Ñandú 法线 😀");
    fs::create_directories(folder);
    const std::string input = folder + "/normal map é ü.png";
    write_normal_map(input, synthesize(Pattern::bumps, 16, 16));
    const std::string out = path("out folder/résultat 出力");
    ASSERT_EQ(ndfb_bake(ctx_, input.c_str(), out.c_str(), &decode_, &fit_, &write_, nullptr, nullptr, nullptr), NDFB_OK) << error();
    EXPECT_TRUE(fs::exists(out + "/level00_lobe0.exr"));
    EXPECT_NE(read_bytes(out + "/report.json").find("normal map é ü.png"), std::string::npos);
    char text[4096];
    size_t length = 0;
    ASSERT_EQ(ndfb_describe_image(ctx_, (out + "/level01_lobe1.exr").c_str(), text, sizeof text, &length), NDFB_OK);
    EXPECT_NE(std::string(text).find("résultat 出力"), std::string::npos);

    // Errors name the path exactly as given.
    const std::string missing = folder + "/n’existe pas.png";
    expect_bake_error(missing, NDFB_ERROR_FILE_NOT_FOUND, {"cannot read '" + missing + "': no such file"}, "missing");
    const std::string damaged = folder + "/abîmé 壊れた.png";
    write_bytes(damaged, std::string(100, 'x'));
    expect_bake_error(damaged, NDFB_ERROR_CORRUPT_FILE, {"cannot read '" + damaged + "'"}, "damaged");

    // And the same for saving a map.
    ndfb_normal_map map = nullptr;
    ASSERT_EQ(ndfb_synthesize(ctx_, "weave", 8, 8, 0, &map), NDFB_OK);
    EXPECT_EQ(ndfb_normal_map_save(ctx_, map, (folder + "/tissé 織物.tga").c_str()), NDFB_OK) << error();
    EXPECT_TRUE(fs::exists(folder + "/tissé 織物.tga"));
    ndfb_normal_map_destroy(map);

    // A name that is not UTF-8 (Latin-1 "é"): the bake works and report.json stays UTF-8, the
    // byte replaced by U+FFFD.
    const std::string latin1 = path("carte \xe9.png");
    write_normal_map(latin1, synthesize(Pattern::bumps, 8, 8));
    ASSERT_EQ(ndfb_bake(ctx_, latin1.c_str(), path("latin1").c_str(), &decode_, &fit_, &write_, nullptr, nullptr, nullptr), NDFB_OK) << error();
    const std::string report = read_bytes(path("latin1") + "/report.json");
    EXPECT_NE(report.find("carte \\ufffd.png"), std::string::npos);
    EXPECT_EQ(report.find('\xe9'), std::string::npos);
}

}  // namespace
}  // namespace ndfbake
