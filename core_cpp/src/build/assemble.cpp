#include "assemble.h"

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <utility>

#include "bvhlab/simd.h"
#include "bvhlab/thread_pool.h"

namespace bvhlab {

namespace {

/// Skip index (and box) of internal node `n` from its children, which come after it.
void finish_internal(BvhNode& n, const BvhNode& first, const BvhNode& second, bool boxes_from_children) {
    n.info = gpu::NODE_INTERNAL_BIT | skip_index(second, n.index);
    if (!boxes_from_children) return;
    Aabb box = node_box(first);
    box.grow(node_box(second));
    set_box(n, box);
}

}  // namespace

void fill_boxes_from_children(BigVector<BvhNode>& nodes) {
    for (std::size_t i = nodes.size(); i-- > 0;) {
        BvhNode& n = nodes[i];
        if (!is_leaf(n)) finish_internal(n, nodes[i + 1], nodes[n.index], true);
    }
}

namespace {

/// Copies subtree `p` to out[base...], shifting its child and skip indices by base.
void copy_part(const Subtree& p, std::uint32_t base, Bvh& out) {
    // Whether a node is a leaf is data: the shift is selected, not branched on (a branch here
    // mispredicted about every other node).
#ifdef BVHLAB_SSE
    // A node is two 16-byte rows, (lo, index) and (hi, info): info's top bit (NODE_INTERNAL_BIT),
    // spread by an arithmetic shift, selects `base` for lane 3 of both (the shift's other lanes
    // are 0, whatever the boxes' sign bits). 11 instructions a node where the scalar loop, which
    // the compiler did not vectorise, took 19 (callgrind, uniform1m's splice on two threads:
    // 37.3 M; bench/build_threads.py).
    static_assert(sizeof(BvhNode) == 32 && offsetof(BvhNode, index) == 12 && offsetof(BvhNode, info) == 28);
    //
    // The rows are streamed to memory (non-temporal stores) where aligned: the splice writes every
    // node of the tree, more than the L2 holds, into memory nothing has read since its last build,
    // and a plain store first reads each line it writes. The splice's CPU time on two threads
    // (perf samples, interleaved with plain stores): Sponza 1.12 -> 0.94 ms a build, room1m
    // 5.05 -> 4.12 ms (bench/build_threads.py --perf; design.md "Building").
    const __m128i shift = _mm_set_epi32(int(base), 0, 0, 0);
    const auto* from = reinterpret_cast<const __m128i*>(p.nodes.data());
    auto* to = reinterpret_cast<__m128i*>(out.nodes.data() + base);
    const std::size_t rows = 2 * p.nodes.size();  // read once: the stores might alias the vector
    const auto copy = [&](auto store) {
        for (std::size_t j = 0; j < rows; j += 2) {
            const __m128i lo = _mm_loadu_si128(from + j), hi = _mm_loadu_si128(from + j + 1);
            const __m128i add = _mm_and_si128(_mm_srai_epi32(hi, 31), shift);
            store(to + j, _mm_add_epi32(lo, add)), store(to + j + 1, _mm_add_epi32(hi, add));
        }
    };
    if (reinterpret_cast<std::uintptr_t>(to) % 16 == 0) {
        copy([](__m128i* at, __m128i v) { _mm_stream_si128(at, v); });
        _mm_sfence();  // before the pool's handover makes them visible to the thread that links
    } else {
        copy([](__m128i* at, __m128i v) { _mm_storeu_si128(at, v); });
    }
#else
    for (std::size_t j = 0; j < p.nodes.size(); ++j) {
        BvhNode n = p.nodes[j];
        const std::uint32_t shift = is_leaf(n) ? 0u : base;
        n.index += shift, n.info += shift;  // the skip keeps NODE_INTERNAL_BIT
        out.nodes[base + j] = n;
    }
#endif
    std::copy(p.depths.begin(), p.depths.end(), out.depths.begin() + base);
}

/// A subtree with placeholders, where it goes: its nodes' final indices and its parts' placeholders.
struct Linked {
    const Subtree* tree;
    std::vector<std::uint32_t> final_index;  ///< of each of its nodes in out.nodes
    std::vector<int> part_of;                ///< the part that fills each node, or -1
};

/// Places `s` at out.nodes[base...]: subtrees without placeholders (s or its parts) into
/// `copies`, those with them into `linked` at their depth of nesting (0: the top). Returns the
/// number of nodes of s with its parts spliced in (a part's root takes its placeholder's place).
std::uint32_t place(const Subtree& s, std::uint32_t base, std::size_t level,
                    std::vector<std::pair<const Subtree*, std::uint32_t>>& copies,
                    std::vector<std::vector<Linked>>& linked) {
    if (s.deferred.empty()) {
        copies.emplace_back(&s, base);
        return static_cast<std::uint32_t>(s.nodes.size());
    }
    if (s.parts.size() != s.deferred.size()) throw std::logic_error("bvhlab: a deferred range was not built");
    Linked l{&s, std::vector<std::uint32_t>(s.nodes.size()), std::vector<int>(s.nodes.size(), -1)};
    for (std::size_t k = 0; k < s.deferred.size(); ++k) l.part_of[s.deferred[k].node] = int(k);
    std::uint32_t at = base;
    for (std::size_t i = 0; i < s.nodes.size(); ++i) {
        l.final_index[i] = at;
        at += l.part_of[i] >= 0 ? place(s.parts[std::size_t(l.part_of[i])], at, level + 1, copies, linked) : 1;
    }
    if (linked.size() <= level) linked.resize(level + 1);
    linked[level].push_back(std::move(l));
    return at - base;
}

/// Writes the nodes of l.tree but its placeholders at their final indices, last to first (a
/// node's skip is its second child's, which comes later), their children's indices shifted and
/// skip indices filled from the children already in `out` (the parts' roots included).
void link(const Linked& l, bool boxes_from_children, Bvh& out) {
    const Subtree& s = *l.tree;
    for (std::size_t i = s.nodes.size(); i-- > 0;) {
        if (l.part_of[i] >= 0) continue;
        BvhNode n = s.nodes[i];
        const std::uint32_t at = l.final_index[i];
        if (!is_leaf(n)) {
            n.index = l.final_index[n.index];
            finish_internal(n, out.nodes[at + 1], out.nodes[n.index], boxes_from_children);
        }
        out.nodes[at] = n;
        out.depths[at] = s.depths[i];
    }
}

}  // namespace

void assemble(const Subtree& top, unsigned threads, bool boxes_from_children, Bvh& out) {
    std::vector<std::pair<const Subtree*, std::uint32_t>> copies;
    std::vector<std::vector<Linked>> linked;
    out.nodes.resize(place(top, 0, 0, copies, linked));
    out.depths.resize(out.nodes.size());
    ThreadPool& pool = ThreadPool::shared();
    pool.run(copies.size(), threads,
             [&](std::size_t k, unsigned) { copy_part(*copies[k].first, copies[k].second, out); });
    // The most nested first: a subtree's links read its parts' roots.
    for (std::size_t level = linked.size(); level-- > 0;)
        pool.run(linked[level].size(), threads,
                 [&](std::size_t k, unsigned) { link(linked[level][k], boxes_from_children, out); });
}

}  // namespace bvhlab
