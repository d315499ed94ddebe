// reinsertion.cpp — the reinsertion step of Bittner, Hapala and Havran 2013 (reinsertion.h).
#include "reinsertion.h"

#include <algorithm>
#include <cmath>

#include "gpu_types.h"

namespace bvhlab::optimize {
namespace {

double area(const Aabb& b) { return b.half_area(); }  // float boxes, summed in double by the caller

Aabb joined(const Aabb& a, const Aabb& b) {
    Aabb u = a;
    u.grow(b);
    return u;
}

bool same_box(const Aabb& a, const Aabb& b) {
    return a.lo.x == b.lo.x && a.lo.y == b.lo.y && a.lo.z == b.lo.z && a.hi.x == b.hi.x && a.hi.y == b.hi.y &&
           a.hi.z == b.hi.z;
}

}  // namespace

float inefficiency(const LinkedTree& tree, std::uint32_t n) {
    constexpr float kTiny = 1e-30f;
    const LinkedNode& node = tree.nodes[n];
    const float a = node.box.half_area();
    const float al = tree.nodes[node.left].box.half_area(), ar = tree.nodes[node.right].box.half_area();
    const float m_sum = a / std::max(kTiny, 0.5f * (al + ar)), m_min = a / std::max(kTiny, std::min(al, ar));
    return m_sum * m_min * a;
}

bool can_take_out(const LinkedTree& tree, std::uint32_t n) {
    const LinkedNode& node = tree.nodes[n];
    return !node.leaf() && node.parent != kNone && tree.nodes[node.parent].parent != kNone;
}

void Reinserter::undo() {
    for (auto it = journal_.rbegin(); it != journal_.rend(); ++it) tree_.nodes[it->index] = it->node;
    tree_.root = root_before_;
}

void Reinserter::replace_child(std::uint32_t parent, std::uint32_t old_child, std::uint32_t new_child) {
    tree_.nodes[new_child].parent = parent;
    if (parent == kNone) {
        tree_.root = new_child;
        return;
    }
    LinkedNode& p = tree_.nodes[parent];
    (p.left == old_child ? p.left : p.right) = new_child;
}

/// New boxes and heights from `n` up to the root, adding each area's change to delta_; stops where
/// nothing changes any more (the ancestors above are then unchanged too).
void Reinserter::refit_up(std::uint32_t n) {
    for (; n != kNone; n = tree_.nodes[n].parent) {
        LinkedNode& node = tree_.nodes[n];
        const LinkedNode &l = tree_.nodes[node.left], &r = tree_.nodes[node.right];
        const Aabb box = joined(l.box, r.box);
        const std::uint32_t height = 1 + std::max(l.height, r.height);
        if (same_box(box, node.box) && height == node.height) return;
        save(n);
        delta_ += area(box) - area(node.box);
        node.box = box, node.height = height;
    }
}

/// Bittner et al. 2013 §3.2: a best-first search over the tree by the induced cost (what placing
/// `l` below a node adds to its ancestors' areas), pruned once the induced cost plus `l`'s own
/// area (the least a new parent can cost) reaches the best total found. A node X is a place when
/// the new parent (at X's depth) keeps every leaf within MAX_TREE_HEIGHT.
std::uint32_t Reinserter::best_sibling(std::uint32_t l) {
    const Aabb lbox = tree_.nodes[l].box;
    const float l_area = lbox.half_area();
    const std::uint32_t l_height = tree_.nodes[l].height;
    // min-heap on the induced cost, ties by node index (one order whatever the heap does)
    auto later = [](const Candidate& a, const Candidate& b) {
        return a.induced > b.induced || (a.induced == b.induced && a.node > b.node);
    };
    float best_cost = INFINITY;
    std::uint32_t best = kNone;
    heap_.assign(1, {0.0f, tree_.root, 0});
    while (!heap_.empty()) {
        std::pop_heap(heap_.begin(), heap_.end(), later);
        const Candidate c = heap_.back();
        heap_.pop_back();
        if (c.induced + l_area >= best_cost) break;  // every candidate left costs at least this
        const LinkedNode& x = tree_.nodes[c.node];
        const float direct = joined(x.box, lbox).half_area();
        const float total = c.induced + direct;
        if (total < best_cost && c.depth + 1 + std::max(x.height, l_height) <= gpu::MAX_TREE_HEIGHT)
            best_cost = total, best = c.node;
        const float induced = total - x.box.half_area();
        if (x.leaf() || induced + l_area >= best_cost) continue;
        for (std::uint32_t child : {x.left, x.right}) {
            heap_.push_back({induced, child, c.depth + 1});
            std::push_heap(heap_.begin(), heap_.end(), later);
        }
    }
    return best;
}

void Reinserter::insert(std::uint32_t l, std::uint32_t x, std::uint32_t parent) {
    save(parent), save(l), save(x);
    const std::uint32_t above = tree_.nodes[x].parent;
    if (above != kNone) save(above);
    replace_child(above, x, parent);
    LinkedNode& p = tree_.nodes[parent];
    p.left = x, p.right = l;
    p.box = joined(tree_.nodes[x].box, tree_.nodes[l].box);
    p.height = 1 + std::max(tree_.nodes[x].height, tree_.nodes[l].height);
    tree_.nodes[x].parent = parent, tree_.nodes[l].parent = parent;
    delta_ += area(p.box);
    refit_up(above);
}

bool Reinserter::reinsert_children(std::uint32_t n) {
    journal_.clear();
    root_before_ = tree_.root;
    delta_ = 0;
    const std::uint32_t p = tree_.nodes[n].parent, g = tree_.nodes[p].parent;
    const std::uint32_t sibling = tree_.nodes[p].left == n ? tree_.nodes[p].right : tree_.nodes[p].left;
    save(n), save(p), save(g), save(sibling);
    replace_child(g, p, sibling);
    delta_ -= area(tree_.nodes[n].box) + area(tree_.nodes[p].box);
    refit_up(g);
    // the larger child first: it has the fewer good places
    std::uint32_t a = tree_.nodes[n].left, b = tree_.nodes[n].right;
    if (tree_.nodes[b].box.half_area() > tree_.nodes[a].box.half_area()) std::swap(a, b);
    for (auto [child, parent] : {std::pair{a, n}, std::pair{b, p}}) {
        const std::uint32_t x = best_sibling(child);
        if (x == kNone) {
            undo();
            return false;
        }
        insert(child, x, parent);
    }
    // keep it when the cost fell by more than the rounding of the sums (never let it grow)
    const double margin = 1e-7 * area(tree_.nodes[tree_.root].box);
    if (delta_ < -margin) return true;
    undo();
    return false;
}

}  // namespace bvhlab::optimize
