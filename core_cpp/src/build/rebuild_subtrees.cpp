// rebuild_subtrees.cpp — rebuilding chosen subtrees and splicing them into the depth-first array
// (docs/design.md "Tree layout"): a subtree is a contiguous range of nodes [root, skip) and of
// leaf slots, so a rebuilt one over the same primitives takes the same slots and a range of nodes
// of its own size; every node index after a replaced range moves by the difference.
#include "rebuild_subtrees.h"

#include <algorithm>

#include "bvhlab/stats.h"
#include "bvhlab/update.h"

namespace bvhlab {
namespace {

/// Primitives under each node (a leaf's count; an inner node's children's sum).
std::vector<std::uint32_t> primitive_counts(const Bvh& bvh) {
    std::vector<std::uint32_t> count(bvh.nodes.size());
    for (std::size_t i = bvh.nodes.size(); i-- > 0;) {
        const BvhNode& n = bvh.nodes[i];
        count[i] = is_leaf(n) ? leaf_count(n) : count[i + 1] + count[n.index];
    }
    return count;
}

/// The first leaf slot of the subtree at `root`: its leftmost leaf's.
std::uint32_t first_slot(const Bvh& bvh, std::uint32_t root) {
    while (!is_leaf(bvh.nodes[root])) ++root;
    return bvh.nodes[root].index;
}

/// A tree over the primitives in slots [first, first + count) of `tree`, built with its settings;
/// its references and packed primitives name the original primitives.
Bvh build_part(const Bvh& tree, const GeometryView& g, std::uint32_t first, std::uint32_t count) {
    std::vector<float> tris, spheres;
    std::vector<std::uint32_t> tri_ref, sphere_ref;
    for (std::uint32_t k = first; k < first + count; ++k) {
        const std::uint32_t ref = tree.refs[k], i = ref_index(ref);
        if (is_sphere_ref(ref)) {
            spheres.insert(spheres.end(), g.spheres + 4 * std::size_t(i), g.spheres + 4 * std::size_t(i) + 4);
            sphere_ref.push_back(ref);
        } else {
            tris.insert(tris.end(), g.triangles + 9 * std::size_t(i), g.triangles + 9 * std::size_t(i) + 9);
            tri_ref.push_back(ref);
        }
    }
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

struct Replacement {
    std::uint32_t root, end;  ///< old node range [root, end)
    Bvh part;
    std::vector<float> costs;
    std::uint32_t slot;  ///< first leaf slot
};

}  // namespace

std::vector<std::uint32_t> subtrees_past(const Bvh& bvh, const std::vector<float>& costs,
                                         const std::vector<float>& built, float growth, std::uint32_t min_primitives) {
    const std::vector<std::uint32_t> count = primitive_counts(bvh);
    std::vector<std::uint32_t> roots;
    for (std::uint32_t i = 0; i < bvh.node_count();) {
        if (count[i] >= min_primitives && costs[i] > growth * built[i]) {
            roots.push_back(i);
            i = skip_index(bvh.nodes[i], i);
        } else {
            ++i;
        }
    }
    return roots;
}

std::uint64_t primitives_under(const Bvh& bvh, const std::vector<std::uint32_t>& roots) {
    const std::vector<std::uint32_t> count = primitive_counts(bvh);
    std::uint64_t sum = 0;
    for (std::uint32_t root : roots) sum += count[root];
    return sum;
}

std::uint64_t rebuild_subtrees(Bvh& tree, std::vector<float>& built, const std::vector<std::uint32_t>& roots,
                               const GeometryView& g) {
    const std::vector<std::uint32_t> count = primitive_counts(tree);
    std::vector<Replacement> parts;
    std::uint64_t rebuilt = 0;
    for (std::uint32_t root : roots) {
        const std::uint32_t slot = first_slot(tree, root);
        Bvh part = build_part(tree, g, slot, count[root]);
        const BvhStats s = compute_stats(part);
        if (tree.depths[root] + s.height > gpu::MAX_TREE_HEIGHT) continue;  // kept as it was
        std::vector<float> costs = subtree_costs(part);
        rebuilt += count[root];
        parts.push_back({root, skip_index(tree.nodes[root], root), std::move(part), std::move(costs), slot});
    }
    if (parts.empty()) return 0;
    // map(i): where old node i (outside the replaced ranges, or the end of one) lands
    auto map = [&](std::uint32_t i) {
        std::int64_t shift = 0;
        for (const Replacement& r : parts) {
            if (r.end > i) break;
            shift += std::int64_t(r.part.node_count()) - std::int64_t(r.end - r.root);
        }
        return std::uint32_t(std::int64_t(i) + shift);
    };
    Bvh out;
    std::vector<float> out_built;
    const std::size_t size = map(tree.node_count());
    out.nodes = BigVector<BvhNode>(size);
    out.depths = BigVector<std::uint8_t>(size);
    out_built.resize(size);
    std::uint32_t next = 0;  // old node to copy next
    std::size_t at = 0;      // where it goes
    auto copy_old = [&](std::uint32_t until) {
        for (; next < until; ++next, ++at) {
            BvhNode n = tree.nodes[next];
            if (!is_leaf(n)) n.index = map(n.index), n.info = gpu::NODE_INTERNAL_BIT | map(skip_index(n, next));
            out.nodes[at] = n, out.depths[at] = tree.depths[next], out_built[at] = built[next];
        }
    };
    for (const Replacement& r : parts) {
        copy_old(r.root);
        const std::uint32_t base = static_cast<std::uint32_t>(at);
        for (std::uint32_t j = 0; j < r.part.node_count(); ++j, ++at) {
            BvhNode n = r.part.nodes[j];
            if (is_leaf(n)) n.index += r.slot;
            else n.index += base, n.info = gpu::NODE_INTERNAL_BIT | (skip_index(n, j) + base);
            out.nodes[at] = n, out.depths[at] = std::uint8_t(tree.depths[r.root] + r.part.depths[j]);
            out_built[at] = r.costs[j];
        }
        std::copy(r.part.refs.begin(), r.part.refs.end(), tree.refs.begin() + r.slot);
        std::copy(r.part.prims.begin(), r.part.prims.end(), tree.prims.begin() + r.slot);
        next = r.end;
    }
    copy_old(tree.node_count());
    tree.nodes = std::move(out.nodes);
    tree.depths = std::move(out.depths);
    built = std::move(out_built);
    return rebuilt;
}

}  // namespace bvhlab
