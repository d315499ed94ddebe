// sbvh_builder.cpp — the SBVH's top-down build (Stich, Friedrich and Dietrich 2009, §4): one work
// array used as a stack of nodes' reference ranges, the node on top always last, so a spatial
// split that duplicates references grows the array in place.
#include "sbvh_builder.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <vector>

#include "bvhlab/build_config.h"
#include "bvhlab/simd.h"
#include "bvhlab/thread_pool.h"
#include "chop.h"
#include "sbvh_splits.h"

namespace bvhlab {
namespace {

using sbvh::ObjectSplit;
using sbvh::SpatialSplit;

/// The box and centroid box of some references.
struct Bounds {
    Aabb box, centroids;
    void grow(const PrimRef& r) { box.grow(r.box()), centroids.grow(r.centroid()); }
};

Bounds bounds_of(const PrimRef* refs, std::size_t n) {
    const float inf = std::numeric_limits<float>::infinity();
    F4 lo = F4::splat(inf), hi = F4::splat(-inf), clo = lo, chi = hi;
    const F4 half = F4::splat(0.5f);
    for (std::size_t i = 0; i < n; ++i) {
        const F4 l = refs[i].lo4(), h = refs[i].hi4(), c = (l + h) * half;  // PrimRef::centroid's
        lo = min(lo, l), hi = max(hi, h), clo = min(clo, c), chi = max(chi, c);
    }
    alignas(16) float v[4][4];
    lo.store(v[0]), hi.store(v[1]), clo.store(v[2]), chi.store(v[3]);
    return {{{v[0][0], v[0][1], v[0][2]}, {v[1][0], v[1][1], v[1][2]}},
            {{v[2][0], v[2][1], v[2][2]}, {v[3][0], v[3][1], v[3][2]}}};
}

/// A node to build: its references are work[begin, end), the last of the work array.
struct Task {
    std::uint32_t begin = 0, end = 0;
    Bounds bounds;
    std::uint32_t depth = 0;
    std::int64_t parent = -1;  ///< the node whose second child this is (its index is written then), or -1
    std::uint32_t size() const { return end - begin; }
};

/// A subtree left to a task of the pool: its place in the top's nodes, its root and references.
struct Deferred {
    std::uint32_t node = 0;
    Task task;
    std::vector<PrimRef> refs;
};

/// Subtrees of at most this many references are built as parts, on the pool (a constant: the tree
/// must not depend on the thread count). Sponza's 262K triangles make about 100.
constexpr std::uint32_t kPartSize = 4096;

std::uint32_t ceil_log2(std::uint32_t n) {
    std::uint32_t k = 0;
    while ((std::uint64_t(1) << k) < n) ++k;
    return k;
}

class SbvhBuilder {
public:
    SbvhBuilder(const GeometryView& g, const BuildConfig& cfg, float root_area)
        : g_(g),
          cfg_(cfg),
          setup_{cfg.bins, std::min(cfg.bins, sbvh::kMaxSpatialBins), SahCost(cfg)},
          min_overlap_(cfg.sbvh_alpha * root_area) {}

    /// Builds the subtree of `root` over `refs` (root.begin = 0, root.end = their count), adding at
    /// most `spare` references by spatial splits, spent as they come (the paper's budget, depth
    /// first). Tasks of at most `defer_size` references (but the root; 0: none) are left in
    /// `deferred`, each as a leaf of no references in `nodes`. `cancel` is polled where `poll` (the
    /// calling thread), else read. False when cancelled.
    bool run(std::vector<PrimRef> refs, const Task& root, std::uint64_t spare, std::uint32_t defer_size,
             Cancellation& cancel, bool poll, std::atomic<std::uint64_t>& in_leaves);
    std::uint64_t spare() const { return spare_; }

