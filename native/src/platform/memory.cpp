#include "platform/memory.h"

#if defined(_WIN32)
#include "platform/windows_api.h"
// After windows.h. K32GetProcessMemoryInfo is KERNEL32's own export (Windows 7 and later):
// the library depends on KERNEL32 and the C runtime only, so not on psapi.dll.
#include <psapi.h>
#else
#include <sys/mman.h>
#include <sys/resource.h>
#include <unistd.h>
#if defined(__APPLE__)
#include <sys/sysctl.h>
#include <sys/types.h>
#endif
#endif

namespace ndfbake {

#if defined(_WIN32)

uint64_t physical_memory_bytes()
{
    MEMORYSTATUSEX status{};
    status.dwLength = sizeof status;
    return GlobalMemoryStatusEx(&status) ? uint64_t(status.ullTotalPhys) : 0;
}

uint64_t peak_resident_bytes()
{
    PROCESS_MEMORY_COUNTERS counters{};
    counters.cb = sizeof counters;
    return K32GetProcessMemoryInfo(GetCurrentProcess(), &counters, sizeof counters)
               ? uint64_t(counters.PeakWorkingSetSize)
               : 0;
}

void* allocate_pages(size_t bytes)
{
    return VirtualAlloc(nullptr, bytes, MEM_RESERVE | MEM_COMMIT, PAGE_READWRITE);
}

void release_pages(void* block, size_t) noexcept { VirtualFree(block, 0, MEM_RELEASE); }

#else  // POSIX: Linux, macOS

uint64_t physical_memory_bytes()
{
#if defined(__APPLE__)
    uint64_t bytes = 0;
    size_t size = sizeof bytes;
    return ::sysctlbyname("hw.memsize", &bytes, &size, nullptr, 0) == 0 ? bytes : 0;
#else
    const long pages = ::sysconf(_SC_PHYS_PAGES), page_size = ::sysconf(_SC_PAGESIZE);
    return pages > 0 && page_size > 0 ? uint64_t(pages) * uint64_t(page_size) : 0;
#endif
}

uint64_t peak_resident_bytes()
{
    struct rusage usage {};
    if (::getrusage(RUSAGE_SELF, &usage) != 0) return 0;
#if defined(__APPLE__)
    return uint64_t(usage.ru_maxrss);  // macOS reports bytes
#else
    return uint64_t(usage.ru_maxrss) * 1024;  // Linux reports KiB
#endif
}

void* allocate_pages(size_t bytes)
{
    void* block = ::mmap(nullptr, bytes, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANON, -1, 0);
    if (block == MAP_FAILED) return nullptr;
#ifdef MADV_HUGEPAGE  // Linux only; advice: without transparent huge pages it is a no-op
    ::madvise(block, bytes, MADV_HUGEPAGE);
#endif
    return block;
}

void release_pages(void* block, size_t bytes) noexcept { ::munmap(block, bytes); }

#endif

}  // namespace ndfbake
