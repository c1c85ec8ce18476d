// A vector whose resize() leaves new elements unwritten, for arrays that their writers fill
// completely before anyone reads them.
#pragma once

#include <memory>
#include <type_traits>
#include <utility>
#include <vector>

namespace ndfbake {

// std::allocator, except that constructing an element without arguments does nothing: resize()
// then allocates without touching the memory, and the threads that later write each part of it
// are the first to touch (page in) that part, in parallel. Only for implicit-lifetime element
// types, which allocation alone brings to life.
template <class T>
struct UnfilledAllocator : std::allocator<T> {
    static_assert(std::is_trivially_copyable_v<T> && std::is_trivially_destructible_v<T>);
    template <class U>
    struct rebind {
        using other = UnfilledAllocator<U>;
    };
    UnfilledAllocator() = default;
    template <class U>
    UnfilledAllocator(const UnfilledAllocator<U>&) noexcept {}

    template <class U>
    void construct(U*) noexcept {}
    template <class U, class... Args>
    void construct(U* p, Args&&... args)
    {
        ::new (static_cast<void*>(p)) U(std::forward<Args>(args)...);
    }
};

template <class T>
using UnfilledVector = std::vector<T, UnfilledAllocator<T>>;

}  // namespace ndfbake
