// rebuild_subtrees.cpp — rebuilding chosen subtrees and splicing them into the depth-first array
// (docs/design.md "Tree layout"): a subtree is a contiguous range of nodes [root, skip) and of
// leaf slots, so a rebuilt one over the same primitives takes the same slots and a range of nodes
// of its own size; every node index after a replaced range moves by the difference.
#include "rebuild_subtrees.h"

#include <algorithm>
#include <cstring>

#include "bvhlab/stats.h"
#include "bvhlab/thread_pool.h"
#include "bvhlab/update.h"

namespace bvhlab {
namespace {

/// The first leaf slot of the subtree at `root`: its leftmost leaf's.
std::uint32_t first_slot(const Bvh& bvh, std::uint32_t root) {
    while (!is_leaf(bvh.nodes[root])) ++root;
    return bvh.nodes[root].index;
}

/// A tree over the primitives in slots [first, first + count) of `tree`, built with its settings;
/// its references and packed primitives name the original primitives.
Bvh build_part(const Bvh& tree, const GeometryView& g, std::uint32_t first, std::uint32_t count) {
    NodeCostArray tris(9 * std::size_t(count)), spheres;
    std::vector<std::uint32_t> tri_ref(count), sphere_ref;
    std::size_t triangles = 0;
    // the input is gathered at random (slot order): fetched kAhead references ahead, and each
    // triangle copied whole into its place (an insert a triangle checked its room first)
    constexpr std::uint32_t kAhead = 16;
    for (std::uint32_t k = first; k < first + std::min(count, kAhead); ++k) prefetch_prim(g, tree.refs[k]);
    for (std::uint32_t k = first; k < first + count; ++k) {
        if (k + kAhead < first + count) prefetch_prim(g, tree.refs[k + kAhead]);
        const std::uint32_t ref = tree.refs[k], i = ref_index(ref);
        if (is_sphere_ref(ref)) {
            spheres.insert(spheres.end(), g.spheres + 4 * std::size_t(i), g.spheres + 4 * std::size_t(i) + 4);
            sphere_ref.push_back(ref);
        } else {
            std::memcpy(&tris[9 * triangles], g.triangles + 9 * std::size_t(i), 9 * sizeof(float));
            tri_ref[triangles++] = ref;
        }
    }
    tris.resize(9 * triangles), tri_ref.resize(triangles);
    BuildConfig config = tree.config;
    config.threads = 1;  // the parts are small; the result never depends on it
    Bvh part = build_bvh({tris.data(), tri_ref.size(), spheres.data(), sphere_ref.size()}, config);
    auto original = [&](std::uint32_t local) {
        return is_sphere_ref(local) ? sphere_ref[ref_index(local)] : tri_ref[local];
    };
    for (std::size_t k = 0; k < part.refs.size(); ++k) part.refs[k] = original(part.refs[k]);
    for (PackedPrim& p : part.prims) p.ref = original(p.ref);
    return part;
}

}  // namespace

std::vector<std::uint32_t> subtrees_past(const Bvh& bvh, const NodeCosts& now, const NodeCostArray& built, float growth,
                                         std::uint32_t min_primitives) {
    std::vector<std::uint32_t> roots;
    for (std::uint32_t i = 0; i < bvh.node_count();) {
        if (now.count[i] >= min_primitives && now.cost[i] > growth * built[i]) {
            roots.push_back(i);
            i = skip_index(bvh.nodes[i], i);
        } else {
            ++i;
        }
    }
    return roots;
}

std::vector<std::uint32_t> subtrees_by_excess(const Bvh& bvh, const NodeCosts& now, const NodeCostArray& built,
                                              double to_remove, std::uint32_t min_primitives,
                                              std::uint64_t max_primitives, double& covered) {
    // a node whose children hold this share of its excess is passed over for them: part of a
    // node's excess is its children's boxes grown, which only the geometry's own shape may cause
    constexpr double kChildrenShare = 0.35;
    auto excess = [&](std::uint32_t i) { return double(now.area[i]) * (double(now.cost[i]) - built[i]); };
    // candidates: walk down from the root, passing over a node for its children while it is too
    // big to fit, holds no excess of its own (its costs when built may date from before a
    // rebuild below it) or its children hold most of its excess
    std::vector<std::uint32_t> candidates, stack;
    if (bvh.node_count() > 0) stack.push_back(0);
    while (!stack.empty()) {
        const std::uint32_t i = stack.back();
        stack.pop_back();
        const double e = excess(i);
        const BvhNode& n = bvh.nodes[i];
        const bool splits = !is_leaf(n) && now.count[i + 1] >= min_primitives && now.count[n.index] >= min_primitives;
        if (splits && (now.count[i] > max_primitives || !(e > 0) ||
                       std::max(excess(i + 1), 0.0) + std::max(excess(n.index), 0.0) >= kChildrenShare * e)) {
            stack.push_back(n.index), stack.push_back(i + 1);
        } else if (e > 0 && now.count[i] >= min_primitives && now.count[i] <= max_primitives) {
            candidates.push_back(i);
        }
    }
    // the most excess per primitive first (ties by node: the same choice on every run)
    std::sort(candidates.begin(), candidates.end(), [&](std::uint32_t a, std::uint32_t b) {
        const double da = excess(a) / now.count[a], db = excess(b) / now.count[b];
        return da != db ? da > db : a < b;
    });
    covered = 0;
    std::uint64_t primitives = 0;
    std::vector<std::uint32_t> taken;
    for (std::uint32_t c : candidates) {
        if (covered >= to_remove) break;
        if (primitives + now.count[c] > max_primitives) continue;  // a smaller one may still fit
        covered += excess(c), primitives += now.count[c];
        taken.push_back(c);
    }
    candidates = std::move(taken);
    std::sort(candidates.begin(), candidates.end());
    return candidates;
}

std::vector<RebuiltPart> build_parts(const Bvh& tree, const std::vector<std::uint32_t>& roots, const GeometryView& g,
                                     const NodeCosts& now, double& area_cost_saved) {
    std::vector<RebuiltPart> parts(roots.size());
    // each part on one thread of the pool (the largest first), each built with threads = 1: the
    // same parts on every thread count
    std::vector<std::size_t> order(roots.size());
    for (std::size_t k = 0; k < order.size(); ++k) order[k] = k;
    std::stable_sort(order.begin(), order.end(),
                     [&](std::size_t a, std::size_t b) { return now.count[roots[a]] > now.count[roots[b]]; });
    ThreadPool::shared().run(roots.size(), ThreadPool::resolve(tree.config.threads), [&](std::size_t i, unsigned) {
        const std::uint32_t root = roots[order[i]];
        RebuiltPart& r = parts[order[i]];
        r.root = root, r.end = skip_index(tree.nodes[root], root), r.slot = first_slot(tree, root);
        r.part = build_part(tree, g, r.slot, now.count[root]);
        r.costs = node_costs(r.part);
    });
    area_cost_saved = 0;
    std::vector<RebuiltPart> kept;
    for (RebuiltPart& r : parts) {
        const std::uint32_t height = *std::max_element(r.part.depths.begin(), r.part.depths.end()) + 1u;
        if (tree.depths[r.root] + height > gpu::MAX_TREE_HEIGHT) continue;  // kept as it was
        // the part's root box is the old root's (both the union of the same primitives' boxes)
        area_cost_saved += now.area_cost(r.root) - r.costs.area_cost(0);
        kept.push_back(std::move(r));
    }
    return kept;
}

void place_part_slots(Bvh& tree, const std::vector<RebuiltPart>& parts) {
    for (const RebuiltPart& r : parts) {
        std::copy(r.part.refs.begin(), r.part.refs.end(), tree.refs.begin() + r.slot);
        std::copy(r.part.prims.begin(), r.part.prims.end(), tree.prims.begin() + r.slot);
    }
}

void splice_parts(Bvh& tree, NodeCostArray& built, const std::vector<RebuiltPart>& parts) {
    if (parts.empty()) return;
    // map(i): where old node i (outside the replaced ranges, or the end of one) lands
    // ends[k]: the end of part k's old range; shift[k]: how far the parts before it move a node
    // (a binary search a node: copying a node once walked every part, 10% of an adaptive update)
    std::vector<std::uint32_t> ends;
    std::vector<std::int64_t> shift{0};
    for (const RebuiltPart& r : parts) {
        ends.push_back(r.end);
        shift.push_back(shift.back() + std::int64_t(r.part.node_count()) - std::int64_t(r.end - r.root));
    }
    auto map = [&](std::uint32_t i) {
        const std::size_t before =
            std::upper_bound(ends.begin(), ends.end(), i) - ends.begin();  // parts ending at or before i
        return std::uint32_t(std::int64_t(i) + shift[before]);
    };
    // map(i) for i at or after the node being copied, the parts before that node being `done`: a
    // child or skip index short of the next part's root moves as the node does (no search)
    auto map_from = [&](std::size_t done, std::uint32_t i) {
        return done == parts.size() || i <= parts[done].root ? std::uint32_t(std::int64_t(i) + shift[done]) : map(i);
    };
    Bvh out;
    NodeCostArray out_built;
    const std::size_t size = map(tree.node_count());
    out.nodes = BigVector<BvhNode>(size);
    out.depths = BigVector<std::uint8_t>(size);
    out_built.resize(size);
    std::uint32_t next = 0;  // old node to copy next
    std::size_t at = 0;      // where it goes
    std::size_t done = 0;    // the parts before it
    auto copy_old = [&](std::uint32_t until) {
        for (; next < until; ++next, ++at) {
            BvhNode n = tree.nodes[next];
            if (!is_leaf(n))
                n.index = map_from(done, n.index),
                n.info = gpu::NODE_INTERNAL_BIT | map_from(done, skip_index(n, next));
            out.nodes[at] = n, out.depths[at] = tree.depths[next], out_built[at] = built[next];
        }
    };
    for (const RebuiltPart& r : parts) {
        copy_old(r.root);
        const std::uint32_t base = static_cast<std::uint32_t>(at);
        for (std::uint32_t j = 0; j < r.part.node_count(); ++j, ++at) {
            BvhNode n = r.part.nodes[j];
            if (is_leaf(n)) n.index += r.slot;
            else n.index += base, n.info = gpu::NODE_INTERNAL_BIT | (skip_index(n, j) + base);
            out.nodes[at] = n, out.depths[at] = std::uint8_t(tree.depths[r.root] + r.part.depths[j]);
            out_built[at] = r.costs.cost[j];
        }
        next = r.end, ++done;
    }
    copy_old(tree.node_count());
    tree.nodes = std::move(out.nodes);
    tree.depths = std::move(out.depths);
    built = std::move(out_built);
}

std::uint64_t rebuild_subtrees(Bvh& tree, NodeCostArray& built, const std::vector<std::uint32_t>& roots,
                               const GeometryView& g, const NodeCosts& now, double& area_cost_saved) {
    const std::vector<RebuiltPart> parts = build_parts(tree, roots, g, now, area_cost_saved);
    place_part_slots(tree, parts);
    splice_parts(tree, built, parts);
    return primitives_in(parts);
}

std::uint64_t primitives_in(const std::vector<RebuiltPart>& parts) {
    std::uint64_t sum = 0;
    for (const RebuiltPart& r : parts) sum += r.part.refs.size();
    return sum;
}

}  // namespace bvhlab
