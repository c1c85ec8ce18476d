// The MIP-mapped lobe files (write option mipmap, `ndfbake bake --mipmap`): one tiled OpenEXR file
// per lobe slot whose MIP levels are the fitted levels, read back through OpenImageIO (every
// level, the attributes) and through its texture system, the filter OSL's texture() runs.
#include <gtest/gtest.h>

#include <OpenImageIO/imageio.h>
#include <OpenImageIO/texture.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "io/image_files.h"
#include "io/lobe_exr.h"
#include "ndfbake.h"
#include "pyramid/footprint.h"
#include "synth/patterns.h"
#include "test_support.h"

namespace ndfbake {
namespace {

std::string level_file(const std::string& dir, int level, int lobe)
{
    char name[48];
    std::snprintf(name, sizeof name, "/level%02d_lobe%d.exr", level, lobe);
    return dir + name;
}

std::string mip_file(const std::string& dir, int lobe) { return dir + "/mip_lobe" + std::to_string(lobe) + ".exr"; }

// Every MIP level of `path` as RGBA floats, top row first, with its size.
struct Level {
    int width = 0, height = 0;
    std::vector<float> rgba;
};

std::vector<Level> read_mip_levels(const std::string& path, OIIO::ImageSpec* first_spec = nullptr)
{
    std::vector<Level> levels;
    auto in = OIIO::ImageInput::open(path);
    EXPECT_TRUE(in) << OIIO::geterror();
    if (!in) return levels;
    if (first_spec) *first_spec = in->spec();
    for (int m = 0; in->seek_subimage(0, m); ++m) {
        const OIIO::ImageSpec& spec = in->spec();
        Level l{spec.width, spec.height, std::vector<float>(size_t(spec.width) * size_t(spec.height) * 4)};
        EXPECT_EQ(spec.nchannels, 4);
        EXPECT_TRUE(in->read_image(0, m, 0, 4, OIIO::TypeDesc::FLOAT, l.rgba.data())) << in->geterror();
        levels.push_back(std::move(l));
    }
    return levels;
}

TEST(MipFile, OpenExrRoundUpLevelsAreTheBakesLevels)
{
    // A chain of the bake's level sizes is the chain OpenEXR lays out (the writer checks against
    // its layout), and reads back level by level at those sizes.
    const std::string path = (std::filesystem::path(::testing::TempDir()) / "ndfbake-mip-levels.exr").string();
    for (const auto& [w, h] : std::vector<std::pair<int, int>>{
             {1, 1}, {2, 2}, {64, 64}, {200, 72}, {5, 3}, {1000, 1}, {3, 1024}, {4097, 17}}) {
        // Level l filled with l; each level's buffer is its own vector, so `chain`'s pointers stay valid.
        std::vector<std::vector<float>> pixels(size_t(level_count(w, h)));
        std::vector<RgbaLevel> chain;
        for (int l = 0; l < level_count(w, h); ++l) {
            const LevelSize size = level_size(w, h, l);
            pixels[size_t(l)].assign(size_t(size.width) * size_t(size.height) * 4, float(l));
            chain.push_back({size.width, size.height, pixels[size_t(l)].data()});
        }
        ASSERT_NO_THROW(write_mip_rgba_exr(path, chain, PixelPrecision::half, {})) << w << "x" << h;
        const std::vector<Level> read = read_mip_levels(path);
        ASSERT_EQ(int(read.size()), level_count(w, h)) << w << "x" << h;
        for (int l = 0; l < level_count(w, h); ++l) {
            EXPECT_EQ(read[size_t(l)].width, level_size(w, h, l).width) << w << "x" << h << " level " << l;
            EXPECT_EQ(read[size_t(l)].height, level_size(w, h, l).height) << w << "x" << h << " level " << l;
            EXPECT_EQ(read[size_t(l)].rgba.front(), float(l)) << w << "x" << h << " level " << l;
        }
    }
    std::filesystem::remove(path);
}

TEST(MipFile, AChainOfOtherSizesIsRefused)
{
    const std::vector<float> pixels(64 * 4, 0.0f);
    const std::string path = (std::filesystem::path(::testing::TempDir()) / "ndfbake-mip-refused.exr").string();
    const std::vector<RgbaLevel> short_chain = {{8, 8, pixels.data()}, {4, 4, pixels.data()}};
    const std::vector<RgbaLevel> rounded_down = {{5, 5, pixels.data()}, {2, 2, pixels.data()}, {1, 1, pixels.data()}};
    for (const auto& chain : {short_chain, rounded_down}) {
        try {
            write_mip_rgba_exr(path, chain, PixelPrecision::half, {});
            ADD_FAILURE() << "a chain of " << chain.size() << " levels from " << chain[0].width << "x" << chain[0].height
                          << " was written";
        } catch (const Error& e) {
            EXPECT_EQ(e.status(), Status::invalid_argument) << e.what();
        }
    }
    // Nothing is left, not even the temporary file the checks ran in.
    for (const auto& entry : std::filesystem::directory_iterator(::testing::TempDir()))
        EXPECT_EQ(entry.path().filename().string().find("ndfbake-mip-refused"), std::string::npos) << entry.path();
}

class MipFileBake : public testing_support::CApiTest {};

// 200 x 72: level 0 is 4 x 2 tiles, level 1 (100 x 36) ends in a tile 36 texels wide, which
// OpenEXRCore 3.1 alone would size from level 0 (lobe_exr.cpp, write_level_tiles).
TEST_F(MipFileBake, EveryLevelIsTheFittedLevelAndTheHeaderDescribesIt)
{
    const std::string input = synth_file(Pattern::fbm, 200, 72, "fbm.png");
    const std::string out = path("out");
    write_.mipmap = 1;
    ASSERT_EQ(ndfb_bake(ctx_, input.c_str(), out.c_str(), &decode_, &fit_, &write_, nullptr, nullptr, nullptr), NDFB_OK) << ndfb_last_error(ctx_);
    const int chain = level_count(200, 72);
    ASSERT_EQ(chain, 9);
    for (int lobe = 0; lobe < 4; ++lobe) {
        OIIO::ImageSpec spec;
        const std::vector<Level> levels = read_mip_levels(mip_file(out, lobe), &spec);
        ASSERT_EQ(int(levels.size()), chain);
        EXPECT_EQ(spec.tile_width, kMipTileSize);
        EXPECT_EQ(spec.tile_height, kMipTileSize);
        EXPECT_EQ(spec.format, OIIO::TypeDesc::HALF);
        EXPECT_EQ(spec.get_int_attribute("ndfbake:lobe", -2), lobe);
        EXPECT_EQ(spec.get_int_attribute("ndfbake:level", -2), -1);
        EXPECT_EQ(spec.get_int_attribute("ndfbake:lobe_slots"), 4);
        EXPECT_EQ(spec.get_int_attribute("ndfbake:mip_levels"), chain);
        EXPECT_EQ(spec.get_int_attribute("ndfbake:fitted_levels"), chain);
        EXPECT_EQ(spec.get_int_attribute("ndfbake:format_version"), 1);
        EXPECT_EQ(spec.get_string_attribute("ndfbake:brdf"), "ggx:0.5");
        EXPECT_EQ(spec.get_string_attribute("ndfbake:source"), "fbm.png");
        EXPECT_NE(spec.get_string_attribute("ndfbake:content").find("R = alpha, GBA = alpha * r"), std::string::npos);
        EXPECT_EQ(std::count(spec.get_string_attribute("ndfbake:level_errors").begin(),
                             spec.get_string_attribute("ndfbake:level_errors").end(), ';') + 1,
                  chain);
        // Channels as the per-level files, and every level bit for bit their pixels.
        for (int c = 0; c < 4; ++c) EXPECT_EQ(spec.channelnames[size_t(c)], std::string(1, "RGBA"[c]));
        for (int l = 0; l < chain; ++l) {
            int w = 0, h = 0;
            const std::vector<float> fitted = read_rgba_exr(level_file(out, l, lobe), w, h);
            ASSERT_EQ(levels[size_t(l)].width, w) << "level " << l;
            ASSERT_EQ(levels[size_t(l)].height, h) << "level " << l;
            ASSERT_EQ(w, level_size(200, 72, l).width);
            ASSERT_EQ(h, level_size(200, 72, l).height);
            ASSERT_EQ(levels[size_t(l)].rgba, fitted) << "lobe " << lobe << " level " << l;
        }
    }
    // `ndfbake info` (ndfb_describe_image) names the levels, their sizes and the slot.
    size_t length = 0;
    ASSERT_EQ(ndfb_describe_image(ctx_, mip_file(out, 2).c_str(), nullptr, 0, &length), NDFB_OK);
    std::string text(length + 1, '\0');
    ASSERT_EQ(ndfb_describe_image(ctx_, mip_file(out, 2).c_str(), text.data(), text.size(), nullptr), NDFB_OK);
    for (const char* line : {"MIP levels: 9\n", "  level 0: 200x72\n", "  level 1: 100x36\n", "  level 8: 1x1\n",
                             "lobe slot: 2 of 4 (0-based)\n", "tiles: 64x64\n", "fitted levels: 9 of 9\n"})
        EXPECT_NE(text.find(line), std::string::npos) << line << " in\n" << text;
}

TEST_F(MipFileBake, LevelsPastTheFittedOnesAreFootprintWeightedAverages)
{
    const std::string input = synth_file(Pattern::bumps, 24, 20, "bumps.png");
    const std::string out = path("out");
    write_.mipmap = 1;
    write_.precision = NDFB_PRECISION_FLOAT;
    fit_.max_levels = 2;
    fit_.wrap = NDFB_WRAP_CLAMP;
    ASSERT_EQ(ndfb_bake(ctx_, input.c_str(), out.c_str(), &decode_, &fit_, &write_, nullptr, nullptr, nullptr), NDFB_OK) << ndfb_last_error(ctx_);
    OIIO::ImageSpec spec;
    const std::vector<Level> levels = read_mip_levels(mip_file(out, 0), &spec);
    ASSERT_EQ(levels.size(), 6u);  // 24x20, 12x10, 6x5, 3x3, 2x2, 1x1
    EXPECT_EQ(spec.get_int_attribute("ndfbake:fitted_levels"), 2);
    EXPECT_EQ(spec.get_int_attribute("ndfbake:mip_levels"), 6);
    for (int l = 0; l < 2; ++l) {
        int w = 0, h = 0;
        EXPECT_EQ(levels[size_t(l)].rgba, read_rgba_exr(level_file(out, l, 0), w, h));
    }
    // Level 2 (6x5) from level 1: exact halves, equal weights. Each texel below is weighted by
    // the fine texels it covers: clamp mode, 24 x 20 fine texels.
    const auto texel = [&](const Level& l, int x, int y, int c) {
        return l.rgba[(size_t(y) * size_t(l.width) + size_t(x)) * 4 + size_t(c)];
    };
    const Level &l1 = levels[1], &l2 = levels[2], &l3 = levels[3], &l4 = levels[4], &l5 = levels[5];
    for (int c = 0; c < 4; ++c) {
        EXPECT_NEAR(texel(l2, 1, 2, c),
                    0.25f * (texel(l1, 2, 4, c) + texel(l1, 3, 4, c) + texel(l1, 2, 5, c) + texel(l1, 3, 5, c)), 1e-6f);
        // Level 3 (3x3) texel (1, 2) has level-2 texels (2..3, 4) below it (row 5 is past the edge).
        EXPECT_NEAR(texel(l3, 1, 2, c), 0.5f * (texel(l2, 2, 4, c) + texel(l2, 3, 4, c)), 1e-6f);
        // Level 4 (2x2) texel (1, 1) has level-3 texel (2, 2) alone.
        EXPECT_NEAR(texel(l4, 1, 1, c), texel(l3, 2, 2, c), 1e-6f);
        // Level 5 (1x1) from level 4, whose texels cover 16x16, 8x16, 16x4 and 8x4 fine texels.
        const float expected = (256 * texel(l4, 0, 0, c) + 128 * texel(l4, 1, 0, c) + 64 * texel(l4, 0, 1, c) +
                                32 * texel(l4, 1, 1, c)) / 480.0f;
        EXPECT_NEAR(texel(l5, 0, 0, c), expected, 1e-6f);
    }
}

// OpenImageIO's texture system (what Cycles' OSL texture() calls): a trilinear lookup with a
// footprint one texel of level L wide, at the centre of a texel of level L, returns that texel of
// the fitted level L.
TEST_F(MipFileBake, TheTextureSystemsTrilinearLookupAtAFittedLevelsTexelReturnsIt)
{
    const std::string input = synth_file(Pattern::fbm, 64, 64, "fbm.png");
    const std::string out = path("out");
    write_.mipmap = 1;
    write_.precision = NDFB_PRECISION_FLOAT;
    ASSERT_EQ(ndfb_bake(ctx_, input.c_str(), out.c_str(), &decode_, &fit_, &write_, nullptr, nullptr, nullptr), NDFB_OK) << ndfb_last_error(ctx_);
    // The shared texture system, never destroyed here: OpenImageIO 2.4's TextureSystem::destroy
    // deletes through the base class with a sized delete, which AddressSanitizer reports as a
    // new-delete-type-mismatch inside OpenImageIO.
    OIIO::TextureSystem* ts = OIIO::TextureSystem::create(true);
    ts->attribute("automip", 0);
    const std::string file = mip_file(out, 1);
    const OIIO::ustring name(file);
    int resolution[2] = {0, 0};
    ASSERT_TRUE(ts->get_texture_info(name, 0, OIIO::ustring("resolution"), OIIO::TypeDesc(OIIO::TypeDesc::INT, 2),
                                     resolution));
    EXPECT_EQ(resolution[0], 64);
    int checked = 0;
    for (int l = 1; l <= 5; ++l) {
        int w = 0, h = 0;
        const std::vector<float> fitted = read_rgba_exr(level_file(out, l, 1), w, h);
        ASSERT_EQ(w, 64 >> l);
        for (const auto& [x, y] : std::vector<std::pair<int, int>>{{0, 0}, {w / 2, h / 3}, {w - 1, h - 1}}) {
            OIIO::TextureOpt opt;
            opt.mipmode = OIIO::TextureOpt::MipModeTrilinear;
            opt.interpmode = OIIO::TextureOpt::InterpBilinear;
            opt.swrap = opt.twrap = OIIO::TextureOpt::WrapPeriodic;
            const float s = (float(x) + 0.5f) / float(w), t = (float(y) + 0.5f) / float(h);  // t down, row 0 on top
            const float texel = 1.0f / float(w);
            float result[4] = {0, 0, 0, 0};
            ASSERT_TRUE(ts->texture(name, opt, s, t, texel, 0.0f, 0.0f, texel, 4, result)) << ts->geterror();
            for (int c = 0; c < 4; ++c) {
                EXPECT_NEAR(result[c], fitted[(size_t(y) * size_t(w) + size_t(x)) * 4 + size_t(c)], 2e-5f)
                    << "level " << l << " texel " << x << "," << y << " channel " << c;
                ++checked;
            }
        }
    }
    EXPECT_EQ(checked, 5 * 3 * 4);
    ts->invalidate(name);
}

}  // namespace
}  // namespace ndfbake
