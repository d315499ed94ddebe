#include "bvhlab/wide_bvh.h"

#include <array>
#include <cstring>
#include <limits>
#include <stdexcept>
#include <vector>

namespace bvhlab {
namespace {

/// A subtree of at most this many primitives becomes one wide leaf (one packet of triangles).
constexpr std::uint32_t kMergedLeaf = 4;

/// Per binary node: primitives in its subtree and the first of them, where they are one range of
/// slots (kNoRange where not: after an update rebuilt the upper levels, rebuild_top.h, a subtree
/// above its cut may hold runs from apart; built and refitted trees lay the slots in depth-first
/// order, every subtree one range). Only a subtree of one range merges into one wide leaf.
/// `merged`: the largest subtree merged into one leaf (kMergedLeaf; 0 for a TLAS, whose leaves
/// stay the binary tree's).
struct SubtreeRanges {
    static constexpr std::uint32_t kNoRange = std::numeric_limits<std::uint32_t>::max();
    std::vector<std::uint32_t> first, size;
    std::uint32_t merged;
    explicit SubtreeRanges(const Bvh& bvh, std::uint32_t merged_leaf = kMergedLeaf) : merged(merged_leaf) {
        if (merged == 0) return;  // a TLAS: the leaves are the binary tree's (leaf()), no ranges needed
        first.resize(bvh.nodes.size()), size.resize(bvh.nodes.size());
        for (std::size_t i = bvh.nodes.size(); i-- > 0;) {
            const BvhNode& n = bvh.nodes[i];
            if (is_leaf(n)) {
                first[i] = n.index, size[i] = leaf_count(n);
                continue;
            }
            const bool one = first[i + 1] != kNoRange && first[n.index] == first[i + 1] + size[i + 1];
            first[i] = one ? first[i + 1] : kNoRange, size[i] = size[i + 1] + size[n.index];
        }
    }
    bool leaf(const Bvh& bvh, std::uint32_t i) const {
        return is_leaf(bvh.nodes[i]) || (merged != 0 && size[i] <= merged && first[i] != kNoRange);
    }
};

/// Packets for the primitives [first, first + n) of bvh.prims: triangles, then spheres, four a packet.
std::uint32_t packets_for(const Bvh& bvh, std::uint32_t first, std::uint32_t n) {
    std::uint32_t spheres = 0;
    for (std::uint32_t k = first; k < first + n; ++k) spheres += is_sphere_ref(bvh.prims[k].ref);
    return (n - spheres + 3) / 4 + (spheres + 3) / 4;
}

/// Appends the primitives [first, first + n) of bvh.prims to wide.lines as packets (triangles,
/// then spheres, four a packet, each but the last with `more` set); returns the child word of the
/// leaf (kLeafChild | its first packet's line).
std::uint32_t pack_leaf(const Bvh& bvh, std::uint32_t first, std::uint32_t n, WideBvh& wide) {
    const auto begin = static_cast<std::uint32_t>(wide.lines.size());
    std::uint32_t count = 0;
    for (bool spheres : {false, true}) {
        PrimPacket q{};
        int lane = 0;
        auto flush = [&] {
            // an empty lane: NaN vertices, which fail the triangle test's sign test (wide_ray.inl)
            // before its zero edge functions would be made again exactly, as a point's are
            for (int l = lane; l < 4; ++l) {
                q.ref[l] = kNoHit, q.slot[l] = kNoHit;
                for (auto& vertex : q.v)
                    for (auto& axis : vertex) axis[l] = std::numeric_limits<float>::quiet_NaN();
            }
            q.more = 1;
            const std::size_t at = wide.lines.size();
            wide.lines.resize(at + kPacketLines);
            std::memcpy(&wide.lines[at], &q, sizeof q);
            ++count, q = PrimPacket{}, lane = 0;
        };
        for (std::uint32_t k = first; k < first + n; ++k) {
            const PackedPrim& p = bvh.prims[k];
            if (is_sphere_ref(p.ref) != spheres) continue;
            const gpu::vec3 vertices[3] = {p.v0, p.v1, p.v2};
            for (int v = 0; v < 3; ++v)
                q.v[v][0][lane] = vertices[v].x, q.v[v][1][lane] = vertices[v].y, q.v[v][2][lane] = vertices[v].z;
            q.ref[lane] = p.ref, q.slot[lane] = k;
            if (++lane == 4) flush();
        }
        if (lane) flush();
    }
    reinterpret_cast<PrimPacket*>(&wide.lines[wide.lines.size() - kPacketLines])->more = 0;
    wide.packet_count += count;
    return kLeafChild | begin;
}

/// Which binary inner nodes become wide nodes: the cost-optimal collapse of Ylitie, Karras and
/// Laine 2017 ("Efficient incoherent ray traversal on GPUs through compressed wide BVHs", §3.1),
/// with the leaves fixed by SubtreeRanges::leaf. Each merged leaf is one child of some wide node
/// whatever the collapse, so the leaves cost the same in every collapse and drop out: what is
/// minimised is the total surface area of the wide nodes, the SAH's measure of how many 8-wide
/// box tests a ray pays (MacDonald and Booth 1990). cost(n, i) is the least such area that covers
/// binary node n's subtree with at most i children of one wide node:
///   a leaf:           0 for every i;
///   split(n, j)     = min over 0 < k < j of cost(first, k) + cost(second, j - k);
///   cost(n, 1)      = area(n) + split(n, 8)             (n becomes a wide node of its own);
///   cost(n, i > 1)  = min(cost(n, i - 1), split(n, i)).
/// Against the greedy collapse (open the largest child until there are eight), which leaves the
/// wide nodes near the leaves half empty: Sponza 16 K wide nodes against 24 K, 5.4 entered per
/// random ray against 6.1, the same leaves.
class Collapse {
public:
    static constexpr int kWidth = 8;

