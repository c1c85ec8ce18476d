// parallel_rows' progress contract (pyramid/parallel.h), which every stage of a bake reports
// through: 0 before any row, 1 after the last, whatever the timing or the thread count, so that
// a stage finishing within the first progress interval is still seen; and each of those ticks
// may cancel.
#include <gtest/gtest.h>

#include <atomic>
#include <stdexcept>
#include <vector>

#include "error.h"
#include "pyramid/parallel.h"

namespace ndfbake {
namespace {

TEST(ParallelProgress, EveryLoopReportsZeroFirstAndOneLastHoweverFastItRuns)
{
    for (int threads : {1, 2, 8})
        for (int rows : {0, 1, 3, 100}) {
            std::vector<double> ticks;
            std::atomic<int> ran{0};
            parallel_rows(rows, threads, [&](int) { ++ran; }, [&](double fraction) {
                ticks.push_back(fraction);
                return true;
            });
            EXPECT_EQ(ran.load(), rows);
            ASSERT_GE(ticks.size(), 2u) << rows << " rows on " << threads << " threads";
            EXPECT_EQ(ticks.front(), 0.0) << rows << " rows on " << threads << " threads";
            EXPECT_EQ(ticks.back(), 1.0) << rows << " rows on " << threads << " threads";
            for (size_t i = 1; i < ticks.size(); ++i) EXPECT_LE(ticks[i - 1], ticks[i]);
        }
}

TEST(ParallelProgress, NoTickRunsRowsWithoutReporting)
{
    std::atomic<int> ran{0};
    parallel_rows(5, 2, [&](int) { ++ran; }, {});
    EXPECT_EQ(ran.load(), 5);
}

TEST(ParallelProgress, CancelAtTheFirstTickRunsNoRow)
{
    for (int threads : {1, 4}) {
        std::atomic<int> ran{0};
        int ticks = 0;
        try {
            parallel_rows(50, threads, [&](int) { ++ran; }, [&](double) { return ++ticks, false; });
            ADD_FAILURE() << "not cancelled";
        } catch (const Error& e) {
            EXPECT_EQ(e.status(), Status::cancelled);
        }
        EXPECT_EQ(ran.load(), 0);
        EXPECT_EQ(ticks, 1);
    }
}

TEST(ParallelProgress, CancelAtTheLastTickStillCancels)
{
    // The final tick may ask to stop like any other (the bake then leaves nothing behind).
    std::atomic<int> ran{0};
    try {
        parallel_rows(3, 2, [&](int) { ++ran; }, [](double fraction) { return fraction < 1.0; });
        ADD_FAILURE() << "not cancelled";
    } catch (const Error& e) {
        EXPECT_EQ(e.status(), Status::cancelled);
    }
    EXPECT_EQ(ran.load(), 3);
}

TEST(ParallelProgress, AFailedRowIsRethrownWithoutAFinalTick)
{
    // One worker: the first row fails, the others never run, so no tick can reach 1.
    std::vector<double> ticks;
    EXPECT_THROW(parallel_rows(100, 1, [](int row) { if (row == 0) throw std::runtime_error("row 0"); },
                               [&](double fraction) {
                                   ticks.push_back(fraction);
                                   return true;
                               }),
                 std::runtime_error);
    ASSERT_FALSE(ticks.empty());
    EXPECT_EQ(ticks.front(), 0.0);
    for (double fraction : ticks) EXPECT_LT(fraction, 1.0);
}

}  // namespace
}  // namespace ndfbake
