#include "pyramid/parallel.h"

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <exception>
#include <mutex>
#include <thread>
#include <vector>

#include "error.h"

namespace ndfbake {

namespace {
// How often the caller's progress callback runs: often enough for a responsive Esc in Blender.
constexpr std::chrono::milliseconds kProgressInterval{50};
}  // namespace

int resolve_thread_count(int requested)
{
    if (requested > 0) return requested;
    const unsigned hardware = std::thread::hardware_concurrency();
    return hardware > 0 ? int(hardware) : 1;
}

void parallel_rows(int rows, int threads, const std::function<void(int)>& body, const ProgressTick& tick)
{
    std::atomic<int> next_row{0};
    std::atomic<int> rows_done{0};
    std::atomic<bool> stop{false};
    std::exception_ptr failure;
    std::mutex mutex;
    std::condition_variable finished;
    int workers_running = std::min(resolve_thread_count(threads), std::max(rows, 1));

    auto worker = [&] {
        for (;;) {
            if (stop.load(std::memory_order_relaxed)) break;
            const int row = next_row.fetch_add(1);
            if (row >= rows) break;
            try {
                body(row);
            } catch (...) {
                std::lock_guard lock(mutex);
                if (!failure) failure = std::current_exception();
                stop = true;
            }
            rows_done.fetch_add(1);
        }
        std::lock_guard lock(mutex);
        if (--workers_running == 0) finished.notify_all();
    };

    // Every loop with a tick reports 0 before any row and 1 after the last, whatever the timing:
    // a stage that finishes within the first interval is still seen (a progress bar, the
    // add-on's stage label), and each of these calls may cancel like the throttled ones.
    if (tick && !tick(0.0)) throw Error(Status::cancelled, "cancelled");

    std::vector<std::jthread> pool;
    const int pool_size = workers_running;
    pool.reserve(size_t(pool_size));
    for (int i = 0; i < pool_size; ++i) pool.emplace_back(worker);

    bool cancelled = false;
    {
        std::unique_lock lock(mutex);
        auto next_tick = std::chrono::steady_clock::now() + kProgressInterval;
        for (;;) {
            if (finished.wait_until(lock, next_tick, [&] { return workers_running == 0; })) break;
            next_tick = std::chrono::steady_clock::now() + kProgressInterval;
            if (!tick || cancelled) continue;
            lock.unlock();
            const bool keep_going = tick(rows > 0 ? double(rows_done.load()) / rows : 1.0);
            lock.lock();
            if (!keep_going) {
                cancelled = true;
                stop = true;
            }
        }
    }
    pool.clear();  // joins
    if (failure) std::rethrow_exception(failure);
    if (cancelled) throw Error(Status::cancelled, "cancelled");
    if (tick && !tick(1.0)) throw Error(Status::cancelled, "cancelled");
}

}  // namespace ndfbake
