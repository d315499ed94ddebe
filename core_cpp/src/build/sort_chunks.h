// sort_chunks.h — a sort whose work spreads over the build's pool: the full-sweep SAH's sorts of
// the nodes at the top of the tree (split_sweep_sah.cpp), which were the build's serial part
// (every node of 2^15 references or more is split by the calling thread, its passes on the pool:
// split.h; a sort was no pass, so 1M triangles built 1.45× faster on two threads than on one).
// Chunks sorted on the pool, then merged pairwise, each round's merges on the pool. With a strict
// total order (the sweep's: centroid, then reference) the result is std::sort's, element for
// element, however many chunks and threads: the tree does not depend on them.
#pragma once
#include <algorithm>
#include <cstdint>
#include <vector>

#include "bvhlab/split.h"

namespace bvhlab {

/// Sorts `v` by `less` (a strict total order) in `chunks` chunks (chunk_of), each sorted by a task
/// of ctx's pool (for_each_range: in turn where the build has one thread), then merged in rounds
/// of pairs into `spare` and back; `v` holds the result (the two vectors may have been swapped).
/// One chunk: std::sort, no spare.
template <class T, class Less>
void sort_in_chunks(const SplitContext& ctx, std::uint32_t chunks, std::vector<T>& v, std::vector<T>& spare,
                    Less less) {
    const Range all{0, static_cast<std::uint32_t>(v.size())};
    chunks = std::min(chunks, std::max<std::uint32_t>(all.size(), 1));
    if (chunks < 2) return std::sort(v.begin(), v.end(), less);
    std::vector<Range> runs(chunks);
    for (std::uint32_t k = 0; k < chunks; ++k) runs[k] = chunk_of(all, k, chunks);
    for_each_range(ctx, runs, [&](std::uint32_t, Range c) { std::sort(v.begin() + c.begin, v.begin() + c.end, less); });
    spare.resize(v.size());
    while (runs.size() > 1) {
        // run 2i and 2i + 1 merged into one; an odd last run copied as it is
        std::vector<Range> joined((runs.size() + 1) / 2);
        for (std::size_t i = 0; i < joined.size(); ++i)
            joined[i] = {runs[2 * i].begin, (2 * i + 1 < runs.size() ? runs[2 * i + 1] : runs[2 * i]).end};
        for_each_range(ctx, joined, [&](std::uint32_t i, Range m) {
            const auto at = [&](std::uint32_t k) { return v.begin() + k; };
            if (2 * i + 1 < runs.size()) {
                const Range a = runs[2 * i], b = runs[2 * i + 1];
                std::merge(at(a.begin), at(a.end), at(b.begin), at(b.end), spare.begin() + m.begin, less);
            } else {
                std::copy(at(m.begin), at(m.end), spare.begin() + m.begin);
            }
        });
        v.swap(spare);
        runs = std::move(joined);
    }
}

}  // namespace bvhlab