    /// Bottom-up in reverse depth-first order, in which each node's two children are the last
    /// two finished: their costs are popped off a stack as high as the tree (the memory for the
    /// costs of every node would be 32 bytes a node), and the choices kept, 3 bits each.
    Collapse(const Bvh& bvh, const SubtreeRanges& ranges) : bvh_(bvh), ranges_(ranges), share_(bvh.nodes.size()) {
        std::vector<Costs> finished;  // of the subtrees whose parents are not done yet
        for (std::size_t n = bvh.nodes.size(); n-- > 0;) {
            Costs c{};  // a merged leaf: 0 for every i
            if (!is_leaf(bvh.nodes[n])) {
                const Costs a = finished.back();  // the first child, n + 1, finished last
                finished.pop_back();
                const Costs b = finished.back();
                finished.pop_back();
                if (!ranges.leaf(bvh, std::uint32_t(n))) {
                    const float area = node_box(bvh.nodes[n]).half_area();
                    // Two leaves (two in five of a TLAS's inner nodes): what choose() finds for costs
                    // of 0, without its 28 sums: cost(n, 1) = area, 0 for more slots (each leaf a
                    // slot of its own), share 1 for i = 1 and 2. Where area is 0, choose() (ties).
                    if (area > 0.0f && ranges.leaf(bvh, std::uint32_t(n) + 1) && ranges.leaf(bvh, bvh.nodes[n].index))
                        c[0] = area, share_[n] = 1u | 1u << 3;
                    else share_[n] = choose(a, b, area, c);
                }
            }
            finished.push_back(c);
        }
    }

    /// The children of the wide node made for binary node n: its two subtrees covered with eight
    /// slots as cost(n, 1) shared them; a leaf (only the root can be one) is its own only child.
    int children(std::uint32_t n, std::uint32_t out[kWidth]) const {
        int count = 0;
        if (ranges_.leaf(bvh_, n)) {
            out[count++] = n;
            return count;
        }
        const int k = share(n, 1);
        cover(n + 1, k, out, count);
        cover(bvh_.nodes[n].index, kWidth - k, out, count);
        return count;
    }

private:
    using Costs = std::array<float, kWidth>;  ///< cost(n, i) at i - 1

    /// cost(n, ·) from the children's, into c; returns the choices, share(n, i) in bits 3(i - 1).
    static std::uint32_t choose(const Costs& a, const Costs& b, float area, Costs& c) {
        float split[kWidth + 1];
        std::uint32_t best[kWidth + 1];
        for (int j = 2; j <= kWidth; ++j) {
            split[j] = a[0] + b[j - 2], best[j] = 1;
            for (int k = 2; k < j; ++k)
                if (a[k - 1] + b[j - k - 1] < split[j]) split[j] = a[k - 1] + b[j - k - 1], best[j] = std::uint32_t(k);
        }
        c[0] = area + split[kWidth];
        std::uint32_t choices = best[kWidth];
        for (int i = 2; i <= kWidth; ++i) {
            const bool fewer = !(split[i] < c[i - 2]);  // ties keep the fewer children
            c[i - 1] = fewer ? c[i - 2] : split[i];
            choices |= (fewer ? 0u : best[i]) << 3 * (i - 1);
        }
        return choices;
    }

    /// i > 1: the slots split(n, i) gives the first child, or 0 where cost(n, i) is
    /// cost(n, i - 1); i = 1: the slots split(n, 8) gives the first child.
    int share(std::uint32_t n, int i) const { return int(share_[n] >> 3 * (i - 1) & 7u); }

    /// Appends the children that cover binary node n's subtree with at most i slots.
    void cover(std::uint32_t n, int i, std::uint32_t out[kWidth], int& count) const {
        if (ranges_.leaf(bvh_, n)) i = 1;
        while (i > 1 && share(n, i) == 0) --i;
        if (i == 1) {
            out[count++] = n;
            return;
        }
        const int k = share(n, i);
        cover(n + 1, k, out, count);
        cover(bvh_.nodes[n].index, i - k, out, count);
    }

