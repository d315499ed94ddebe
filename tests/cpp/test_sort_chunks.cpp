// The full-sweep SAH's sort on the pool (sort_chunks.h sort_in_chunks) against std::sort: the
// same sequence, element for element, for every chunk count (odd ones leave a run to carry over a
// round), thread count and size, keys with many ties broken by a second field (the sweep's
// order: centroid, then reference).
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <random>
#include <utility>
#include <vector>

#include "bvhlab/thread_pool.h"
#include "sort_chunks.h"

using namespace bvhlab;

namespace {

using Item = std::pair<float, std::uint32_t>;

bool by_key(const Item& a, const Item& b) { return a.first < b.first || (a.first == b.first && a.second < b.second); }

std::vector<Item> items(std::uint32_t n, std::uint32_t distinct, unsigned seed) {
    std::mt19937 rng(seed);
    std::uniform_int_distribution<std::uint32_t> key(0, distinct - 1);
    std::vector<Item> v(n);
    for (std::uint32_t i = 0; i < n; ++i) v[i] = {float(key(rng)) * 0.25f, i};
    std::shuffle(v.begin(), v.end(), rng);
    return v;
}

}  // namespace

TEST(SortInChunks, SameAsStdSortForEveryChunkAndThreadCount) {
    BuildConfig config;
    SplitScratch scratch;
    PrimRef* buffers[2] = {nullptr, nullptr};
    for (std::uint32_t n : {0u, 1u, 2u, 7u, 1000u, 40000u}) {
        for (std::uint32_t distinct : {1u, 13u, 100000u}) {
            std::vector<Item> expected = items(n, distinct, n + distinct);
            const std::vector<Item> input = expected;
            std::sort(expected.begin(), expected.end(), by_key);
            for (unsigned threads : {1u, 2u, 3u}) {
                const ParallelPasses parallel{&ThreadPool::shared(), threads, nullptr, n, nullptr};
                SplitContext ctx{{buffers[0], buffers[1]}, config, scratch, &parallel};
                for (std::uint32_t chunks : {1u, 2u, 3u, 4u, 5u, 8u, 9u, 64u}) {
                    std::vector<Item> v = input, spare;
                    sort_in_chunks(ctx, chunks, v, spare, by_key);
                    EXPECT_EQ(v, expected)
                        << n << " items, " << distinct << " keys, " << threads << " threads, " << chunks << " chunks";
                }
            }
        }
    }
}

TEST(SortInChunks, WithoutParallelPassesSortsInTurn) {
    // A subtree's context has no ParallelPasses: the chunks are sorted and merged on the calling thread.
    BuildConfig config;
    SplitScratch scratch;
    SplitContext ctx{{nullptr, nullptr}, config, scratch, nullptr};
    std::vector<Item> v = items(5000, 50, 9), expected = v, spare;
    std::sort(expected.begin(), expected.end(), by_key);
    sort_in_chunks(ctx, 6, v, spare, by_key);
    EXPECT_EQ(v, expected);
}
