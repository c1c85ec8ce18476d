// Memory facts and large allocations, with one implementation per platform (platform/memory.cpp),
// so that no #ifdef appears elsewhere.
#pragma once

#include <cstddef>
#include <cstdint>

namespace ndfbake {

// The machine's physical memory in bytes; 0 where it cannot be told.
uint64_t physical_memory_bytes();

// The process's peak resident memory so far in bytes (the host application's own included);
// 0 where it cannot be told.
uint64_t peak_resident_bytes();

// `bytes` of zeroed, page-aligned memory straight from the system (not the heap), or null.
// Where the system has transparent huge pages (Linux), the block is marked for them: faulting in
// a few hundred MB of scratch arrays 4 KiB at a time costs about as much as the work on them.
void* allocate_pages(size_t bytes);
// Returns a block of allocate_pages; `bytes` is the size it was allocated with.
void release_pages(void* block, size_t bytes) noexcept;

}  // namespace ndfbake