    const Bvh& bvh_;
    const SubtreeRanges& ranges_;
    std::vector<std::uint32_t> share_;  ///< per binary node, the choices (choose)
};

void set_slot(WideNode& w, int k, const BvhNode* c) {
    const float inf = std::numeric_limits<float>::infinity();
    w.lo_x[k] = c ? c->lo.x : inf, w.lo_y[k] = c ? c->lo.y : inf, w.lo_z[k] = c ? c->lo.z : inf;
    w.hi_x[k] = c ? c->hi.x : -inf, w.hi_y[k] = c ? c->hi.y : -inf, w.hi_z[k] = c ? c->hi.z : -inf;
    w.child[k] = 0, w.unused[k] = 0;
}

/// Lays the wide nodes down in preorder: a node, what `fill` appends after it (a tree's leaf
/// packets), then its inner children in slot order (the job of slot 0 pops first); each node
/// writes its line into its parent's slot when it is laid down. `leaf(n)`: whether binary node n
/// ends in a leaf slot; `fill(node, n, children, count)` sets the slots of the node collapsed from n.
template <class Leaf, class Fill>
void lay_down(const Collapse& collapse, WideBvh& wide, Leaf leaf, Fill fill) {
    struct Job {
        std::uint32_t binary, parent_line;
        int slot;
    };
    constexpr std::uint32_t kRoot = std::numeric_limits<std::uint32_t>::max();
    std::vector<Job> jobs{{0, kRoot, 0}};
    while (!jobs.empty()) {
        const Job job = jobs.back();
        jobs.pop_back();
        const auto at = static_cast<std::uint32_t>(wide.lines.size());
        if (at > kLeafChild - kNodeLines) throw std::length_error("the wide tree needs over 2^31 lines");
        wide.lines.resize(at + kNodeLines);
        ++wide.node_count;
        if (job.parent_line != kRoot) reinterpret_cast<WideNode*>(&wide.lines[job.parent_line])->child[job.slot] = at;
        std::uint32_t children[8];
        const int count = collapse.children(job.binary, children);
        WideNode node;
        fill(node, job.binary, children, count);
        std::memcpy(&wide.lines[at], &node, sizeof node);
        for (int k = count - 1; k >= 0; --k)
            if (!leaf(children[k])) jobs.push_back({children[k], at, k});
    }
}

}  // namespace

WideBvh make_wide(const Bvh& bvh) {
    WideBvh wide;
    if (bvh.empty()) return wide;
    const SubtreeRanges ranges(bvh);
    const Collapse collapse(bvh, ranges);
    // The lines needed, counted first, so that the block is one allocation, advised onto huge
    // pages before any of it is touched.
    std::size_t lines = 0;
    std::vector<std::uint32_t> todo{0};
    while (!todo.empty()) {
        const std::uint32_t n = todo.back();
        todo.pop_back();
        lines += kNodeLines;
        std::uint32_t children[8];
        const int count = collapse.children(n, children);
        for (int k = 0; k < count; ++k) {
            if (!ranges.leaf(bvh, children[k])) todo.push_back(children[k]);
            else
                lines +=
                    std::size_t(kPacketLines) * packets_for(bvh, ranges.first[children[k]], ranges.size[children[k]]);
        }
    }
    if (lines > kLeafChild) throw std::length_error("the wide tree needs over 2^31 lines");
    wide.lines.reserve(lines);
    advise_huge_pages(wide.lines.data(), lines * sizeof(WideLine));
    lay_down(
        collapse, wide, [&](std::uint32_t n) { return ranges.leaf(bvh, n); },
        [&](WideNode& node, std::uint32_t, const std::uint32_t* children, int count) {
            for (int k = 0; k < 8; ++k) {
                const BvhNode* c = k < count ? &bvh.nodes[children[k]] : nullptr;
                set_slot(node, k, c);
                if (c && ranges.leaf(bvh, children[k]))
                    node.child[k] = pack_leaf(bvh, ranges.first[children[k]], ranges.size[children[k]], wide);
            }
        });
    return wide;
}

WideBvh make_wide_tlas(const Bvh& tlas) {
    WideBvh wide;
    if (tlas.empty()) return wide;
    const SubtreeRanges ranges(tlas, 0);
    const Collapse collapse(tlas, ranges);
    wide.lines.reserve(std::size_t(kNodeLines) * (tlas.nodes.size() / 2 + 1));  // a node per binary inner node at most
    lay_down(
        collapse, wide, [&](std::uint32_t n) { return is_leaf(tlas.nodes[n]); },  // nodes only: no packets
        [&](WideNode& node, std::uint32_t binary, const std::uint32_t* children, int count) {
            for (int k = 0; k < 8; ++k) {
                const BvhNode* c = k < count ? &tlas.nodes[children[k]] : nullptr;
                set_slot(node, k, c);
                if (c && is_leaf(*c)) node.child[k] = kLeafChild | c->index;
            }
            node.unused[0] = std::uint32_t(count), node.unused[1] = binary;
        });
    return wide;
}

}  // namespace bvhlab
