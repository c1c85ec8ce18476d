// The benchmark end to end on small maps: every requested row present, finite, and ranked as the
// fitting tests establish (four lobes beat Toksvig), with its files written.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "bench/benchmark.h"
#include "error.h"
#include "synth/patterns.h"
#include "test_support.h"

namespace ndfbake {
namespace {

class Bench : public testing_support::TempDirTest {};

TEST_F(Bench, MeasuresEveryMethodOnTheSameFootprints)
{
    BenchSettings settings;
    settings.maps = {{"weave", synthesize(Pattern::weave, 32, 32)}, {"fbm", synthesize(Pattern::fbm, 32, 32)}};
    settings.methods = {"bake-default", "vmf-4", "toksvig", "lean", "xu-2x4", "sh-4"};
    settings.brdfs = {BaseBrdf::ggx(0.4f)};
    settings.levels = {2, 4};
    settings.texels_per_level = 8;
    const std::vector<BenchRow> rows = run_benchmark(settings, path("out"), {});
    ASSERT_EQ(rows.size(), 2u * 6u * 2u);
    double vmf = 0.0, toksvig = 0.0;
    for (const BenchRow& r : rows) {
        EXPECT_TRUE(std::isfinite(r.mean_error) && r.mean_error >= 0.0) << r.method;
        EXPECT_GE(r.p95_error, 0.0);
        EXPECT_GT(r.floats_per_texel, 0.0);
        if (r.method == "vmf-4") vmf += r.mean_error;
        if (r.method == "toksvig") toksvig += r.mean_error;
    }
    EXPECT_LT(vmf, toksvig);
    for (const char* file : {"bench.csv", "bench.md", "heatmap_bake-default_level2.png", "heatmap_toksvig_level4.png"})
        EXPECT_TRUE(std::filesystem::exists(path("out") + "/" + file)) << file;
    std::ifstream csv(path("out") + "/bench.csv");
    int lines = 0;
    for (std::string line; std::getline(csv, line);) ++lines;
    EXPECT_EQ(lines, 1 + int(rows.size()));
}

TEST_F(Bench, ACancelledRunWritesNothing)
{
    // Cancelled after the first method: no heat map, table or folder (new, and nested) is left.
    BenchSettings settings;
    settings.maps = {{"fbm", synthesize(Pattern::fbm, 16, 16)}};
    settings.methods = {"bake-default", "toksvig"};
    settings.brdfs = {BaseBrdf::ggx(0.4f)};
    settings.levels = {2};
    const std::string out = path("new") + "/out";
    EXPECT_THROW(run_benchmark(settings, out, [](const std::string&) { return false; }), Error);
    EXPECT_FALSE(std::filesystem::exists(path("new"))) << "left: " << ::testing::PrintToString(listing(path("new")));
}

TEST_F(Bench, RejectsUnknownMethods)
{
    BenchSettings settings;
    settings.maps = {{"fbm", synthesize(Pattern::fbm, 8, 8)}};
    settings.methods = {"vmf-99"};
    settings.brdfs = {BaseBrdf::ggx(0.4f)};
    settings.levels = {1};
    EXPECT_THROW(run_benchmark(settings, path("out"), {}), Error);
}

}  // namespace
}  // namespace ndfbake
