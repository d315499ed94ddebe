#include "subtree_builder.h"

#include <bit>

#include "small_subtree.h"
#include "subtree_writer.h"

namespace bvhlab {
namespace {

std::uint64_t mix(std::uint64_t x) {  // splitmix64 finaliser
    x ^= x >> 30, x *= 0xbf58476d1ce4e5b9ull;
    x ^= x >> 27, x *= 0x94d049bb133111ebull;
    return x ^ (x >> 31);
}

}  // namespace

int choose_axis(const BuildConfig& cfg, Vec3 extent, Range range, std::uint32_t depth) {
    switch (cfg.axis) {
        case AxisPolicy::Auto:
            return method_info(cfg.method).uses_sah ? kAllAxes : largest_axis(extent);
        case AxisPolicy::Largest:
            return largest_axis(extent);
        case AxisPolicy::Best:
            return kAllAxes;
        case AxisPolicy::Random: {
            int axes[3], n = 0;
            for (int a = 0; a < 3; ++a)
                if (extent[a] > 0.0f) axes[n++] = a;
            if (n == 0) return largest_axis(extent);
            std::uint64_t h = mix(cfg.seed ^ mix(range.begin ^ (std::uint64_t(range.end) << 32)) ^ depth);
            return axes[h % n];
        }
    }
    return 0;
}

namespace {

/// Two primitives: every method splits them 1 | 1; order them by centroid on the largest axis.
Split split_pair(SplitContext& ctx, const WorkItem& item) {
    PrimRef* p = ctx.buffers[item.buffer] + item.range.begin;
    int axis = largest_axis(item.bounds.centroids.extent());
    if (p[1].centroid(axis) < p[0].centroid(axis)) std::swap(p[0], p[1]);
    Split s;
    s.mid = item.range.begin + 1;
    s.left = {p[0].box(), {p[0].centroid(), p[0].centroid()}};
    s.right = {p[1].box(), {p[1].centroid(), p[1].centroid()}};
    s.cost = SahCost(ctx.config)
                 .split(SahCost::inverse_area(item.bounds.box.half_area()), s.left.box.half_area(), 1,
                        s.right.box.half_area(), 1);
    s.buffer = item.buffer;
    return s;
}

/// The median split on the largest centroid extent (or an even split when all centroids coincide).
Split median_of(SplitContext& ctx, Range r, int src, const NodeBounds& b) {
    const Vec3 extent = b.centroids.extent();
    if (!(extent.x > 0.0f || extent.y > 0.0f || extent.z > 0.0f)) return split_even(ctx, r, src, b);
    return *split_median(ctx, r, src, b, largest_axis(extent));
}

/// Writes the split of a range to `out` (in place: a Split is 192 bytes, see split_common.cpp's
/// write_bounds on why it is never assembled and copied).
void find_split(SplitContext& ctx, const WorkItem& item, Split& out) {
    const Range r = item.range;
    const int src = item.buffer;
    const NodeBounds& b = item.bounds;
    const SplitMethodInfo& method = method_info(ctx.config.method);
    if (r.size() == 2) return void(out = split_pair(ctx, item));
    if (method.bottom_up_boxes) {  // no bounds on the way down; the rare depth fallback makes its own
        if (too_deep(item.depth, r.size())) return void(out = median_of(ctx, r, src, bounds_of(ctx, r, src, false)));
    } else {
        const Vec3 extent = b.centroids.extent();
        if (!(extent.x > 0.0f || extent.y > 0.0f || extent.z > 0.0f)) return void(out = split_even(ctx, r, src, b));
        if (too_deep(item.depth, r.size())) return void(out = median_of(ctx, r, src, b));
    }

    const int axis = method.bottom_up_boxes ? kAllAxes  // LBVH has no axis
                                            : choose_axis(ctx.config, b.centroids.extent(), r, item.depth);
    const std::optional<Split> s = axis == kAllAxes && !method.all_axes
                                       ? split_best_of_axes(method.split, ctx, r, src, b)
                                       : method.split(ctx, r, src, b, axis);
    if (s) out = *s;
    else out = split_even(ctx, r, src, b);
}

}  // namespace

bool choose_split(SplitContext& ctx, const WorkItem& item, Split& out) {
    const BuildConfig& cfg = ctx.config;
    const std::uint32_t n = item.range.size();
    if (n <= 1) return false;
    const bool fits_leaf = n <= cfg.max_leaf_size;
    const bool weighs_leaves = method_info(cfg.method).uses_sah;
    if (fits_leaf && !weighs_leaves) return false;
    // SAH leaf termination (report §5.1, PBRT): a range that may be a leaf becomes one when
    // intersecting all of it costs no more than the best split. The SAH methods answer that
    // themselves before they move anything (Split::leaf); the check after covers the fallbacks.
    ctx.leaf_allowed = fits_leaf;
    find_split(ctx, item, out);
    return !(out.leaf || (fits_leaf && SahCost(cfg).leaf(n) <= out.cost));
}

void SubtreeWriter::make_leaf(std::uint32_t index, const WorkItem& item) {
    const Range r = item.range;
    std::uint32_t* out = make_leaf(index, r.begin, r.size());
    const PrimRef* refs = shared_.buffers[item.buffer];
    for (std::uint32_t i = r.begin; i < r.end; ++i) out[i - r.begin] = refs[i].ref;
    if (shared_.prims) pack_later(r.begin, r.size());
    if (!shared_.method.bottom_up_boxes) return;
    F4 lo = refs[r.begin].lo4(), hi = refs[r.begin].hi4();
    for (std::uint32_t i = r.begin + 1; i < r.end; ++i) lo = min(lo, refs[i].lo4()), hi = max(hi, refs[i].hi4());
    set_box(out_.nodes[index], to_aabb(lo, hi));
}

namespace {

/// A range that is a leaf without asking the split method: one primitive, or few enough for a
/// leaf under a method that does not weigh leaves against splits.
bool obviously_leaf(const BuildShared& shared, std::uint32_t n) {
    return n == 1 || (n <= shared.config.max_leaf_size && !shared.method.uses_sah);
}

/// Nodes of at least this many references are each preceded by a stop check (should_stop).
constexpr std::uint32_t kStopCheckRange = 1u << 16;

/// True when the build should stop: polls the cancellation on the calling thread (which runs
/// the caller's progress check at most every 20 ms), reads the flag on workers.
bool should_stop(BuildShared& shared, const SubtreeRun& run) {
    return run.calling_thread ? shared.cancel.poll() : shared.cancel.stop_requested();
}

}  // namespace

namespace {

/// Replaces the item on top of the stack (the node `index`) with its children: the right one in
/// its place, the left one above it, so that the left subtree is built first. Children that
/// are plainly leaves (most leaves) are written at once, without a work item.
void replace_by_children(SubtreeWriter& writer, std::vector<WorkItem>& stack, const Split& split, std::uint32_t index) {
    const Range r = stack.back().range;
    const std::uint32_t d = stack.back().depth + 1;
    const WorkItem left{{r.begin, split.mid}, split.left, index, d, false, split.buffer};
    const WorkItem right{{split.mid, r.end}, split.right, index, d, true, split.buffer};
    if (!obviously_leaf(writer.shared(), left.range.size())) {
        stack.back() = right;
        stack.push_back(left);
        return;
    }
    writer.make_leaf(writer.open(left), left);
    if (!obviously_leaf(writer.shared(), right.range.size())) return void(stack.back() = right);
    stack.pop_back();
    writer.make_leaf(writer.open(right), right);
}

}  // namespace

void pack_unpacked(const BuildShared& shared, const Subtree& subtree) {
    if (!shared.prims) return;
    for (const Range r : subtree.unpacked)
        pack_run(*shared.geometry, shared.leaf_refs + r.begin, r.size(), shared.prims + r.begin);
}

void build_subtree(BuildShared& shared, SplitScratch& scratch, const WorkItem& root, Subtree& out,
                   const SubtreeRun& run) {
    SplitContext ctx{{shared.buffers[0], shared.buffers[1]}, shared.config, scratch, run.parallel};
    SubtreeWriter writer(shared, out);
    // A binary tree with n leaves has 2n - 1 nodes at most. A subtree that defers ranges of up to
    // defer_size has about 2n / defer_size (more where splits are uneven: the arrays then grow);
    // reserved for 2n - 1, its blocks, barely touched, would pass to arrays that fill them.
    const std::size_t n = root.range.size(), most = 2 * n - 1;
    out.nodes.reserve(run.defer_size ? std::min(most, 8 * n / run.defer_size + 64) : most);
    out.depths.reserve(out.nodes.capacity());
    std::vector<WorkItem> stack{root};
    const std::uint32_t small_size = small_subtree_size(shared.config);
    Split split;
    for (std::uint32_t nodes = 0; !stack.empty(); ++nodes) {
        // every 64 nodes, and before each large one: 64 nodes at the top of a tree are most of its
        // work (a full-sweep SAH build of 2M references, two threads: 3.1 s between stop checks)
        if ((nodes & 63) == 0 || stack.back().range.size() >= kStopCheckRange) {
            writer.flush_leaf_count();
            if (should_stop(shared, run)) return;
        }
        // The item stays on the stack, read in place, until its children replace it.
        WorkItem& item = stack.back();
        const std::uint32_t index = writer.open(item);
        if (index > 0 && (item.range.size() <= run.defer_size || item.range.size() < run.serial_below)) {
            // its buckets, in this thread's store, go with it
            out.deferred.push_back({index, item, carry_bins(scratch, item.bounds.bins)});
            out.deferred.back().item.bounds.bins = -1;
        } else if (item.range.size() >= 2 && item.range.size() <= small_size) {  // the last levels at once
            build_small_subtree(writer, shared.config, item, index);
        } else {
            ctx.child_slot = static_cast<std::uint32_t>(stack.size() - 1);  // where the children will be
            if (!obviously_leaf(shared, item.range.size()) && choose_split(ctx, item, split)) {
                writer.make_internal(index);
                replace_by_children(writer, stack, split, index);
                continue;
            }
            writer.make_leaf(index, item);
        }
        stack.pop_back();
    }
    if (!out.nodes.empty()) writer.close_spine(0, static_cast<std::uint32_t>(out.nodes.size()));  // the root's
}

}  // namespace bvhlab
