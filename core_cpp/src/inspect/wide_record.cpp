// wide_record.cpp — one ray's walk of the 8-wide tree (wide_bvh.h), recorded by the walk itself
// (wide_traverse.inl traverse_nodes, its recorded instantiation) and named by binary nodes.
#include <algorithm>
#include <cstdint>
#include <stdexcept>
#include <unordered_map>
#include <utility>

#include "../query/wide_kernel.h"
#include "bvhlab/isa.h"
#include "bvhlab/ray_record.h"

namespace bvhlab {
namespace {

/// A range of leaf-order slots (Bvh::prims) as one key: first in the high word, count in the low.
std::uint64_t range_key(std::uint32_t first, std::uint32_t count) { return std::uint64_t(first) << 32 | count; }

/// Every binary node by its subtree's first slot and slot count. Keys are distinct: an inner
/// node's slots are its children's together, each child holding at least one, and subtrees that
/// are not nested hold no slot in common. (A subtree's slots are one range in a built tree, runs
/// from apart after an update rebuilt the upper levels: rebuild_top.h.)
std::unordered_map<std::uint64_t, std::uint32_t> nodes_by_range(const Bvh& bvh) {
    const std::size_t n = bvh.nodes.size();
    std::vector<std::uint32_t> first(n), count(n);
    for (std::size_t i = n; i-- > 0;) {  // children (i + 1 and index) come after their parent
        const BvhNode& node = bvh.nodes[i];
        if (is_leaf(node)) first[i] = node.index, count[i] = leaf_count(node);
        else first[i] = std::min(first[i + 1], first[node.index]), count[i] = count[i + 1] + count[node.index];
    }
    std::unordered_map<std::uint64_t, std::uint32_t> by_range;
    by_range.reserve(n);
    for (std::size_t i = 0; i < n; ++i) by_range.emplace(range_key(first[i], count[i]), std::uint32_t(i));
    return by_range;
}

/// Names the children of the wide node at `line`, its subtree first (post-order), and returns the
/// node's slot range (first, count).
class Namer {
public:
    Namer(const Bvh& bvh, const WideBvh& wide, WideNames& names)
        : wide_(wide), by_range_(nodes_by_range(bvh)), names_(names) {}

    std::pair<std::uint32_t, std::uint32_t> name(std::uint32_t child_word) {
        const std::uint32_t line = child_word & ~kLeafChild;
        std::uint32_t first = kNoHit, count = 0;
        if (child_word & kLeafChild) {
            for (std::uint32_t at = line;; at += kPacketLines) {
                const PrimPacket& p = wide_.packet(at);
                for (int l = 0; l < 4; ++l)
                    if (p.ref[l] != kNoHit) first = std::min(first, p.slot[l]), ++count;
                if (!p.more) break;
            }
        } else {
            const WideNode& node = wide_.node(line);
            for (int k = 0; k < 8; ++k) {
                if (node.child[k] == 0) continue;  // an unused slot (line 0 is the root, no one's child)
                const auto [f, c] = name(node.child[k]);
                first = std::min(first, f), count += c;
            }
        }
        const auto found = by_range_.find(range_key(first, count));
        if (found == by_range_.end()) throw std::invalid_argument("the wide tree is not a copy of this binary tree");
        names_.binary_of_line[line] = found->second;
        return {first, count};
    }

private:
    const WideBvh& wide_;
    std::unordered_map<std::uint64_t, std::uint32_t> by_range_;
    WideNames& names_;
};

/// The recorder the wide walk calls (wide_kernel.h): boxes and primitives as binary nodes and
/// slots. A leaf's primitives are replayed by the scalar test (hit_prim) from the hit the leaf
/// started with, in the kernel's order (packets, then lanes), which computes what the kernel's
/// lanes compute bit for bit (wide_traverse.inl), to say which of them came closer.
class Recorder final : public WideRecorder {
public:
    Recorder(const Bvh& bvh, const WideBvh& wide, const WideNames& names, const Ray& ray, TraversalRecord& r)
        : bvh_(bvh), wide_(wide), names_(names), q_(ray), r_(r) {}

    void node(std::uint32_t line, std::uint32_t nearest, const std::uint32_t* pushed, std::uint32_t count) override {
        const auto step = std::uint32_t(r_.wide_nodes.size());
        r_.wide_nodes.push_back(names_.at(line));
        const WideNode& node = wide_.node(line);
        for (int k = 0; k < 8; ++k) {
            const std::uint32_t child = node.child[k];
            if (child == 0) continue;
            const bool entered = child == nearest || std::find(pushed, pushed + count, child) != pushed + count;
            r_.box_nodes.push_back(names_.at(child & ~kLeafChild)), r_.box_hit.push_back(entered);
            r_.box_wide_step.push_back(step);
        }
    }

    void leaf(std::uint32_t line, const Hit& before, const Hit& after) override {
        const std::uint32_t leaf = names_.at(line);
        Hit running = before;
        for (std::uint32_t at = line;; at += kPacketLines) {
            const PrimPacket& p = wide_.packet(at);
            for (int l = 0; l < 4; ++l) {
                if (p.ref[l] == kNoHit) continue;
                const bool closer = hit_prim(bvh_.prims[p.slot[l]], q_, running);
                if (closer) running.slot = p.slot[l];
                r_.prim_slots.push_back(p.slot[l]), r_.prim_leaf.push_back(leaf), r_.prim_closer.push_back(closer);
                r_.prim_box_test.push_back(std::uint32_t(r_.box_nodes.size()));
            }
            if (!p.more) break;
        }
        if (after.ref != before.ref || after.slot != before.slot || after.t != before.t) r_.hit_leaf = leaf;
    }

private:
    const Bvh& bvh_;
    const WideBvh& wide_;
    const WideNames& names_;
    RayQuery q_;
    TraversalRecord& r_;
};

}  // namespace

WideNames name_wide_nodes(const Bvh& bvh, const WideBvh& wide) {
    WideNames names;
    if (wide.lines.empty()) return names;
    Namer(bvh, wide, names).name(0);
    return names;
}

Hit detail::intersect_wide_recorded(const Bvh& bvh, const WideBvh& wide, const WideNames& names, const Ray& ray,
                                    TraversalRecord& record) {
    const WideView view = view_of(wide);
    Recorder recorder(bvh, wide, names, ray, record);
    // The kernel intersect_wide runs (isa.h): both visit the same nodes in the same order anyway
    const auto walk = [&] {
#if defined(BVHLAB_AVX512_KERNELS)
        if (active_isa() == Isa::Avx512) return avx512::record_wide_kernel(view, ray, recorder, &record.nodes_visited);
#endif
#if defined(BVHLAB_AVX2_KERNELS)
        if (active_isa() == Isa::Avx2) return avx2::record_wide_kernel(view, ray, recorder, &record.nodes_visited);
#endif
        return portable::record_wide_kernel(view, ray, recorder, &record.nodes_visited);
    };
    Hit hit = walk();
    if (hit.ref == kNoHit) hit.t = kInfinity;
    else if (hit.ref & gpu::REF_SPHERE_BIT) finish_hit(bvh, ray, hit);
    return hit;
}

}  // namespace bvhlab
