// Row-parallel loops with progress and cancellation reported on the calling thread.
#pragma once

#include <functional>

namespace ndfbake {

// Called on the caller's thread with the fraction done in [0, 1]; returns false to cancel.
using ProgressTick = std::function<bool(double fraction)>;

// Runs body(row) for every row in [0, rows) on `threads` workers (0: all cores). The calling
// thread only reports progress (so callbacks into Python stay on the thread that called us):
// tick(0) before any row, tick(rows done / rows) about every 50 ms while rows run, and tick(1)
// once every row is done, so that a loop is always reported however fast it finishes.
// Throws Error(cancelled) when tick returns false (the first tick: before any row runs; a later
// one: after the workers have stopped); rethrows the first exception a worker raised (then no
// final tick).
void parallel_rows(int rows, int threads, const std::function<void(int row)>& body,
                   const ProgressTick& tick);

int resolve_thread_count(int requested);

}  // namespace ndfbake
