// Concurrency through the public C API (issue 6): two bakes at once on two contexts give the same
// files as one at a time, a cancel from a third thread (a shared atomic flag the progress callback
// reads) stops them cleanly, and contexts keep their errors to themselves. Run under the
// sanitizer build too (build-asan), where a race that corrupts memory would be reported.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <cstring>
#include <fstream>
#include <map>
#include <string>
#include <thread>
#include <vector>

#include "io/image_files.h"
#include "io/lobe_exr.h"
#include "io/normal_encode.h"
#include "ndfbake.h"
#include "synth/patterns.h"
#include "test_support.h"

namespace ndfbake {
namespace {

namespace fs = std::filesystem;

using testing_support::read_bytes;

// What one bake's progress callback sees and obeys.
struct BakeWatch {
    const std::atomic<bool>* cancel = nullptr;  // null: this bake ignores the flag
    std::atomic<bool> fitting{false};
    std::atomic<int> calls{0};
};

int watch_progress(void* user, const char* stage, float fraction)
{
    auto* watch = static_cast<BakeWatch*>(user);
    ++watch->calls;
    EXPECT_TRUE(fraction >= 0.0f && fraction <= 1.0f) << stage << " " << fraction;
    if (std::strcmp(stage, "fit") == 0) watch->fitting = true;
    return watch->cancel && watch->cancel->load() ? 1 : 0;
}

class Concurrency : public testing_support::TempDirTest {
protected:
    std::string synth_png(const std::string& name, Pattern pattern, int width, int height)
    {
        write_normal_map(path(name), synthesize(pattern, width, height));
        return path(name);
    }

    // One bake on a context of its own, as an add-on thread would run it.
    static ndfb_status bake(const std::string& input, const std::string& out, BakeWatch* watch, std::string* error,
                            uint32_t max_lobes = 3)
    {
        ndfb_context ctx = nullptr;
        if (ndfb_context_create(&ctx) != NDFB_OK) return NDFB_ERROR_INTERNAL;
        ndfb_fit_options fit;
        ndfb_fit_options_init(&fit);
        fit.max_lobes = max_lobes;
        fit.threads = 2;
        const ndfb_status status = ndfb_bake(ctx, input.c_str(), out.c_str(), nullptr, &fit, nullptr,
                                             watch ? watch_progress : nullptr, watch, nullptr);
        if (error) *error = ndfb_last_error(ctx);
        ndfb_context_destroy(ctx);
        return status;
    }

    // The pixels of a bake folder's EXR files, by name (the files' headers hold a capture date,
    // report.json timings: neither is compared).
    static std::map<std::string, std::vector<float>> exr_files(const std::string& folder)
    {
        std::map<std::string, std::vector<float>> files;
        for (const auto& e : fs::directory_iterator(folder))
            if (e.path().extension() == ".exr") {
                int width = 0, height = 0;
                files[e.path().filename().string()] = read_rgba_exr(e.path().string(), width, height);
            }
        return files;
    }

