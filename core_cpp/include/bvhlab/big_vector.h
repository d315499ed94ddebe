// big_vector.h — std::vector for the large arrays of a build (references, nodes, leaf geometry).
// Blocks of 2 MiB and more come from a cache of freed blocks (big_blocks.cpp), so that a build
// reuses the scratch memory of the last one: fresh memory costs a page fault per page and its
// zeroing in the kernel. Elements are not zeroed on resize (every slot is written before it is
// read). There are no huge-page hints (MADV_HUGEPAGE): they made the first build's page faults
// cheaper, but when earlier trees stay alive every build needs fresh huge pages, and the kernel's
// compaction to find them made each further build slower (Sponza: +8, +40, +51, +70 ms of system
// time for builds 2-5), the "second build 1.4-1.7× slower" of issue 11.
#pragma once
#include <cstddef>
#include <new>
#include <utility>
#include <vector>

namespace bvhlab {

/// A block of `bytes` (a multiple of 2 MiB), 2 MiB aligned: a cached one if any fits, else fresh.
void* allocate_big_block(std::size_t bytes);
/// Returns a block from allocate_big_block, to the cache or, past its limit, to the system.
void free_big_block(void* p, std::size_t bytes) noexcept;

template <class T>
struct BigAllocator {
    using value_type = T;
    static constexpr std::size_t kHuge = std::size_t(2) << 20;

    BigAllocator() = default;
    template <class U>
    BigAllocator(const BigAllocator<U>&) {}

    /// Elements are default-initialised (resize() does not zero what will be overwritten).
    template <class U, class... Args>
    void construct(U* p, Args&&... args) {
        if constexpr (sizeof...(Args) == 0) ::new (static_cast<void*>(p)) U;
        else ::new (static_cast<void*>(p)) U(std::forward<Args>(args)...);
    }

    T* allocate(std::size_t n) {
        std::size_t bytes = n * sizeof(T);
        if (bytes < kHuge) return static_cast<T*>(::operator new(bytes));
        return static_cast<T*>(allocate_big_block((bytes + kHuge - 1) / kHuge * kHuge));
    }
    void deallocate(T* p, std::size_t n) {
        const std::size_t bytes = n * sizeof(T);
        if (bytes < kHuge) ::operator delete(p);
        else free_big_block(p, (bytes + kHuge - 1) / kHuge * kHuge);
    }
    template <class U>
    bool operator==(const BigAllocator<U>&) const {
        return true;
    }
};

template <class T>
using BigVector = std::vector<T, BigAllocator<T>>;

}  // namespace bvhlab
