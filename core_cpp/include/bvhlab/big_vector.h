// big_vector.h — std::vector for the large arrays of a build (references, nodes, leaf geometry).
// Blocks of 16 KiB and more come from a cache of freed blocks (big_blocks.cpp), so that a build
// reuses the scratch memory of the last one: fresh memory costs a page fault per page and its
// zeroing in the kernel. (The node arrays of the subtrees a parallel build hands to its threads
// are below 2 MiB: with fresh memory for them, a two-thread Sponza build took 2,100 page faults
// and 7 ms of system time, against 32 faults on one thread. Their depth arrays, tens of KiB, from
// malloc, which gives a worker's freed memory back to the system: 170 faults a two-thread room1m
// build, most of uniform1m's 384, when the cache began at 256 KiB.) Elements are not zeroed on resize
// (every slot is written before it is read). There are no huge-page hints (MADV_HUGEPAGE): they
// made the first build's page faults cheaper, but when earlier trees stay alive every build needs
// fresh huge pages, and the kernel's compaction to find them made each further build slower
// (Sponza: +8, +40, +51, +70 ms of system time for builds 2-5), the "second build 1.4-1.7×
// slower" of issue 11.
#pragma once
#include <cstddef>
#include <new>
#include <type_traits>
#include <utility>
#include <vector>

namespace bvhlab {

/// What a cached block was last used for: its element type (block_kind<T>). A block goes back
/// only to arrays of its kind. Arrays of some kinds are written whole (references, geometry),
/// of others a part (node arrays are reserved for the largest tree their range can make, 2n - 1,
/// and filled about a third of the way): a block that held nodes, taken for an array written
/// whole, faults in the rest (a two-thread build of room1m: 433 faults, about 1 ms in this VM,
/// when the tree's references took the blocks of the parts' nodes).
using BlockKind = const void*;
template <class T>
inline constexpr char kBlockKindTag = 0;
template <class T>
constexpr BlockKind block_kind() {
    return &kBlockKindTag<T>;
}

/// A block of `bytes` (a size big_block_bytes gives), 4 KiB aligned and 2 MiB aligned from 2 MiB
/// up: a cached one of this kind if any fits, else fresh.
void* allocate_big_block(std::size_t bytes, BlockKind kind);
/// Returns a block from allocate_big_block, to the cache or, past its limit, to the system.
void free_big_block(void* p, std::size_t bytes, BlockKind kind) noexcept;

/// Asks the system to back the whole 2 MiB pages within [p, p + bytes) with huge pages where it
/// can (Linux: MADV_HUGEPAGE; elsewhere nothing). For the long-lived arrays that rays read at
/// random, the wide tree's (make_wide), not for a build's scratch (see above): uniform1m's 60 MB
/// wide tree then takes 30 TLB entries instead of 15,000 (random rays +3.5%, best of interleaved
/// runs; Embree's trees are on huge pages too), and making it takes a third of the page faults
/// (uniform1m 5,600 against 19,000; Sponza 17-19 against 21-24 ms).
void advise_huge_pages(void* p, std::size_t bytes) noexcept;

/// Below this, BigAllocator uses operator new.
inline constexpr std::size_t kBigBlockMin = std::size_t(16) << 10;

/// The block size for a request of `bytes` >= kBigBlockMin: the next power of two below 2 MiB (so
/// that a block freed by one build fits the like request of the next), else a multiple of 2 MiB.
constexpr std::size_t big_block_bytes(std::size_t bytes) {
    constexpr std::size_t kHuge = std::size_t(2) << 20;
    if (bytes >= kHuge) return (bytes + kHuge - 1) / kHuge * kHuge;
    std::size_t size = kBigBlockMin;
    while (size < bytes) size *= 2;
    return size;
}

/// True for types whose BigVector elements every user writes whole before reading them, so that
/// BigVector(n) and resize(n) need not run their default member initialisers (as they run none
/// for trivial types). Only for implicit-lifetime types (aggregates: C++20's P0593), which the
/// allocation itself creates. Specialised next to the type, in the header that every user of
/// such a BigVector includes.
template <class T>
struct WrittenBeforeRead : std::false_type {};

template <class T>
struct BigAllocator {
    using value_type = T;

    BigAllocator() = default;
    template <class U>
    BigAllocator(const BigAllocator<U>&) {}

    /// Elements are default-initialised (resize() does not zero what will be overwritten).
    template <class U, class... Args>
    void construct(U* p, Args&&... args) {
        if constexpr (sizeof...(Args) == 0 && WrittenBeforeRead<U>::value) static_assert(std::is_aggregate_v<U>);
        else if constexpr (sizeof...(Args) == 0) ::new (static_cast<void*>(p)) U;
        else ::new (static_cast<void*>(p)) U(std::forward<Args>(args)...);
    }

    T* allocate(std::size_t n) {
        const std::size_t bytes = n * sizeof(T);
        if (bytes < kBigBlockMin) return static_cast<T*>(::operator new(bytes, std::align_val_t(alignof(T))));
        return static_cast<T*>(allocate_big_block(big_block_bytes(bytes), block_kind<T>()));
    }
    void deallocate(T* p, std::size_t n) {
        const std::size_t bytes = n * sizeof(T);
        if (bytes < kBigBlockMin) ::operator delete(p, std::align_val_t(alignof(T)));  // WideNode: 64
        else free_big_block(p, big_block_bytes(bytes), block_kind<T>());
    }
    template <class U>
    bool operator==(const BigAllocator<U>&) const {
        return true;
    }
};

template <class T>
using BigVector = std::vector<T, BigAllocator<T>>;

}  // namespace bvhlab