    // Nothing but finished bake files: no staging folder, temporary or probe.
    static void expect_only_bake_files(const std::string& folder)
    {
        for (const std::string& entry : listing(folder))
            EXPECT_EQ(fs::path(entry).filename().string().rfind('.', 0), std::string::npos) << entry;
    }
};

TEST_F(Concurrency, TwoBakesInParallelGiveTheSameFilesAsOneAtATime)
{
    const std::string a = synth_png("a.png", Pattern::weave, 64, 64);
    const std::string b = synth_png("b.png", Pattern::scratches, 48, 32);
    ASSERT_EQ(bake(a, path("serial-a"), nullptr, nullptr), NDFB_OK);
    ASSERT_EQ(bake(b, path("serial-b"), nullptr, nullptr), NDFB_OK);

    BakeWatch watch_a, watch_b;
    std::string error_a, error_b;
    ndfb_status status_a = NDFB_ERROR_INTERNAL, status_b = NDFB_ERROR_INTERNAL;
    std::thread ta([&] { status_a = bake(a, path("parallel-a"), &watch_a, &error_a); });
    std::thread tb([&] { status_b = bake(b, path("parallel-b"), &watch_b, &error_b); });
    ta.join();
    tb.join();
    ASSERT_EQ(status_a, NDFB_OK) << error_a;
    ASSERT_EQ(status_b, NDFB_OK) << error_b;
    EXPECT_GT(watch_a.calls.load(), 0);
    EXPECT_GT(watch_b.calls.load(), 0);
    EXPECT_EQ(exr_files(path("parallel-a")), exr_files(path("serial-a")));
    EXPECT_EQ(exr_files(path("parallel-b")), exr_files(path("serial-b")));
    expect_only_bake_files(path("parallel-a"));
    expect_only_bake_files(path("parallel-b"));
}

TEST_F(Concurrency, ACancelFromAThirdThreadStopsBothBakesAndLeavesTheirFoldersAsTheyWere)
{
    const std::string earlier = synth_png("earlier.png", Pattern::bumps, 8, 8);
    const std::string a = synth_png("a.png", Pattern::weave, 256, 256);
    const std::string b = synth_png("b.png", Pattern::fbm, 256, 128);
    // Each folder holds an earlier bake that must survive the cancelled one.
    ASSERT_EQ(bake(earlier, path("out-a"), nullptr, nullptr, 2), NDFB_OK);
    ASSERT_EQ(bake(earlier, path("out-b"), nullptr, nullptr, 2), NDFB_OK);
    const auto before_a = listing(path("out-a")), before_b = listing(path("out-b"));
    const std::string report_a = read_bytes(path("out-a/report.json"));

    std::atomic<bool> cancel{false};
    BakeWatch watch_a, watch_b;
    watch_a.cancel = watch_b.cancel = &cancel;
    std::string error_a, error_b;
    ndfb_status status_a = NDFB_OK, status_b = NDFB_OK;
    std::thread ta([&] { status_a = bake(a, path("out-a"), &watch_a, &error_a, 4); });
    std::thread tb([&] { status_b = bake(b, path("out-b"), &watch_b, &error_b, 4); });
    std::thread canceller([&] {
        // Once both are fitting (or after a minute, so a failure cannot hang the suite).
        const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(60);
        while (!(watch_a.fitting && watch_b.fitting) && std::chrono::steady_clock::now() < deadline)
            std::this_thread::sleep_for(std::chrono::milliseconds(5));
        cancel = true;
    });
    ta.join();
    tb.join();
    canceller.join();
    EXPECT_TRUE(watch_a.fitting && watch_b.fitting);
    EXPECT_EQ(status_a, NDFB_ERROR_CANCELLED) << error_a;
    EXPECT_EQ(status_b, NDFB_ERROR_CANCELLED) << error_b;
    EXPECT_EQ(error_a, "cancelled");
    EXPECT_EQ(listing(path("out-a")), before_a);
    EXPECT_EQ(listing(path("out-b")), before_b);
    EXPECT_EQ(read_bytes(path("out-a/report.json")), report_a);
}

TEST_F(Concurrency, ACancelReachesOnlyTheBakeThatReadsTheFlag)
{
    const std::string a = synth_png("a.png", Pattern::weave, 128, 128);
    const std::string b = synth_png("b.png", Pattern::bumps, 32, 32);
    ASSERT_EQ(bake(b, path("serial-b"), nullptr, nullptr), NDFB_OK);

    std::atomic<bool> cancel{false};
    BakeWatch watch_a, watch_b;  // b ignores the flag
    watch_a.cancel = &cancel;
    ndfb_status status_a = NDFB_OK, status_b = NDFB_ERROR_INTERNAL;
    std::string error_a, error_b;
    std::thread ta([&] { status_a = bake(a, path("out-a"), &watch_a, &error_a, 4); });
    std::thread tb([&] { status_b = bake(b, path("out-b"), &watch_b, &error_b); });
    std::thread canceller([&] {
        const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(60);
        while (!watch_a.fitting && std::chrono::steady_clock::now() < deadline)
            std::this_thread::sleep_for(std::chrono::milliseconds(5));
        cancel = true;
    });
    ta.join();
    tb.join();
    canceller.join();
    EXPECT_EQ(status_a, NDFB_ERROR_CANCELLED) << error_a;
    EXPECT_TRUE(listing(path("out-a")).empty());
    ASSERT_EQ(status_b, NDFB_OK) << error_b;
    EXPECT_EQ(exr_files(path("out-b")), exr_files(path("serial-b")));
}

TEST_F(Concurrency, TwoBakesIntoOneFolderBothFinishAndLeaveOneWholeBake)
{
    const std::string input = synth_png("in.png", Pattern::fbm, 32, 32);
    ASSERT_EQ(bake(input, path("serial"), nullptr, nullptr), NDFB_OK);
    std::string error_a, error_b;
    ndfb_status status_a = NDFB_ERROR_INTERNAL, status_b = NDFB_ERROR_INTERNAL;
    std::thread ta([&] { status_a = bake(input, path("shared"), nullptr, &error_a); });
    std::thread tb([&] { status_b = bake(input, path("shared"), nullptr, &error_b); });
    ta.join();
    tb.join();
    EXPECT_EQ(status_a, NDFB_OK) << error_a;
    EXPECT_EQ(status_b, NDFB_OK) << error_b;
    EXPECT_EQ(exr_files(path("shared")), exr_files(path("serial")));
    EXPECT_TRUE(fs::exists(path("shared/report.json")));
    expect_only_bake_files(path("shared"));
}

TEST_F(Concurrency, ContextsKeepTheirOwnErrorsAndComeAndGoFromManyThreads)
{
    const std::string good = synth_png("good.png", Pattern::bumps, 8, 8);
    std::atomic<int> wrong{0};
    std::vector<std::thread> threads;
    for (int t = 0; t < 4; ++t)
        threads.emplace_back([&, t] {
            for (int i = 0; i < 50; ++i) {
                ndfb_context ctx = nullptr;
                if (ndfb_context_create(&ctx) != NDFB_OK) {
                    ++wrong;
                    continue;
                }
                // Odd threads fail on a file of their own; even ones succeed.
                const std::string missing = path("missing-" + std::to_string(t) + ".png");
                ndfb_normal_map map = nullptr;
                const bool fail = t % 2 == 1;
                const ndfb_status s =
                    ndfb_normal_map_load(ctx, (fail ? missing : good).c_str(), nullptr, &map);
                const std::string message = ndfb_last_error(ctx);
                if (fail ? (s != NDFB_ERROR_FILE_NOT_FOUND || message.find(missing) == std::string::npos)
                         : (s != NDFB_OK || !message.empty()))
                    ++wrong;
                ndfb_normal_map_destroy(map);
                ndfb_context_destroy(ctx);
            }
        });
    for (std::thread& t : threads) t.join();
    EXPECT_EQ(wrong.load(), 0);
}

}  // namespace
}  // namespace ndfbake
