#include "small_subtree.h"

#include <algorithm>
#include <cstring>
#include <limits>

#include "bvhlab/isa.h"
#include "bvhlab/sah.h"
#include "sah_sweep.h"
#include "sah_sweep_avx2.h"

namespace bvhlab {
namespace {

constexpr std::uint32_t K = kSmallSubtree;
static_assert(K <= 255, "orders are bytes");
constexpr float kInf = std::numeric_limits<float>::infinity();

/// The references of the range: boxes as (lo, -hi), twice the centroids, and their order on
/// each axis (stable: ties keep input order). A node of the subtree owns positions
/// [first, first + count) of all three orders, and its leaves take the same positions.
struct SmallSet {
    std::uint32_t n = 0;
    SmallBox box[K];
    F4 c2[K];
    std::uint32_t ref[K];
    std::uint8_t order[3][K];

    SmallSet(const PrimRef* in, std::uint32_t count) : n(count) {
        for (std::uint32_t i = 0; i < n; ++i) {
            box[i] = {in[i].lo4(), neg(in[i].hi4())}, c2[i] = in[i].lo4() + in[i].hi4();
            ref[i] = in[i].ref;
        }
#if defined(BVHLAB_AVX2_KERNELS)
        if (active_isa() >= Isa::Avx2) {
            avx2::small_ranks(reinterpret_cast<const float*>(c2), n, order);
            return;
        }
#endif
        rank_all();
    }
    /// rank of i = #{j : c2[j] < c2[i], or c2[j] == c2[i] and j < i}, per axis lane.
    void rank_all() {
        const F4 one = F4::splat(1.0f);
        for (std::uint32_t i = 0; i < n; ++i) {
            F4 rank = F4::splat(0.0f);
            for (std::uint32_t j = 0; j < i; ++j) rank = rank + (less_equal(c2[j], c2[i]) & one);
            for (std::uint32_t j = i + 1; j < n; ++j) rank = rank + (less(c2[j], c2[i]) & one);
            std::uint32_t r[4];
            truncate_to_u32(rank, r);
            for (int a = 0; a < 3; ++a) order[a][r[a]] = std::uint8_t(i);
        }
    }
};

/// Copies n bytes between arrays that do not overlap: up to 32 in two moves of 16, 8, 4, 2 or 1
/// bytes, which may overlap each other (a byte at a time cost 4 instructions a byte).
inline void copy_bytes(std::uint8_t* dst, const std::uint8_t* src, std::uint32_t n) {
    struct W16 {
        std::uint64_t a, b;
    };
    const auto two = [&]<class W>(W) {  // the first and the last sizeof(W) bytes
        W head, tail;
        std::memcpy(&head, src, sizeof(W)), std::memcpy(&tail, src + n - sizeof(W), sizeof(W));
        std::memcpy(dst, &head, sizeof(W)), std::memcpy(dst + n - sizeof(W), &tail, sizeof(W));
    };
    for (; n > 32; n -= 16, dst += 16, src += 16) std::memcpy(dst, src, 16);  // K above 32 only
    if (n >= 16) two(W16{});
    else if (n >= 8) two(std::uint64_t{});
    else if (n >= 4) two(std::uint32_t{});
    else if (n >= 2) two(std::uint16_t{});
    else if (n == 1) dst[0] = src[0];
}

/// One node of the subtree still to build: positions, depth, box, and where it hangs.
struct SmallNode {
    std::uint32_t first, count, depth, parent;
    bool second_child;
    F4 lo, neg_hi;
};

/// How a node is split: positions [first, first + last_left] of order[axis] go left.
struct SmallCut {
    int axis = -1;
    std::uint32_t last_left = 0;
    float cost = kInf;
};

/// The builder of one small subtree.
class SmallBuilder {
public:
    SmallBuilder(SubtreeWriter& writer, const BuildConfig& cfg, const WorkItem& item)
        : writer_(writer),
          cfg_(cfg),
          sah_(cfg),
          all_axes_(choose_axis(cfg, Vec3{1.0f, 1.0f, 1.0f}, Range{0, 0}, 0) == kAllAxes),
          begin_(item.range.begin),
          set_(writer.shared().buffers[item.buffer] + item.range.begin, item.range.size()),
          pack_here_(writer.shared().prims && close_together(set_)) {
        if (pack_here_)  // fetched now, the input arrives while the subtree is built
            for (std::uint32_t i = 0; i < set_.n; ++i) prefetch_prim(*writer.shared().geometry, set_.ref[i]);
    }

