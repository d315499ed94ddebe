// subtree_writer.h — appends the nodes of one subtree in depth-first order (docs/design.md,
// "Tree layout"): the top-down builder and the small-subtree builder write through it.
#pragma once
#include "subtree_builder.h"

namespace bvhlab {

/// Writes the nodes of one subtree in depth-first order; leaves copy their references to
/// BuildShared::leaf_refs. A node's skip index, the node after its subtree, is written when
/// that node is opened (close_spine), while the subtree's nodes are still in the caches.
class SubtreeWriter {
public:
    SubtreeWriter(BuildShared& shared, Subtree& out) : shared_(shared), out_(out) {}
    ~SubtreeWriter() { flush_leaf_count(); }
    SubtreeWriter(const SubtreeWriter&) = delete;
    SubtreeWriter& operator=(const SubtreeWriter&) = delete;

    /// Appends a node with `box` at `depth`; a second child is linked to its parent.
    std::uint32_t open(const Aabb& box, std::uint32_t depth, std::uint32_t parent, bool second_child) {
        const auto index = static_cast<std::uint32_t>(out_.nodes.size());
        BvhNode& node = out_.nodes.emplace_back();  // written in place: no copy to wait for its stores
        set_box(node, box);
        node.index = 0, node.info = 0;
        out_.depths.push_back(static_cast<std::uint8_t>(depth));
        if (second_child) {
            out_.nodes[parent].index = index;
            close_spine(parent + 1, index);
        }
        return index;
    }
    std::uint32_t open(const WorkItem& item) {
        return open(item.bounds.box, item.depth, item.parent, item.second_child);
    }
    void make_internal(std::uint32_t index) { out_.nodes[index].info = gpu::NODE_INTERNAL_BIT; }  // skip: close_spine
    /// Node `next` follows the subtree of node `first` (depth-first order): `first` and the second
    /// children down from it, whose subtrees all end there, skip to it. Each inner node lies on
    /// one such spine, so the tree's skips cost one visit a node (they were a pass over the tree
    /// at the end, reading each node's second child far away). A placeholder (a deferred range,
    /// info 0) ends the spine like a leaf: assemble() links the top's nodes.
    void close_spine(std::uint32_t first, std::uint32_t next) {
        for (std::uint32_t i = first; !is_leaf(out_.nodes[i]); i = out_.nodes[i].index)
            out_.nodes[i].info = gpu::NODE_INTERNAL_BIT | next;
    }
    /// Makes node `index` a leaf of the `count` references from position `first` on, and
    /// returns where their references go (the caller writes them).
    std::uint32_t* make_leaf(std::uint32_t index, std::uint32_t first, std::uint32_t count) {
        BvhNode& node = out_.nodes[index];
        node.index = first;
        node.info = count;
        leaf_primitives_ += count;
        return shared_.leaf_refs + first;
    }
    /// A leaf of the references of `item` as they lie in its buffer (boxes from them if the
    /// method makes boxes bottom-up).
    void make_leaf(std::uint32_t index, const WorkItem& item);
    void flush_leaf_count() {
        shared_.primitives_in_leaves.fetch_add(leaf_primitives_, std::memory_order_relaxed);
        leaf_primitives_ = 0;
    }
    BuildShared& shared() const { return shared_; }
    /// Leaves the geometry of leaf positions [begin, begin + count) to pack_unpacked.
    void pack_later(std::uint32_t begin, std::uint32_t count) {
        if (!out_.unpacked.empty() && out_.unpacked.back().end == begin) out_.unpacked.back().end += count;
        else out_.unpacked.push_back({begin, begin + count});
    }

private:
    BuildShared& shared_;
    Subtree& out_;
    std::uint64_t leaf_primitives_ = 0;
};

}  // namespace bvhlab
