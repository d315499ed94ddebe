// restore.cpp — a saved tree checked and made whole again (restore.h).
#include "bvhlab/restore.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "bvhlab/geometry.h"
#include "bvhlab/prim_ref.h"
#include "coverage.h"

namespace bvhlab {

namespace {

[[noreturn]] void refuse(const std::string& what) { throw std::invalid_argument("not a valid saved tree: " + what); }

std::string node_name(std::uint32_t i) { return "node " + std::to_string(i); }

bool finite_box(const BvhNode& n) {
    return std::isfinite(n.lo.x) && std::isfinite(n.lo.y) && std::isfinite(n.lo.z) && std::isfinite(n.hi.x) &&
           std::isfinite(n.hi.y) && std::isfinite(n.hi.z) && n.lo.x <= n.hi.x && n.lo.y <= n.hi.y && n.lo.z <= n.hi.z;
}

/// Each reference names an existing primitive, and each primitive is named once; in an SBVH
/// (`repeats`) at least once, and the references are within its budget (sbvh_reference_limit).
void check_refs(const std::vector<std::uint32_t>& refs, const GeometryView& g, const BuildConfig& config) {
    const bool repeats = config.method == SplitMethod::Sbvh;
    const std::uint64_t most = repeats ? sbvh_reference_limit(g.primitive_count(), config) : g.primitive_count();
    if (refs.size() < g.primitive_count() || refs.size() > most)
        refuse(std::to_string(refs.size()) + " references for " + std::to_string(g.primitive_count()) + " primitives");
    std::vector<std::uint8_t> seen(g.primitive_count(), 0);
    for (std::size_t k = 0; k < refs.size(); ++k) {
        const std::uint32_t ref = refs[k];
        const std::size_t i = ref_index(ref);
        const bool sphere = is_sphere_ref(ref);
        if (i >= (sphere ? g.sphere_count : g.triangle_count))
            refuse("reference " + std::to_string(k) + " out of range");
        std::uint8_t& s = seen[sphere ? g.triangle_count + i : i];
        if (s && !repeats) refuse("primitive reference " + std::to_string(ref) + " used twice");
        s = 1;
    }
    for (std::size_t i = 0; i < seen.size(); ++i)
        if (!seen[i]) refuse("primitive " + std::to_string(i) + " has no reference");
}

/// Depth-first layout, skip indices, leaf slots and depths (bvh.h, docs/design.md "Tree layout").
/// Children come after their parent, so subtree ends are found in one backward pass.
void check_layout(const std::vector<BvhNode>& nodes, std::size_t ref_count, std::uint32_t max_leaf_size,
                  std::vector<std::uint8_t>& depths) {
    const std::uint32_t n = std::uint32_t(nodes.size());
    depths.assign(n, 0);
    if (n == 0) return;
    std::vector<std::uint32_t> end(n);
    for (std::uint32_t i = n; i-- > 0;) {
        const BvhNode& node = nodes[i];
        if (is_leaf(node)) {
            end[i] = i + 1;
            continue;
        }
        const std::uint32_t second = node.index;
        if (i + 1 >= n || second <= i + 1 || second >= n) refuse(node_name(i) + " has a child out of order or range");
        if (end[i + 1] != second) refuse(node_name(i) + "'s second child does not follow its first child's subtree");
        end[i] = end[second];
        if (skip_index(node, i) != end[i]) refuse(node_name(i) + " has a wrong skip index");
    }
    if (end[0] != n) refuse("the root's subtree does not hold every node");
    std::vector<std::pair<std::uint32_t, std::uint32_t>> runs;  // each leaf's first slot, and the leaf
    for (std::uint32_t i = 0; i < n; ++i) {
        const BvhNode& node = nodes[i];
        if (depths[i] >= gpu::MAX_TREE_HEIGHT) refuse(node_name(i) + " lies deeper than MAX_TREE_HEIGHT");
        if (!is_leaf(node)) {
            depths[i + 1] = depths[node.index] = std::uint8_t(depths[i] + 1);
            continue;
        }
        if (leaf_count(node) == 0 || std::uint64_t(node.index) + leaf_count(node) > ref_count)
            refuse("leaf " + std::to_string(i) + " has wrong slots");
        // every builder, update and optimize keeps leaves within the setting (a file whose header
        // says otherwise would show false settings in tables and pass `config=` checks)
        if (leaf_count(node) > max_leaf_size)
            refuse("leaf " + std::to_string(i) + " holds " + std::to_string(leaf_count(node)) +
                   " primitives, more than its max_leaf_size " + std::to_string(max_leaf_size));
        runs.emplace_back(node.index, i);
    }
    // the leaves' runs of slots tile the references: in depth-first order after a build, in any
    // order after an update rebuilt the upper levels (rebuild_top.h)
    std::sort(runs.begin(), runs.end());
    std::uint64_t next_slot = 0;
    for (const auto& [first, leaf] : runs) {
        if (first != next_slot) refuse("leaf " + std::to_string(leaf) + " has wrong slots");
        next_slot += leaf_count(nodes[leaf]);
    }
    if (next_slot != ref_count) refuse("the leaves do not hold every reference");
}

/// Every box is finite and holds its children's boxes, or its primitives; an SBVH leaf (`clipped`)
/// holds a part of each of its primitives, so its box need only meet theirs.
void check_boxes(const std::vector<BvhNode>& nodes, const std::vector<std::uint32_t>& refs, const GeometryView& g,
                 bool clipped) {
    for (std::uint32_t i = 0; i < nodes.size(); ++i)
        if (!finite_box(nodes[i])) refuse(node_name(i) + " has a box that is not finite");
    for (std::uint32_t i = 0; i < nodes.size(); ++i) {
        const BvhNode& node = nodes[i];
        const Aabb box = node_box(node);
        if (!is_leaf(node)) {
            if (!box.contains(node_box(nodes[i + 1])) || !box.contains(node_box(nodes[node.index])))
                refuse(node_name(i) + "'s box does not hold its children's");
            continue;
        }
        for (std::uint32_t k = node.index; k < node.index + leaf_count(node); ++k) {
            const Aabb prim = prim_box(g, refs[k]);
            const bool ok = clipped ? !Aabb{max(box.lo, prim.lo), min(box.hi, prim.hi)}.empty() : box.contains(prim);
            if (!ok) refuse(node_name(i) + "'s box does not hold its primitives");
        }
    }
}

/// An SBVH's references of each primitive stand for its parts inside their leaves' boxes: those
/// boxes together must hold all of it (a file whose leaf box was shrunk loaded, each box meeting
/// its primitives', and its rays missed what the box no longer held).
void check_coverage(const std::vector<BvhNode>& nodes, const std::vector<std::uint32_t>& refs, const GeometryView& g) {
    std::vector<std::pair<std::uint32_t, std::uint32_t>> owners;  // (primitive, leaf) for each slot
    owners.reserve(refs.size());
    for (std::uint32_t i = 0; i < nodes.size(); ++i) {
        const BvhNode& node = nodes[i];
        if (!is_leaf(node)) continue;
        for (std::uint32_t k = node.index; k < node.index + leaf_count(node); ++k) {
            const std::uint32_t ref = refs[k];
            owners.emplace_back(is_sphere_ref(ref) ? std::uint32_t(g.triangle_count + ref_index(ref)) : ref, i);
        }
    }
    std::sort(owners.begin(), owners.end());
    std::vector<Aabb> parts;
    for (std::size_t first = 0; first < owners.size();) {
        const std::uint32_t prim = owners[first].first;
        parts.clear();
        std::size_t last = first;
        for (; last < owners.size() && owners[last].first == prim; ++last)
            parts.push_back(node_box(nodes[owners[last].second]));
        const bool sphere = prim >= g.triangle_count;
        bool ok;
        if (sphere) {
            ok = box_covered(prim_box(g, std::uint32_t(prim - g.triangle_count) | gpu::REF_SPHERE_BIT), parts);
        } else {
            const Vec3 v[3] = {g.vertex(prim, 0), g.vertex(prim, 1), g.vertex(prim, 2)};
            ok = triangle_covered(v, parts);
        }
        if (!ok)
            refuse(std::string(sphere ? "sphere " : "triangle ") +
                   std::to_string(sphere ? prim - g.triangle_count : prim) + " is not covered by its leaves' boxes");
        first = last;
    }
}

}  // namespace

Bvh restore_bvh(SavedTree saved, const GeometryView& geometry, unsigned threads) {
    validate(geometry);
    validate(saved.config);
    const std::uint64_t fingerprint = geometry_fingerprint(geometry, threads);
    if (fingerprint != saved.geometry_fingerprint)
        throw std::invalid_argument("the tree was saved for other geometry (its fingerprint " +
                                    std::to_string(saved.geometry_fingerprint) + ", this scene's " +
                                    std::to_string(fingerprint) + ")");
    if (saved.nodes.empty() != (geometry.primitive_count() == 0)) refuse("nodes and primitives disagree");
    check_refs(saved.refs, geometry, saved.config);
    std::vector<std::uint8_t> depths;
    check_layout(saved.nodes, saved.refs.size(), saved.config.max_leaf_size, depths);
    const bool clipped = saved.config.method == SplitMethod::Sbvh;
    check_boxes(saved.nodes, saved.refs, geometry, clipped);
    if (clipped) check_coverage(saved.nodes, saved.refs, geometry);
    // a file made before build refused tiny scenes: its root holds the primitives (check_boxes)
    if (!saved.nodes.empty()) check_extent(node_box(saved.nodes[0]), geometry.triangle_count);

    Bvh bvh;
    bvh.nodes.assign(saved.nodes.begin(), saved.nodes.end());
    bvh.refs.assign(saved.refs.begin(), saved.refs.end());
    bvh.depths.assign(depths.begin(), depths.end());
    bvh.prims = pack_prims(geometry, bvh.refs, threads);
    bvh.triangle_count = std::uint32_t(geometry.triangle_count);
    bvh.sphere_count = std::uint32_t(geometry.sphere_count);
    bvh.set_fingerprint(fingerprint);
    saved.config.progress = nullptr;
    bvh.config = saved.config;
    bvh.build_ms = saved.build_ms;
    return bvh;
}

}  // namespace bvhlab
