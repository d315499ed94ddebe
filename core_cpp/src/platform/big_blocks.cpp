// big_blocks.cpp — the large blocks behind BigVector, and the cache that lets one build reuse the
// memory of the last instead of faulting in fresh pages (big_vector.h says why that matters).
#include <cstdint>
#include <cstdlib>
#include <mutex>
#include <new>
#include <vector>

#include "bvhlab/big_vector.h"

#if defined(__linux__)
#include <sys/mman.h>
#endif

namespace bvhlab {
namespace {

/// Freed blocks kept for reuse, at most kCacheBytes in all; a request takes the smallest cached
/// block of its kind (BlockKind) that is large enough and not more than 1.5 times too large. A
/// block lent for a smaller request comes back at its own size, not the request's: kept under
/// the smaller size, it would never again serve a request of its own size, which would then take
/// fresh memory.
class BlockCache {
public:
    static constexpr std::size_t kCacheBytes = std::size_t(512) << 20;

    void* take(std::size_t bytes, BlockKind kind) {
        std::lock_guard<std::mutex> lock(mutex_);
        std::size_t best = blocks_.size();
        for (std::size_t i = 0; i < blocks_.size(); ++i) {
            const std::size_t size = blocks_[i].bytes;
            if (blocks_[i].kind == kind && size >= bytes && size <= bytes + bytes / 2 &&
                (best == blocks_.size() || size < blocks_[best].bytes))
                best = i;
        }
        if (best == blocks_.size()) return nullptr;
        const Block b = blocks_[best];
        if (b.bytes != bytes) lent_.push_back(b);  // first: if this throws, nothing has changed
        cached_ -= b.bytes;
        blocks_.erase(blocks_.begin() + std::ptrdiff_t(best));
        return b.p;
    }
    /// Keeps the block (`bytes`: the size asked for it); returns the blocks that no longer fit
    /// (the oldest first) for freeing.
    std::vector<void*> keep(void* p, std::size_t bytes, BlockKind kind) {
        std::lock_guard<std::mutex> lock(mutex_);
        for (std::size_t i = 0; i < lent_.size(); ++i)
            if (lent_[i].p == p) {  // lent larger than asked: back at its own size
                bytes = lent_[i].bytes;
                lent_.erase(lent_.begin() + std::ptrdiff_t(i));
                break;
            }
        std::vector<void*> evicted;
        if (bytes > kCacheBytes) return {p};
        blocks_.push_back({p, bytes, kind});
        cached_ += bytes;
        while (cached_ > kCacheBytes) {
            evicted.push_back(blocks_.front().p);
            cached_ -= blocks_.front().bytes;
            blocks_.erase(blocks_.begin());
        }
        return evicted;
    }

private:
    struct Block {
        void* p;
        std::size_t bytes;
        BlockKind kind = nullptr;
    };
    std::mutex mutex_;
    std::vector<Block> blocks_;
    std::vector<Block> lent_;  ///< blocks out on loan that are larger than their request
    std::size_t cached_ = 0;
};

BlockCache& cache() {
    static BlockCache* c = new BlockCache();  // never destroyed: blocks may be freed during exit
    return *c;
}

}  // namespace

void* allocate_big_block(std::size_t bytes, BlockKind kind) {
    if (void* p = cache().take(bytes, kind)) return p;
    const std::size_t huge = std::size_t(2) << 20;
    void* p = std::aligned_alloc(bytes >= huge ? huge : std::size_t(4096), bytes);
    if (!p) throw std::bad_alloc();
    return p;
}

void free_big_block(void* p, std::size_t bytes, BlockKind kind) noexcept {
    try {
        for (void* old : cache().keep(p, bytes, kind)) std::free(old);
    } catch (...) {  // no memory to remember the block: give it back
        std::free(p);
    }
}

void advise_huge_pages(void* p, std::size_t bytes) noexcept {
#if defined(__linux__) && defined(MADV_HUGEPAGE)
    constexpr std::uintptr_t kHuge = std::uintptr_t(2) << 20;
    const auto begin = (reinterpret_cast<std::uintptr_t>(p) + kHuge - 1) & ~(kHuge - 1);
    const auto end = (reinterpret_cast<std::uintptr_t>(p) + bytes) & ~(kHuge - 1);
    if (begin < end)
        madvise(reinterpret_cast<void*>(begin), end - begin, MADV_HUGEPAGE);  // a hint: failure changes nothing
#else
    (void)p, (void)bytes;
#endif
}

}  // namespace bvhlab