    void build(const WorkItem& item, std::uint32_t index) {
        const Aabb& b = item.bounds.box;
        const F4 lo = F4::set3(b.lo.x, b.lo.y, b.lo.z), neg_hi = neg(F4::set3(b.hi.x, b.hi.y, b.hi.z));
        SmallNode stack[2 * K];
        std::uint32_t size = 0;
        // The node at hand stays out of the stack: its left child is taken next straight from
        // divide(), only the right one waits there (a node read back from the stack just after
        // its fields were written one by one waits for those stores).
        SmallNode node{0, set_.n, item.depth, item.parent, item.second_child, lo, neg_hi};
        for (std::uint32_t at = index;;) {
            const SmallCut cut = node.count > 1 && !pair_is_leaf(node) ? choose(node) : SmallCut{};
            if (cut.axis >= 0) {
                writer_.make_internal(at);
                SmallNode children[2];
                divide(node, cut, at, children);
                stack[size++] = children[1];
                node = children[0];
            } else {
                make_leaf(at, node);
                if (size == 0) break;
                node = stack[--size];
            }
            at = writer_.open(to_aabb(node.lo, neg(node.neg_hi)), node.depth, node.parent, node.second_child);
        }
        if (!pack_here_ && writer_.shared().prims) writer_.pack_later(begin_, set_.n);
    }

private:
    /// choose()'s answer "a leaf" for a node of two references, without its fallbacks: every cut
    /// of two references costs the same (SahCost::split is symmetric), so any axis's order will do.
    bool pair_is_leaf(const SmallNode& node) const {
        return node.count == 2 && cfg_.max_leaf_size >= 2 && sah_.leaf(2) <= pair_cost(0, node);
    }
    /// The cost of splitting a node of two references, its two in order[axis], one to a side:
    /// cut_at(axis, node, 0) bit for bit (a min with an empty box gives the other box), without its loops.
    float pair_cost(int axis, const SmallNode& node) const {
        const std::uint8_t a = set_.order[axis][node.first], b = set_.order[axis][node.first + 1];
        const float inv = SahCost::inverse_area(half_area(node.lo, neg(node.neg_hi)));
        return sah_.split(inv, half_area(set_.box[a].lo, neg(set_.box[a].neg_hi)), 1,
                          half_area(set_.box[b].lo, neg(set_.box[b].neg_hi)), 1);
    }
    SmallCut choose(const SmallNode& node) const;
    SmallCut cheapest(const SmallNode& node, const bool allowed[3]) const;
    static SmallCut cheapest_of(const LaneMin& cheapest, const bool allowed[3]);
    SmallCut cut_at(int axis, const SmallNode& node, std::uint32_t last_left) const;
    void divide(const SmallNode& node, const SmallCut& cut, std::uint32_t at, SmallNode children[2]);
    void make_leaf(std::uint32_t at, const SmallNode& node) {
        std::uint32_t* out = writer_.make_leaf(at, begin_ + node.first, node.count);
        for (std::uint32_t j = 0; j < node.count; ++j) out[j] = set_.ref[set_.order[0][node.first + j]];
        // Packed as each leaf is made, the packing's loads and stores overlap the builder's work
        // (at the subtree's end, in one run, the build took 0.7 ms longer on Sponza).
        const BuildShared& shared = writer_.shared();
        if (pack_here_) pack_run(*shared.geometry, out, node.count, shared.prims + begin_ + node.first, true);
    }

    /// Whether the references lie within kCloseTogether of each other (a sphere's reference bit
    /// puts it far from any triangle): then the subtree fetches their input when it starts and
    /// packs each leaf as it is made (BuildShared::prims). Input visited at random (uniform1m:
    /// 1M triangles in random order) is packed faster afterwards in one stream: packing it here
    /// cost 7%. The bound, 65,536 triangles (2.4 MB of input), takes most of Sponza's subtrees;
    /// 4,096 took too few to gain and 256 lost 1.5% to the many short runs packed after.
    static bool close_together(const SmallSet& set) {
        std::uint32_t lo = set.ref[0], hi = set.ref[0];
        for (std::uint32_t i = 1; i < set.n; ++i) lo = std::min(lo, set.ref[i]), hi = std::max(hi, set.ref[i]);
        return hi - lo < kCloseTogether;
    }
    static constexpr std::uint32_t kCloseTogether = 65536;

