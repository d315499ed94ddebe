// rebuild_top.cpp — rebuilding a refitted tree above a cut (rebuild_top.h). A refit keeps each
// subtree's own shape but not how the subtrees are grouped: where geometry moves, the large nodes'
// boxes span parts that were near each other when built. No subtree of a share of the primitives
// holds that excess, and rebuilding from primitives the nodes that do is a full rebuild. The levels
// above a cut of subtrees, each taken as one box, are rebuilt instead: a build over a few thousand
// boxes and one copy of the nodes, the leaf slots left where they are. (HLBVH builds its upper
// levels by the SAH over clusters' boxes the same way, Pantaleoni and Luebke 2010; Garanzha,
// Pantaleoni and McAllister 2011. bench/updates.py: on the 24-frame wave, after the subtrees of
// adaptive, no more full rebuilds.)
#include "rebuild_top.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <stdexcept>

#include "bvhlab/simd.h"

namespace bvhlab {
namespace {

/// Children whose half areas sum to less than this share of their parent's have come apart.
constexpr float kApart = 0.5f;
/// A subtree whose cost (relative to its own box) is within this share of its cost when built
/// is taken as moved whole (top_cut's intact subtrees).
constexpr float kIntact = 1e-5f;

/// The end of the subtree at `n` in its own node array.
std::uint32_t end_of(const PartedTree& t, PartNode n) { return skip_index(t.node(n), n.node); }

/// The nodes and depths of the subtree at `n`, for a copy.
const BvhNode* nodes_of(const PartedTree& t, PartNode n) {
    return n.part < 0 ? t.tree().nodes.data() : t.parts()[std::size_t(n.part)].part.nodes.data();
}
const std::uint8_t* depths_of(const PartedTree& t, PartNode n) {
    return n.part < 0 ? t.tree().depths.data() : t.parts()[std::size_t(n.part)].part.depths.data();
}

/// Levels below `n` in its subtree, the node itself counted (its height).
std::uint32_t height_of(const PartedTree& t, PartNode n) {
    const std::uint8_t* depths = depths_of(t, n);
    std::uint32_t deepest = depths[n.node];
    for (std::uint32_t i = n.node; i < end_of(t, n); ++i) deepest = std::max<std::uint32_t>(deepest, depths[i]);
    return deepest - depths[n.node] + 1;
}

}  // namespace

PartedTree::PartedTree(const Bvh& tree, const NodeCosts& now, const std::vector<RebuiltPart>& parts,
                       const NodeCostArray* built)
    : tree_(tree), now_(now), parts_(parts), built_(built) {}

namespace {

/// The cuts one scan takes (top_cut, top_cuts): `fine` of fine_primitives, and with `coarse` also
/// the cut of coarse_primitives (at least fine_primitives; the same intact size), the scan following
/// the fine cut until it holds more than `dense` nodes and the coarse one after that.
struct CutScan {
    std::uint32_t fine_primitives, coarse_primitives, intact_primitives;
    std::size_t dense;
    std::vector<PartNode>* fine;
    std::vector<PartNode>* coarse;  ///< null: the fine cut alone
    bool past_dense = false;
};

/// Appends the cuts (top_cut, top_cuts) of the subtree whose nodes are [first, end) of one array:
/// `part` -1 the tree's, with the parts standing in for their roots' subtrees, else
/// parts[part]'s. One scan forwards in depth-first order, jumping over each cut node's subtree:
/// the nodes, their counts and areas are read in order (walking down by the children read them at
/// random, and a cut node's children, whose areas tell whether they came apart, are near it: it
/// is small). A node whole for the fine cut is whole for the coarse one, so every coarse cut node
/// is on the fine cut's path (none of its ancestors whole for either): the coarse cut is taken on
/// the way, each node whole for it and not inside the last one taken, and once the fine cut is
/// dense the scan jumps over the coarse cut's subtrees instead (the rest of the coarse scan).
void cut_scan(const PartedTree& t, std::int32_t part, std::uint32_t first, std::uint32_t end, CutScan& scan) {
    const std::vector<RebuiltPart>& parts = t.parts();
    const Bvh& bvh = part < 0 ? t.tree() : parts[std::size_t(part)].part;
    const NodeCosts& costs = part < 0 ? t.tree_costs() : parts[std::size_t(part)].costs;
    const NodeCostArray* built = t.built();
    std::size_t next = 0;              // the next part (in node order) not yet passed
    std::uint32_t coarse_end = first;  // the end of the last coarse cut node's subtree
    for (std::uint32_t i = first; i < end;) {
        if (part < 0 && next < parts.size() && parts[next].root == i) {
            cut_scan(t, std::int32_t(next), 0, parts[next].part.node_count(), scan);
            i = parts[next++].end;
            continue;
        }
        if (scan.past_dense && i < coarse_end) {
            i = coarse_end;
            continue;
        }
        const BvhNode& n = bvh.nodes[i];
        const std::uint32_t count = costs.count[i];
        // as built: a part's nodes are; the tree's, where the cost is within kIntact of it
        const auto intact = [&] {
            if (part >= 0) return true;
            if (!built) return false;
            const float was = (*built)[i], now = costs.cost[i];
            return std::abs(now - was) <= kIntact * was;
        };
        const auto whole = [&](std::uint32_t max_primitives) {
            return is_leaf(n) || ((count <= max_primitives || (count <= scan.intact_primitives && intact())) &&
                                  !(costs.area[i + 1] + costs.area[n.index] < kApart * costs.area[i]) &&
                                  !(part < 0 && next < parts.size() && parts[next].root < skip_index(n, i)));
        };
        // whole for the fine cut: whole for the coarse one too (no second test)
        const bool fine_here = !scan.past_dense && whole(scan.fine_primitives);
        const bool coarse_here = scan.coarse && i >= coarse_end && (fine_here || whole(scan.coarse_primitives));
        if (coarse_here) scan.coarse->push_back({part, i}), coarse_end = skip_index(n, i);
        if (fine_here) {
            scan.fine->push_back({part, i});
            scan.past_dense = scan.coarse && scan.fine->size() > scan.dense;
            i = skip_index(n, i);
        } else if (scan.past_dense && coarse_here) {
            i = coarse_end;
        } else {
            // its children (at i + 1 and after its first child's subtree) come next. Every jump
            // over a cut subtree lands on the second child of a node the scan went into, so that
            // child is fetched now, while the first child's subtree is scanned (and the second
            // child of its first child, two steps ahead): the jumps missed the cache at the node
            // (perf: 70% of the scan's time on the load of its info word, the wave's frames)
            __builtin_prefetch(&bvh.nodes[n.index]), __builtin_prefetch(&costs.count[n.index]);
            const BvhNode& first_child = bvh.nodes[i + 1];
            if (!is_leaf(first_child)) __builtin_prefetch(&bvh.nodes[first_child.index]);
            ++i;
        }
    }
}

}  // namespace

std::vector<PartNode> top_cut(const PartedTree& tree, std::uint32_t max_primitives, std::uint32_t intact_primitives) {
    std::vector<PartNode> cut;
    CutScan scan{max_primitives, max_primitives, intact_primitives, SIZE_MAX, &cut, nullptr};
    cut_scan(tree, -1, 0, tree.tree().node_count(), scan);
    return cut;
}

bool top_cuts(const PartedTree& tree, std::uint32_t fine_primitives, std::uint32_t coarse_primitives,
              std::uint32_t intact_primitives, std::size_t dense, std::vector<PartNode>& fine,
              std::vector<PartNode>& coarse) {
    if (fine_primitives > coarse_primitives)
        throw std::invalid_argument("top_cuts: the fine cut's size is the smaller");
    fine.clear(), coarse.clear();
    CutScan scan{fine_primitives, coarse_primitives, intact_primitives, dense, &fine, &coarse};
    cut_scan(tree, -1, 0, tree.tree().node_count(), scan);
    return scan.past_dense;
}

CutInfo cut_info(const PartedTree& parted, const std::vector<PartNode>& cut) {
    // read in cut order: the nodes, counts and costs in order, where reading them in the new
    // top's order missed the cache at every one
    const std::size_t cuts = cut.size();
    CutInfo info{BigVector<Aabb>(cuts), BigVector<std::uint32_t>(cuts), BigVector<std::uint32_t>(cuts),
                 BigVector<double>(cuts)};
    constexpr std::size_t kAhead = 8;  // the cut nodes lie apart: each missed the cache (perf)
    for (std::size_t c = 0; c < std::min(cuts, kAhead); ++c) __builtin_prefetch(&parted.node(cut[c]));
    for (std::size_t c = 0; c < cuts; ++c) {
        if (c + kAhead < cuts) __builtin_prefetch(&parted.node(cut[c + kAhead]));
        info.boxes[c] = node_box(parted.node(cut[c]));
        info.size[c] = end_of(parted, cut[c]) - cut[c].node, info.count[c] = parted.count(cut[c]);
        info.area_cost[c] = parted.area_cost(cut[c]);
    }
    return info;
}

Bvh built_top(const BuildConfig& tree_config, const CutInfo& info) {
    BuildConfig config = tree_config;
    config.max_leaf_size = 1, config.sah_block = 1, config.threads = 1, config.progress = nullptr;
    return build_bvh_over_boxes(info.boxes.data(), info.boxes.size(), config);
}

double top_sah_cost(const Bvh& top, const CutInfo& info) {
    double s = 0;
    for (std::uint32_t j = 0; j < top.node_count(); ++j) {
        const BvhNode& n = top.nodes[j];
        s += is_leaf(n) ? info.area_cost[top.refs[n.index]] : double(node_box(n).half_area());
    }
    return top.empty() ? 0.0 : s / node_box(top.nodes[0]).half_area();
}

bool rebuild_top(Bvh& tree, NodeCostArray& built, const PartedTree& parted, const std::vector<PartNode>& cut,
                 const CutInfo& info, const Bvh& top, double& sah_cost) {
    if (tree.empty() || top.empty() || !(node_box(tree.nodes[0]).half_area() > 0)) return false;
    const std::size_t cuts = cut.size();
    const BigVector<std::uint32_t>&size = info.size, &count = info.count;
    const BigVector<double>& cut_area_cost = info.area_cost;
    // where each top node lands: after the top nodes before it and the cut subtrees they hold;
    // dest[c]: where cut node c's subtree goes
    const std::uint32_t top_nodes = top.node_count();
    BigVector<std::uint32_t> at(top_nodes + 1), dest(cuts);
    BigVector<std::uint8_t> dest_depth(cuts);
    for (std::uint32_t j = 0, pos = 0; j <= top_nodes; ++j) {
        at[j] = pos;
        if (j == top_nodes) break;
        const BvhNode& n = top.nodes[j];
        if (!is_leaf(n)) {
            ++pos;
            continue;
        }
        if (leaf_count(n) != 1) return false;  // one box a leaf (max_leaf_size 1)
        const std::uint32_t c = top.refs[n.index];
        // a cut subtree holds at most max(count, 1) leaves, so it is no taller: the exact height
        // only where that bound could pass the limit
        if (top.depths[j] + std::max<std::uint32_t>(count[c], 1) > gpu::MAX_TREE_HEIGHT &&
            top.depths[j] + height_of(parted, cut[c]) > gpu::MAX_TREE_HEIGHT)
            return false;
        dest[c] = pos, dest_depth[c] = top.depths[j];
        pos += size[c];
    }
    // the new arrays: top inner nodes with their children's places, cut subtrees shifted whole
    BigVector<BvhNode> nodes(at[top_nodes]);
    BigVector<std::uint8_t> depths(at[top_nodes]);
    NodeCostArray out_built(at[top_nodes]);
    // each cut subtree moved whole to its place
    auto move_subtree = [&](std::size_t k) {
        const PartNode c = cut[k];
        const BvhNode* from = nodes_of(parted, c);
        const std::uint8_t* from_depths = depths_of(parted, c);
        const float* from_built = c.part < 0 ? built.data() : parted.parts()[std::size_t(c.part)].costs.cost.data();
        // a part's leaves take its slots (placed by place_part_slots); the tree's keep theirs
        const std::uint32_t slot_shift = c.part < 0 ? 0 : parted.parts()[std::size_t(c.part)].slot;
        const std::uint32_t shift = dest[k] - c.node;  // unsigned: wraps where the subtree moves up
        const std::uint8_t depth_shift = std::uint8_t(dest_depth[k] - from_depths[c.node]);
        for (std::uint32_t i = c.node, o = dest[k]; i < c.node + size[k]; ++i, ++o) {
            const BvhNode& m = from[i];
            // an inner node's child and skip move by `shift` (the skip in info's low bits: no carry,
            // sizes < 2^31), a leaf's first slot by `slot_shift`: by a mask, as leaves and inner
            // nodes alternate at random (a branch mispredicted half the time)
            const std::uint32_t inner = 0u - (m.info >> 31);
            const std::uint32_t index_shift = (shift & inner) | (slot_shift & ~inner), info_shift = shift & inner;
#ifdef BVHLAB_SSE
            // each row whole, its lane 3 (index, info) moved by an integer add (lanes 0-2 add 0):
            // two loads and two stores a node (the copy field by field stored it in six pieces)
            const __m128i* row = reinterpret_cast<const __m128i*>(&m);
            __m128i* out = reinterpret_cast<__m128i*>(&nodes[o]);
            _mm_storeu_si128(out, _mm_add_epi32(_mm_loadu_si128(row), _mm_set_epi32(int(index_shift), 0, 0, 0)));
            _mm_storeu_si128(out + 1, _mm_add_epi32(_mm_loadu_si128(row + 1), _mm_set_epi32(int(info_shift), 0, 0, 0)));
#else
            BvhNode moved = m;
            moved.index += index_shift, moved.info += info_shift;
            nodes[o] = moved;
#endif
            depths[o] = std::uint8_t(from_depths[i] + depth_shift);
            out_built[o] = from_built[i];
        }
    };
    for (std::size_t k = 0; k < cuts; ++k) move_subtree(k);  // read in order, each written to its place
    // the top nodes, and S(n) = A(n)·cost(n) of each, for its cost (built) and the tree's SAH cost
    BigVector<double> area_cost(top_nodes);
    for (std::uint32_t j = top_nodes; j-- > 0;) {
        const BvhNode& n = top.nodes[j];
        if (is_leaf(n)) {
            area_cost[j] = cut_area_cost[top.refs[n.index]];
            continue;
        }
        BvhNode& o = nodes[at[j]];
        o = n;
        o.index = at[n.index], o.info = gpu::NODE_INTERNAL_BIT | at[skip_index(n, j)];
        depths[at[j]] = top.depths[j];
        const double area = node_box(n).half_area();
        area_cost[j] = area + area_cost[j + 1] + area_cost[n.index];
        // a node of zero area has no cost to compare with (node_costs' convention: 0)
        out_built[at[j]] = float(area > 0 ? area_cost[j] / area : 0.0);
    }
    out_built[0] = built[0];  // the root's cost when built stays the update's reference
    sah_cost = area_cost[0] / node_box(top.nodes[0]).half_area();  // the old root's box: not 0
    tree.nodes = std::move(nodes), tree.depths = std::move(depths);
    built = std::move(out_built);
    return true;
}

}  // namespace bvhlab
