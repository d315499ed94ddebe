// The large arrays of a build (big_vector.h, big_blocks.cpp): block sizes and alignment, and the
// cache of blocks that lends them again.
#include <gtest/gtest.h>

#include <cstdint>

#include "bvhlab/big_vector.h"
#include "bvhlab/bvh.h"
#include "bvhlab/geometry.h"
#include "bvhlab/wide_bvh.h"

using namespace bvhlab;

// big_vector.h: the block sizes, and the alignment a type asks for (WideNode's 64 bytes, which
// operator new without an alignment did not give below 2 MiB).
TEST(BigVector, BlockSizesAndAlignment) {
    EXPECT_EQ(big_block_bytes(kBigBlockMin), kBigBlockMin);
    EXPECT_EQ(big_block_bytes(kBigBlockMin + 1), 2 * kBigBlockMin);
    EXPECT_EQ(big_block_bytes((std::size_t(1) << 20) + 1), std::size_t(2) << 20);
    EXPECT_EQ(big_block_bytes((std::size_t(2) << 20) + 1), std::size_t(4) << 20);
    EXPECT_EQ(big_block_bytes(std::size_t(5) << 20), std::size_t(6) << 20);
    for (std::size_t n : {1, 100, 5000}) {  // below and above kBigBlockMin
        BigVector<WideNode> nodes(n);
        EXPECT_EQ(reinterpret_cast<std::uintptr_t>(nodes.data()) % alignof(WideNode), 0u) << n;
    }
}

// big_blocks.cpp: a cached block lent for a smaller request (within 1.5 times) comes back at its
// own size, so that it serves a request of that size again (kept under the smaller request's size,
// it never would, and every such request took fresh memory). Sizes no other test asks for.
TEST(BigVector, BlockLentForLessComesBackWhole) {
    const std::size_t whole = std::size_t(62) << 20, less = std::size_t(42) << 20;
    const BlockKind kind = block_kind<PrimRef>();
    void* p = allocate_big_block(whole, kind);
    free_big_block(p, whole, kind);
    void* q = allocate_big_block(less, kind);
    EXPECT_EQ(q, p);
    free_big_block(q, less, kind);
    void* r = allocate_big_block(whole, kind);
    EXPECT_EQ(r, p);
    free_big_block(r, whole, kind);
}

// big_blocks.cpp: a cached block goes back only to arrays of the element type it held (node
// arrays are filled a part of the way; a block of theirs given to an array written whole faults
// in the rest).
TEST(BigVector, BlocksGoBackToArraysOfTheirKind) {
    const std::size_t size = std::size_t(26) << 20;  // a size no other test asks for
    void* nodes = allocate_big_block(size, block_kind<BvhNode>());
    free_big_block(nodes, size, block_kind<BvhNode>());
    void* refs = allocate_big_block(size, block_kind<std::uint32_t>());
    EXPECT_NE(refs, nodes);
    void* again = allocate_big_block(size, block_kind<BvhNode>());
    EXPECT_EQ(again, nodes);
    free_big_block(refs, size, block_kind<std::uint32_t>());
    free_big_block(again, size, block_kind<BvhNode>());
}