    SubtreeWriter& writer_;
    const BuildConfig& cfg_;
    const SahCost sah_;
    /// The policy sweeps every axis at every node (Best, and Auto for the SAH methods: choose_axis
    /// gives kAllAxes whatever the node), so choose_axis need not be asked per node.
    const bool all_axes_;
    /// The AVX2 sweep, asked once a subtree (active_isa() is a call and an atomic load).
    const bool avx2_ = active_isa() >= Isa::Avx2;
    const std::uint32_t begin_;
    SmallSet set_;
    const bool pack_here_;
};

/// The split (or nothing, for a leaf) of one node: the cheapest cut on the axes the policy
/// allows, with the fallbacks of the top-down builder (subtree_builder.cpp's find_split).
SmallCut SmallBuilder::choose(const SmallNode& node) const {
    const std::uint32_t f = node.first, m = node.count;
    // The centroid extent as NodeBounds::centroids gives it (halved twice-centroids).
    const F4 half = F4::splat(0.5f);
    Vec3 extent;
    for (int a = 0; a < 3; ++a)
        extent[a] = (set_.c2[set_.order[a][f + m - 1]] * half - set_.c2[set_.order[a][f]] * half).lane(a);
    SmallCut best;
    if (!(extent.x > 0.0f || extent.y > 0.0f || extent.z > 0.0f)) {
        best = cut_at(0, node, m / 2 - 1);  // every centroid the same: an even split
    } else if (too_deep(node.depth, m)) {
        best = cut_at(largest_axis(extent), node, m / 2 - 1);
    } else if (m == 2) {
        const int axis = largest_axis(extent);
        best = {axis, 0, pair_cost(axis, node)};  // one way to split, whatever the axis
    } else {
        const Range r{begin_ + f, begin_ + f + m};
        const int axis = all_axes_ ? kAllAxes : choose_axis(cfg_, extent, r, node.depth);
        bool allowed[3];
        for (int a = 0; a < 3; ++a) allowed[a] = (axis == kAllAxes || a == axis) && extent[a] > 0.0f;
        best = cheapest(node, allowed);
        if (best.axis < 0) best = cut_at(0, node, m / 2 - 1);
    }
    // SAH leaf termination (report §5.1, PBRT): a leaf when intersecting all costs no more.
    if (m <= cfg_.max_leaf_size && sah_.leaf(m) <= best.cost) return {};
    return best;
}

/// The exact SAH sweep (report §2.3.2) on the three sorted orders at once, one vector lane per
/// axis: a suffix pass of right-side areas, then a prefix pass that prices every candidate with
/// SahCost::split's operations (bit for bit). Ties: the first candidate of an axis, then the
/// first axis.
SmallCut SmallBuilder::cheapest(const SmallNode& node, const bool allowed[3]) const {
    const std::uint32_t f = node.first, m = node.count;
    const std::uint8_t* order[3] = {set_.order[0] + f, set_.order[1] + f, set_.order[2] + f};
    const float inv = SahCost::inverse_area(half_area(node.lo, neg(node.neg_hi)));
    const std::uint32_t mask = sah_.round_mask(m);
    LaneMin cheapest;  // keyed by the left count, c + 1
#if defined(BVHLAB_AVX2_KERNELS)
    if (avx2_) {
        alignas(16) float cost[4], key[4];
        avx2::small_sweep(set_.box, order, m, {sah_.traversal, sah_.intersection, inv, mask}, cost, key);
        cheapest.cost = F4::load(cost), cheapest.key = F4::load(key);
        return cheapest_of(cheapest, allowed);
    }
#endif
    auto grow = [&](AxisBoxes& box, std::uint32_t j) {
        const std::uint8_t x = order[0][j], y = order[1][j], z = order[2][j];
        const SmallBox &bx = set_.box[x], &by = set_.box[y], &bz = set_.box[z];
        box.grow(bx.lo, bx.neg_hi, by.lo, by.neg_hi, bz.lo, bz.neg_hi);
    };
    F4 right_area[K];  // candidate c: the right side is [c + 1, m)
    AxisBoxes box;
    for (std::uint32_t j = m - 1; j > 0; --j) grow(box, j), right_area[j - 1] = box.half_areas();
    const LaneSplitCost price(sah_, inv);
    box = AxisBoxes();
    for (std::uint32_t c = 0; c + 1 < m; ++c) {
        grow(box, c);
        const std::uint32_t n_left = SahCost::counted(c + 1, mask), n_right = SahCost::counted(m - c - 1, mask);
        cheapest.offer(price(box.half_areas(), F4::splat(float(n_left)), right_area[c], F4::splat(float(n_right)),
                             [&] { return F4::splat(float(n_left + n_right)); }),
                       F4::splat(float(c + 1)));
    }
    return cheapest_of(cheapest, allowed);
}

/// The cheapest cut among the allowed axes' cheapest candidates (ties: the first axis).
SmallCut SmallBuilder::cheapest_of(const LaneMin& cheapest, const bool allowed[3]) {
    std::uint32_t lefts[4];
    truncate_to_u32(cheapest.key, lefts);
    SmallCut best;
    for (int a = 0; a < 3; ++a)
        if (allowed[a] && cheapest.cost.lane(a) < best.cost) best = {a, lefts[a] - 1, cheapest.cost.lane(a)};
    return best;
}

SmallCut SmallBuilder::cut_at(int axis, const SmallNode& node, std::uint32_t last_left) const {
    const std::uint8_t* order = set_.order[axis] + node.first;
    F4 llo = F4::splat(kInf), lnh = llo, rlo = llo, rnh = llo;
    for (std::uint32_t j = 0; j <= last_left; ++j)
        llo = min(llo, set_.box[order[j]].lo), lnh = min(lnh, set_.box[order[j]].neg_hi);
    for (std::uint32_t j = last_left + 1; j < node.count; ++j)
        rlo = min(rlo, set_.box[order[j]].lo), rnh = min(rnh, set_.box[order[j]].neg_hi);
    const float inv = SahCost::inverse_area(half_area(node.lo, neg(node.neg_hi)));
    const float cost =
        sah_.split(inv, half_area(llo, neg(lnh)), last_left + 1, half_area(rlo, neg(rnh)), node.count - last_left - 1);
    return {axis, last_left, cost};
}

/// Divides the node's positions: the cut's order as it is, the other two orders stably by side.
void SmallBuilder::divide(const SmallNode& node, const SmallCut& cut, std::uint32_t at, SmallNode children[2]) {
    const std::uint32_t f = node.first, m = node.count, n_left = cut.last_left + 1;
    bool left_of[K];
    const std::uint8_t* by_cut = set_.order[cut.axis] + f;
    // Each side's box in registers: a record joins both, raised to +inf for the side it is not on
    // (max with -inf keeps it as it is), so no side is picked by an index into memory, which made
    // each record wait for the last one's store.
    static const F4 kGate[2] = {F4::splat(-kInf), F4::splat(kInf)};
    F4 box[2][2] = {{F4::splat(kInf), F4::splat(kInf)}, {F4::splat(kInf), F4::splat(kInf)}};
    for (std::uint32_t j = 0; j < m; ++j) {
        const std::uint8_t i = by_cut[j];
        const bool left = j < n_left;
        left_of[i] = left;
        const F4 to_left = kGate[!left], to_right = kGate[left];
        const SmallBox& b = set_.box[i];
        box[0][0] = min(box[0][0], max(b.lo, to_left));
        box[0][1] = min(box[0][1], max(b.neg_hi, to_left));
        box[1][0] = min(box[1][0], max(b.lo, to_right));
        box[1][1] = min(box[1][1], max(b.neg_hi, to_right));
    }
    for (int a = 0; a < 3; ++a) {
        if (a == cut.axis) continue;
        std::uint8_t* order = set_.order[a] + f;
        std::uint8_t right[K];
        std::size_t l = 0;                     // 64-bit indices: no zero extension at each address
        for (std::size_t j = 0; j < m; ++j) {  // both stores, one cursor moves: no branch on the side
            const std::uint8_t i = order[j];
            order[l] = i, right[j - l] = i;  // j - l: the right ones so far
            l += left_of[i];
        }
        copy_bytes(order + l, right, std::uint32_t(m - l));
    }
    const std::uint32_t d = node.depth + 1;
    children[0] = {f, n_left, d, at, false, box[0][0], box[0][1]};
    children[1] = {f + n_left, m - n_left, d, at, true, box[1][0], box[1][1]};
}

}  // namespace

std::uint32_t small_subtree_size(const BuildConfig& config) {
    switch (config.method) {
        case SplitMethod::SweepSah:
            return kSmallSubtree;
        case SplitMethod::Sah:
            return config.bin_bounds == BinBounds::Box ? kSmallSubtree : kSmallExactReport;
        default:
            return 0;
    }
}

void build_small_subtree(SubtreeWriter& writer, const BuildConfig& cfg, const WorkItem& item, std::uint32_t index) {
    SmallBuilder(writer, cfg, item).build(item, index);
}

}  // namespace bvhlab
