// The MIP atlas: layout, frames that make bilinear filtering exact up to a level's edges (checked
// with the addressing the add-on's node group uses), and the atlas files a bake writes.
#include <gtest/gtest.h>

#include <cctype>
#include <cmath>
#include <fstream>
#include <random>

#include "bake/lobe_atlas.h"
#include "io/image_files.h"
#include "io/lobe_exr.h"
#include "ndfbake.h"
#include "synth/patterns.h"
#include "test_support.h"

namespace ndfbake {
namespace {

TEST(LobeAtlas, LevelZeroOnTheLeftAndTheOthersStackedInAColumn)
{
    const std::vector<LevelSize> sizes = {{8, 4}, {4, 2}, {2, 1}, {1, 1}};
    const AtlasLayout layout = atlas_layout(sizes);
    ASSERT_EQ(layout.levels.size(), 4u);
    EXPECT_EQ(layout.width, 10 + 6);
    EXPECT_EQ(layout.height, 4 + 3 + 3);  // the column (4 + 3 + 3 rows) is taller than level 0 (6)
    const int expected[4][2] = {{0, 0}, {10, 0}, {10, 4}, {10, 7}};
    for (size_t l = 0; l < 4; ++l) {
        EXPECT_EQ(layout.levels[l].x, expected[l][0]);
        EXPECT_EQ(layout.levels[l].y, expected[l][1]);
        EXPECT_EQ(layout.levels[l].width, sizes[l].width);
    }
}

// Bilinear filtering of a level at (u, v) as a renderer does it on the level alone (v up,
// texel centres at half-integers), with repeat or clamp addressing.
float level_bilinear(const std::vector<float>& rgba, int w, int h, float u, float v, int channel, WrapMode wrap)
{
    const float x = u * float(w) - 0.5f, y_up = v * float(h) - 0.5f;
    const int x0 = int(std::floor(x)), y0 = int(std::floor(y_up));
    const float fx = x - float(x0), fy = y_up - float(y0);
    auto texel = [&](int xi, int yi_up) {
        xi = wrap == WrapMode::wrap ? (xi % w + w) % w : std::clamp(xi, 0, w - 1);
        yi_up = wrap == WrapMode::wrap ? (yi_up % h + h) % h : std::clamp(yi_up, 0, h - 1);
        const int row = h - 1 - yi_up;  // top row first in memory
        return rgba[(size_t(row) * size_t(w) + size_t(xi)) * 4 + size_t(channel)];
    };
    return (1 - fy) * ((1 - fx) * texel(x0, y0) + fx * texel(x0 + 1, y0)) +
           fy * ((1 - fx) * texel(x0, y0 + 1) + fx * texel(x0 + 1, y0 + 1));
}

// The node group's addressing (addon/ndfbake/shading/nodes.py, atlas_taps): wrap u, v into the level,
// then four point lookups at atlas texel centres, rows counted up from the atlas bottom.
float atlas_bilinear(const std::vector<float>& atlas, const AtlasLayout& layout, int level, float u, float v,
                     int channel, WrapMode wrap)
{
    const AtlasLevel& p = layout.levels[size_t(level)];
    if (wrap == WrapMode::wrap) {
        u -= std::floor(u);
        v -= std::floor(v);
    } else {
        u = std::clamp(u, 0.0f, 1.0f);
        v = std::clamp(v, 0.0f, 1.0f);
    }
    const float x = u * float(p.width) - 0.5f, y_up = v * float(p.height) - 0.5f;
    const float x0 = std::floor(x), y0 = std::floor(y_up);
    const float fx = x - x0, fy = y_up - y0;
    auto lookup = [&](float xi, float yi_up) {
        const float column = float(p.x + 1) + xi;
        const float row_up = float(layout.height - 1 - p.y - p.height) + yi_up;
        // The point lookup a renderer makes at the texel centre (column + 0.5, row_up + 0.5) / size.
        const int c = int(std::floor((column + 0.5f) / float(layout.width) * float(layout.width)));
        const int r_up = int(std::floor((row_up + 0.5f) / float(layout.height) * float(layout.height)));
        const int row = layout.height - 1 - r_up;
        return atlas[(size_t(row) * size_t(layout.width) + size_t(c)) * 4 + size_t(channel)];
    };
    return (1 - fy) * ((1 - fx) * lookup(x0, y0) + fx * lookup(x0 + 1, y0)) +
           fy * ((1 - fx) * lookup(x0, y0 + 1) + fx * lookup(x0 + 1, y0 + 1));
}

TEST(LobeAtlas, BilinearLookupsInTheAtlasEqualFilteringTheLevelAloneUpToItsEdges)
{
    const std::vector<LevelSize> sizes = {{16, 8}, {8, 4}, {4, 2}, {2, 1}, {1, 1}};
    const AtlasLayout layout = atlas_layout(sizes);
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> value(-1.0f, 1.0f), coordinate(-1.5f, 2.5f);
    for (WrapMode wrap : {WrapMode::wrap, WrapMode::clamp}) {
        std::vector<std::vector<float>> levels;
        std::vector<float> atlas(size_t(layout.width) * size_t(layout.height) * 4, 0.0f);
        for (size_t l = 0; l < sizes.size(); ++l) {
            levels.emplace_back(size_t(sizes[l].width) * size_t(sizes[l].height) * 4);
            for (float& v : levels.back()) v = value(rng);
            place_atlas_level(layout, int(l), levels.back().data(), wrap, atlas);
        }
        for (int trial = 0; trial < 2000; ++trial) {
            const int l = trial % int(sizes.size());
            const float u = coordinate(rng), v = coordinate(rng);
            const int channel = trial % 4;
            EXPECT_NEAR(atlas_bilinear(atlas, layout, l, u, v, channel, wrap),
                        level_bilinear(levels[size_t(l)], sizes[size_t(l)].width, sizes[size_t(l)].height, u, v,
                                       channel, wrap),
                        1e-5f)
                << "level " << l << " at (" << u << ", " << v << ")";
        }
    }
}

class LobeAtlasBake : public testing_support::CApiTest {};

TEST_F(LobeAtlasBake, TheAtlasHoldsEveryLevelFileAndTheReportGivesItsLayout)
{
    const std::string input = synth_file(Pattern::weave, 32, 16, "weave.png");
    const std::string out = path("out");
    write_.atlas = 1;
    ASSERT_EQ(ndfb_bake(ctx_, input.c_str(), out.c_str(), &decode_, &fit_, &write_, nullptr, nullptr, nullptr), NDFB_OK) << ndfb_last_error(ctx_);
    std::vector<LevelSize> sizes;
    for (int l = 0; l < 6; ++l) sizes.push_back({std::max(1, 32 >> l), std::max(1, 16 >> l)});
    const AtlasLayout layout = atlas_layout(sizes);
    for (int lobe = 0; lobe < 4; ++lobe) {
        int aw = 0, ah = 0;
        const std::vector<float> atlas = read_rgba_exr(out + "/atlas_lobe" + std::to_string(lobe) + ".exr", aw, ah);
        ASSERT_EQ(aw, layout.width);
        ASSERT_EQ(ah, layout.height);
        for (int l = 0; l < 6; ++l) {
            char name[40];
            std::snprintf(name, sizeof name, "/level%02d_lobe%d.exr", l, lobe);
            int w = 0, h = 0;
            const std::vector<float> level = read_rgba_exr(out + name, w, h);
            const AtlasLevel& p = layout.levels[size_t(l)];
            for (int y = 0; y < h; ++y)
                for (int x = 0; x < w; ++x)
                    for (int c = 0; c < 4; ++c)
                        ASSERT_EQ(atlas[(size_t(p.y + 1 + y) * size_t(aw) + size_t(p.x + 1 + x)) * 4 + size_t(c)],
                                  level[(size_t(y) * size_t(w) + size_t(x)) * 4 + size_t(c)])
                            << "lobe " << lobe << " level " << l << " texel " << x << "," << y;
        }
    }
    std::ifstream report(out + "/report.json");
    std::string text((std::istreambuf_iterator<char>(report)), std::istreambuf_iterator<char>());
    std::erase_if(text, [](char c) { return std::isspace(static_cast<unsigned char>(c)); });
    EXPECT_NE(text.find("\"atlas\":{\"width\":" + std::to_string(layout.width) + ",\"height\":" +
                        std::to_string(layout.height)), std::string::npos);
    EXPECT_NE(text.find("{\"x\":34,\"y\":16,\"width\":4,\"height\":2}"), std::string::npos);  // level 3
}

}  // namespace
}  // namespace ndfbake
