// reinsertion.h — one reinsertion step of Bittner, Hapala and Havran 2013 on a linked tree: take
// an inner node N and its parent P out (N's sibling takes P's place), put N's two children back
// where the SAH finds them cheapest (§3.2's branch-and-bound search), with N and P as their new
// parents, and keep the change only if the tree's cost went down (else every node is restored).
#pragma once
#include <cstdint>
#include <vector>

#include "linked_tree.h"

namespace bvhlab::optimize {

/// The inefficiency of an inner node by which the nodes to take out are chosen (Bittner et al.
/// 2013 §3.4, their best measure M_sum · M_min · M_area): large and badly filled by its children.
float inefficiency(const LinkedTree& tree, std::uint32_t n);

/// Whether `n` may be taken out: an inner node whose parent is not the root (the sibling needs a
/// grandparent to move into).
bool can_take_out(const LinkedTree& tree, std::uint32_t n);

class Reinserter {
public:
    explicit Reinserter(LinkedTree& tree) : tree_(tree) {}

    /// Takes out `n` (can_take_out) and reinserts its children; keeps the result if the sum of the
    /// inner nodes' areas (the SAH cost up to a constant, leaves being unchanged) fell by more than
    /// a rounding margin. Returns whether it was kept.
    bool reinsert_children(std::uint32_t n);

private:
    struct Saved {
        std::uint32_t index;
        LinkedNode node;
    };
    void save(std::uint32_t i) { journal_.push_back({i, tree_.nodes[i]}); }
    void undo();
    void replace_child(std::uint32_t parent, std::uint32_t old_child, std::uint32_t new_child);
    void refit_up(std::uint32_t n);
    /// The node beside which `l` costs least (kNone: none keeps the tree within MAX_TREE_HEIGHT).
    std::uint32_t best_sibling(std::uint32_t l);
    /// Puts `l` beside `x` under the free node `parent`.
    void insert(std::uint32_t l, std::uint32_t x, std::uint32_t parent);

    struct Candidate {
        float induced;
        std::uint32_t node, depth;
    };
    LinkedTree& tree_;
    std::vector<Saved> journal_;
    std::vector<Candidate> heap_;
    std::uint32_t root_before_ = kNone;
    double delta_ = 0;  ///< change of the inner nodes' summed half areas
};

}  // namespace bvhlab::optimize
