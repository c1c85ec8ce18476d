// Chunked parallel loop over an index range, built on the project's parallel_rows so thread
// counts and exception propagation behave the same everywhere in the library.
#pragma once

#include <algorithm>
#include <cstddef>
#include <functional>

#include "pyramid/parallel.h"

namespace ndfbake {

// Calls body(begin, end) on disjoint sub-ranges covering [0, count). Small ranges run inline:
// starting threads costs more than a few thousand cheap iterations.
inline void parallel_for(size_t count, int threads, size_t grain, const std::function<void(size_t, size_t)>& body)
{
    if (count == 0) return;
    grain = std::max<size_t>(grain, 1);
    const int workers = resolve_thread_count(threads);
    if (workers <= 1 || count <= grain) {
        body(0, count);
        return;
    }
    // A few chunks per worker balance uneven work without many scheduling round trips.
    const size_t chunks = std::min((count + grain - 1) / grain, size_t(workers) * 8);
    const size_t step = (count + chunks - 1) / chunks;
    parallel_rows(int((count + step - 1) / step), workers,
                  [&](int chunk) {
                      const size_t begin = size_t(chunk) * step;
                      body(begin, std::min(count, begin + step));
                  },
                  {});
}

}  // namespace ndfbake