    std::vector<BvhNode> nodes;
    std::vector<std::uint32_t> leaf_refs;
    std::vector<std::uint8_t> depths;
    std::vector<Deferred> deferred;

private:
    bool split(const Task& t, Task& left, Task& right);
    bool spatial_partition(const Task& t, const SpatialSplit& s, Task& left, Task& right);
    void object_partition(const Task& t, const ObjectSplit& s, Task& left, Task& right);
    void median_partition(const Task& t, Task& left, Task& right);
    /// Children of t from work[t.begin, t.begin + right_count) (right) and the rest (left).
    void children(const Task& t, std::uint32_t right_count, Task& left, Task& right) const;
    void emit_leaf(const Task& t);
    void defer(const Task& t);
    /// What the object split's bins divide (BuildConfig::bin_bounds).
    const Aabb& object_span(const Task& t) const {
        return cfg_.bin_bounds == BinBounds::Box ? t.bounds.box : t.bounds.centroids;
    }

    const GeometryView& g_;
    const BuildConfig& cfg_;
    sbvh::BinSetup setup_;
    float min_overlap_;        ///< α · A(root): children overlapping less need no spatial split
    std::uint64_t spare_ = 0;  ///< references spatial splits may still add
    std::vector<PrimRef> work_, lefts_, rights_;
};

bool SbvhBuilder::run(std::vector<PrimRef> refs, const Task& root, std::uint64_t spare, std::uint32_t defer_size,
                      Cancellation& cancel, bool poll, std::atomic<std::uint64_t>& in_leaves) {
    work_ = std::move(refs);
    spare_ = spare;
    work_.reserve(root.size() + spare);
    std::vector<Task> stack{root};
    while (!stack.empty()) {
        const Task t = stack.back();
        stack.pop_back();
        if (t.parent >= 0) nodes[t.parent].index = static_cast<std::uint32_t>(nodes.size());
        if ((nodes.size() & 255) == 0) {
            if (poll ? cancel.poll() : cancel.stop_requested()) return false;
            if (poll)
                in_leaves.store(std::min<std::uint64_t>(leaf_refs.size(), root.size()), std::memory_order_relaxed);
        }
        if (t.size() <= defer_size && t.parent != -2) {
            defer(t);
            continue;
        }
        Task left, right;
        if (!split(t, left, right)) {
            emit_leaf(t);
            continue;
        }
        BvhNode node{};
        set_box(node, t.bounds.box);
        node.info = gpu::NODE_INTERNAL_BIT;  // its skip index is written when the tree is whole
        right.parent = static_cast<std::int64_t>(nodes.size());
        nodes.push_back(node), depths.push_back(std::uint8_t(t.depth));
        stack.push_back(right), stack.push_back(left);  // left on top: the next node, i + 1
    }
    return true;
}

void SbvhBuilder::defer(const Task& t) {
    Deferred d{static_cast<std::uint32_t>(nodes.size()), t, {work_.begin() + t.begin, work_.begin() + t.end}};
    d.task.begin = 0, d.task.end = t.size(), d.task.parent = -2;  // -2: a root, never deferred again
    deferred.push_back(std::move(d));
    BvhNode node{};
    set_box(node, t.bounds.box);
    nodes.push_back(node), depths.push_back(std::uint8_t(t.depth));
    work_.resize(t.begin);
}

void SbvhBuilder::emit_leaf(const Task& t) {
    BvhNode node{};
    set_box(node, t.bounds.box);
    node.index = static_cast<std::uint32_t>(leaf_refs.size());
    node.info = t.size();
    nodes.push_back(node), depths.push_back(std::uint8_t(t.depth));
    for (std::uint32_t i = t.begin; i < t.end; ++i) leaf_refs.push_back(work_[i].ref);
    work_.resize(t.begin);
}

/// Where a node of more than one reference is split (Stich et al. 2009 §4): the object split; the
/// spatial split where the object split's children overlap by more than α·A(root) (§4.5) and it is
/// cheaper; a leaf where one is allowed and cheaper than both; the median once the tree could grow
/// past MAX_TREE_HEIGHT.
bool SbvhBuilder::split(const Task& t, Task& left, Task& right) {
    const std::uint32_t n = t.size();
    if (n <= 1) return false;
    if (t.depth + ceil_log2(n) + 1 >= gpu::MAX_TREE_HEIGHT) {
        median_partition(t, left, right);
        return true;
    }
    const PrimRef* refs = work_.data() + t.begin;
    const ObjectSplit object = sbvh::find_object_split(refs, n, object_span(t), t.bounds.box.half_area(), setup_);
    SpatialSplit spatial;
    const bool overlapping = object.axis < 0 || sbvh::intersect(object.left, object.right).half_area() > min_overlap_;
    if (overlapping && spare_ > 0) spatial = sbvh::find_spatial_split(g_, refs, n, t.bounds.box, setup_);
    // without an object split the median's cost bounds the split (its children's boxes at most the node's)
    const float area = t.bounds.box.half_area();
    const float object_cost =
        object.axis >= 0 ? object.cost : setup_.sah.split(SahCost::inverse_area(area), area, n / 2, area, n - n / 2);
    if (n <= cfg_.max_leaf_size && setup_.sah.leaf(n) <= std::min(object_cost, spatial.cost)) return false;
    if (spatial.cost < object_cost && spatial_partition(t, spatial, left, right)) return true;
    if (object.axis >= 0) {
        object_partition(t, object, left, right);
    } else {
        median_partition(t, left, right);
    }
    return true;
}

void SbvhBuilder::children(const Task& t, std::uint32_t right_count, Task& left, Task& right) const {
    const PrimRef* refs = work_.data() + t.begin;
    right = Task{t.begin, t.begin + right_count, bounds_of(refs, right_count), t.depth + 1, -1};
    const auto end = static_cast<std::uint32_t>(work_.size());
    left = Task{right.end, end, bounds_of(refs + right_count, end - right.end), t.depth + 1, -1};
}

void SbvhBuilder::object_partition(const Task& t, const ObjectSplit& s, Task& left, Task& right) {
    const Aabb& span = object_span(t);
    const std::uint32_t bins = setup_.bins;
    auto first = work_.begin() + t.begin;
    auto mid = std::partition(first, work_.end(), [&](const PrimRef& r) {  // right side first
        return !sbvh::object_goes_left(r, s, span, bins);
    });
    children(t, static_cast<std::uint32_t>(mid - first), left, right);
}

/// The even split by count on the largest centroid axis (ties by reference): always two non-empty
/// halves, and every leaf within depth + ⌈log2 n⌉.
void SbvhBuilder::median_partition(const Task& t, Task& left, Task& right) {
    const int axis = largest_axis(t.bounds.centroids.extent());
    const std::uint32_t n = t.size(), right_count = n - n / 2;
    auto first = work_.begin() + t.begin;
    std::nth_element(first, first + right_count, work_.end(), [axis](const PrimRef& a, const PrimRef& b) {
        const float ca = a.centroid(axis), cb = b.centroid(axis);
        return ca > cb || (ca == cb && a.ref > b.ref);
    });
    children(t, right_count, left, right);
}

/// The spatial split's references (§4.3): those on one side of the plane go there; a straddling one
/// is chopped into both, or goes whole to the side where that is cheaper (unsplitting, §4.4:
/// A(L ∪ r)·N_L + A(R)·(N_R − 1) or A(L)·(N_L − 1) + A(R ∪ r)·N_R against A(L)·N_L + A(R)·N_R).
/// False, nothing moved, when a side would be empty or the budget would be overdrawn.
bool SbvhBuilder::spatial_partition(const Task& t, const SpatialSplit& s, Task& left, Task& right) {
    const int axis = s.axis;
    const float pos = s.position;
    Aabb lbox = s.left, rbox = s.right;
    float nl = float(s.left_count), nr = float(s.right_count);
    lefts_.clear(), rights_.clear();
    for (std::uint32_t i = t.begin; i < t.end; ++i) {
        const PrimRef& r = work_[i];
        if (r.hi[axis] <= pos) {
            lefts_.push_back(r);
            continue;
        }
        if (r.lo[axis] >= pos) {
            rights_.push_back(r);
            continue;
        }
        Aabb below, above;
        sbvh::chop_reference(g_, r, axis, pos, below, above);
        if (below.empty() || above.empty()) {
            (below.empty() ? rights_ : lefts_).push_back(sbvh::with_box(r, below.empty() ? above : below));
            continue;
        }
        if (cfg_.sbvh_unsplit) {
            Aabb lgrown = lbox, rgrown = rbox;
            lgrown.grow(r.box()), rgrown.grow(r.box());
            const float both = lbox.half_area() * nl + rbox.half_area() * nr;
            const float to_left = lgrown.half_area() * nl + rbox.half_area() * (nr - 1);
            const float to_right = lbox.half_area() * (nl - 1) + rgrown.half_area() * nr;
            if (to_left < both && to_left <= to_right) {
                lefts_.push_back(r), lbox = lgrown, nr -= 1;
                continue;
            }
            if (to_right < both) {
                rights_.push_back(r), rbox = rgrown, nl -= 1;
                continue;
            }
        }
        lefts_.push_back(sbvh::with_box(r, below)), rights_.push_back(sbvh::with_box(r, above));
    }
    const std::uint64_t added = lefts_.size() + rights_.size() - t.size();
    if (lefts_.empty() || rights_.empty() || added > spare_) return false;
    spare_ -= added;
    work_.resize(t.begin);
    work_.insert(work_.end(), rights_.begin(), rights_.end());
    work_.insert(work_.end(), lefts_.begin(), lefts_.end());
    children(t, static_cast<std::uint32_t>(rights_.size()), left, right);
    return true;
}

}  // namespace

std::uint64_t sbvh_reference_limit(std::uint64_t primitives, const BuildConfig& config) {
    const auto budget = static_cast<std::uint64_t>(std::floor(double(config.sbvh_budget) * double(primitives)));
    constexpr std::uint64_t kMaxReferences = gpu::REF_INDEX_MASK - 2 * (kMaxSahBlock - 1);
    return std::max(primitives, std::min(budget, kMaxReferences));
}

namespace {

/// Each part's share of the `spare` references the top left: in proportion to the area of its
/// references' boxes over its own box's (how often a ray through the part meets a reference: the
/// parts where references overlap most are where spatial splits pay), in order, rounded down.
std::vector<std::uint64_t> shares(const std::vector<Deferred>& parts, std::uint64_t spare) {
    std::vector<double> weight;
    double total = 0;
    for (const Deferred& d : parts) {
        double area = 0;
        for (const PrimRef& r : d.refs) area += r.box().half_area();
        const double box = d.task.bounds.box.half_area();
        weight.push_back(box > 0 ? area / box : double(d.refs.size()));
        total += weight.back();
    }
    std::vector<std::uint64_t> out;
    std::uint64_t handed = 0;  // never more than spare, whatever the rounding
    for (double w : weight) {
        const auto s = std::min(spare - handed, total > 0 ? std::uint64_t(double(spare) * (w / total)) : 0);
        out.push_back(s), handed += s;
    }
    return out;
}

/// The tree of `top` with its deferred subtrees `parts` spliced in, each in its placeholder's place
/// (depth-first order holds: a subtree is a contiguous range of nodes and of leaf slots): second
/// children, leaf slots and skip indices are written here.
void assemble(const SbvhBuilder& top, const std::vector<std::unique_ptr<SbvhBuilder>>& parts, Bvh& out) {
    const std::size_t m = top.nodes.size();
    std::vector<std::int64_t> part_of(m, -1);
    for (std::size_t k = 0; k < parts.size(); ++k) part_of[top.deferred[k].node] = std::int64_t(k);
    std::vector<std::uint32_t> pos(m);
    std::size_t total = 0, slots = top.leaf_refs.size();
    for (std::size_t i = 0; i < m; ++i) {
        pos[i] = static_cast<std::uint32_t>(total);
        total += part_of[i] >= 0 ? parts[part_of[i]]->nodes.size() : 1;
    }
    for (const auto& p : parts) slots += p->leaf_refs.size();
    out.nodes = BigVector<BvhNode>(total);
    out.depths = BigVector<std::uint8_t>(total);
    out.refs = BigVector<std::uint32_t>(slots);
    std::uint32_t slot = 0;
    for (std::size_t i = 0; i < m; ++i) {
        if (part_of[i] >= 0) {
            const SbvhBuilder& p = *parts[part_of[i]];
            for (std::size_t j = 0; j < p.nodes.size(); ++j) {
                BvhNode c = p.nodes[j];
                c.index += is_leaf(c) ? slot : pos[i];
                out.nodes[pos[i] + j] = c, out.depths[pos[i] + j] = p.depths[j];
            }
            std::copy(p.leaf_refs.begin(), p.leaf_refs.end(), out.refs.begin() + slot);
            slot += static_cast<std::uint32_t>(p.leaf_refs.size());
            continue;
        }
        BvhNode n = top.nodes[i];
        if (is_leaf(n)) {
            std::copy_n(top.leaf_refs.begin() + n.index, leaf_count(n), out.refs.begin() + slot);
            n.index = slot, slot += leaf_count(n);
        } else {
            n.index = pos[n.index];
        }
        out.nodes[pos[i]] = n, out.depths[pos[i]] = top.depths[i];
    }
    // skip index of an internal node: the end of its second child's subtree (children come later)
    std::vector<std::uint32_t> end(total);
    for (std::size_t i = total; i-- > 0;) {
        BvhNode& node = out.nodes[i];
        end[i] = is_leaf(node) ? std::uint32_t(i + 1) : end[node.index];
        if (!is_leaf(node)) node.info = gpu::NODE_INTERNAL_BIT | end[i];
    }
}

}  // namespace

void build_sbvh(const BigVector<PrimRef>& refs, const GeometryView& geometry, const BuildConfig& config,
                Cancellation& cancel, std::atomic<std::uint64_t>& in_leaves, Bvh& out) {
    if (refs.empty()) return;
    const auto n = static_cast<std::uint32_t>(refs.size());
    const Bounds bounds = bounds_of(refs.data(), n);
    const float root_area = bounds.box.half_area();
    const Task root{0, n, bounds, 0, -2};
    // The top of the tree leaves its subtrees of at most kPartSize references to the pool; the top
    // spends the budget first, then each part gets a share of what is left in proportion to its
    // references: the same tree on every thread count.
    SbvhBuilder top(geometry, config, root_area);
    if (!top.run({refs.begin(), refs.end()}, root, sbvh_reference_limit(n, config) - n, kPartSize, cancel, true,
                 in_leaves))
        return;
    std::vector<std::unique_ptr<SbvhBuilder>> parts;
    std::vector<std::size_t> order;  // largest first
    const std::vector<std::uint64_t> share = shares(top.deferred, top.spare());
    for (std::size_t k = 0; k < top.deferred.size(); ++k) {
        parts.push_back(std::make_unique<SbvhBuilder>(geometry, config, root_area));
        order.push_back(k);
    }
    std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
        return top.deferred[a].task.size() > top.deferred[b].task.size();
    });
    const bool whole = ThreadPool::shared().run_until_stopped(
        order.size(), ThreadPool::resolve(config.threads),
        [&](std::size_t i, unsigned) {
            Deferred& d = top.deferred[order[i]];
            parts[order[i]]->run(std::move(d.refs), d.task, share[order[i]], 0, cancel, false, in_leaves);
        },
        &cancel);
    if (!whole || cancel.stop_requested()) return;
    assemble(top, parts, out);
    out.prims = pack_prims(geometry, out.refs, config.threads);
}

}  // namespace bvhlab
