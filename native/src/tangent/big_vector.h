// Vectors for the module's large per-corner arrays. A 1M-triangle mesh needs ~200 MB of scratch
// arrays; faulting that in 4 KiB pages costs the kernel about as much time as the whole tangent
// computation, so large blocks come straight from the system in whole 2 MiB units and, where the
// system has them, are marked for transparent huge pages (platform/memory.h). Elements
// are default-initialized (not zeroed) on resize: every array here is written before it is read,
// and zeroing it first would be a second pass over memory.
#pragma once

#include <cstddef>
#include <cstdlib>
#include <memory>
#include <new>
#include <utility>
#include <vector>

#include "platform/memory.h"

namespace ndfbake {

template <typename T>
struct BigAllocator {
    using value_type = T;
    static constexpr size_t kHuge = size_t(2) << 20;

    BigAllocator() = default;
    template <typename U>
    BigAllocator(const BigAllocator<U>&) noexcept {}

    T* allocate(size_t n)
    {
        if (n > size_t(-1) / sizeof(T)) throw std::bad_alloc();
        const size_t bytes = n * sizeof(T);
        if (bytes < kHuge) return std::allocator<T>().allocate(n);
        const size_t rounded = (bytes + kHuge - 1) & ~(kHuge - 1);
        void* p = allocate_pages(rounded);
        if (!p) throw std::bad_alloc();
        return static_cast<T*>(p);
    }
    void deallocate(T* p, size_t n) noexcept
    {
        const size_t bytes = n * sizeof(T);
        if (bytes < kHuge) std::allocator<T>().deallocate(p, n);
        else release_pages(p, (bytes + kHuge - 1) & ~(kHuge - 1));
    }
    template <typename U>
    void construct(U* p) noexcept
    {
        ::new (static_cast<void*>(p)) U;
    }
    template <typename U, typename... Args>
    void construct(U* p, Args&&... args)
    {
        ::new (static_cast<void*>(p)) U(std::forward<Args>(args)...);
    }
    template <typename U>
    bool operator==(const BigAllocator<U>&) const noexcept
    {
        return true;
    }
};

template <typename T>
using BigVector = std::vector<T, BigAllocator<T>>;

}  // namespace ndfbake
