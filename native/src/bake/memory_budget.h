// How much memory a bake will hold at its peak, computed from the image header and the settings
// before any pixel is read, so that a map too large for the memory the user allows is refused up
// front instead of failing (or being killed, with the host application) half-way.
#pragma once

#include <cstdint>
#include <string>

#include "bake/write_settings.h"
#include "pyramid/lobe_pyramid.h"

namespace ndfbake {

// What the input file holds per pixel; a bake from memory or an already decoded map has none.
struct SourceLayout {
    int channels = 0;       // 0: no file to decode
    int sample_bytes = 0;   // bytes per stored sample (1, 2, 4; half = 2)
    bool float_samples = false;
};

// The peak of the stages of a bake, in bytes: decoding (file samples, OpenImageIO's own copy and
// the normals), fitting (the map, the pyramid's copy of it, every level's lobes, and the largest
// footprint the worker threads gather and hand to EM at once), writing (one level-0 texture in
// float and as converted for the file, the colour textures, one lobe's atlas). Allocator overhead
// and the process's own baseline (libraries) are not included.
struct MemoryEstimate {
    uint64_t decode = 0, fit = 0, write = 0;
    uint64_t peak() const;
};

MemoryEstimate estimate_bake_memory(int width, int height, const SourceLayout& source,
                                    const PyramidSettings& settings, const WriteSettings& write);

// The limit in force: `requested`, or the machine's physical memory when it is 0.
uint64_t effective_memory_limit(uint64_t requested);

// Throws Error(out_of_memory) naming `what`, the estimate and the limit when the estimate's peak
// is above the limit.
void check_memory_budget(const MemoryEstimate& estimate, uint64_t requested_limit, int width, int height,
                         int slots, const std::string& what);

// The process's peak resident set so far, in bytes (platform/memory.h: peak_resident_bytes).
uint64_t process_peak_memory();

}  // namespace ndfbake
