// Row-parallel loops with progress and cancellation reported on the calling thread.
#pragma once

#include <functional>

namespace ndfbake {

// Called on the caller's thread with the fraction done in [0, 1]; returns false to cancel.
using ProgressTick = std::function<bool(double fraction)>;

// Runs body(row) for every row in [0, rows) on `threads` workers (0: all cores). The calling
// thread only reports progress (so callbacks into Python stay on the thread that called us).
// Throws Error(cancelled) when tick returns false, after the workers have stopped; rethrows the
// first exception a worker raised.
void parallel_rows(int rows, int threads, const std::function<void(int row)>& body,
                   const ProgressTick& tick);

int resolve_thread_count(int requested);

}  // namespace ndfbake
