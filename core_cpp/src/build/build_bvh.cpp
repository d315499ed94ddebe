// build_bvh.cpp — build_bvh: input checks, primitive references, the top-down build (the top of
// the tree with every thread on each node, then the subtrees below on the pool), and the
// finishing touches (skip indices, leaf-ordered geometry).
#include <algorithm>
#include <chrono>
#include <exception>
#include <stdexcept>

#include "assemble.h"
#include "deferred_parts.h"
#include "bvhlab/bvh.h"
#include "bvhlab/cancel.h"
#include "bvhlab/thread_pool.h"
#include "bvhlab/work_trace.h"
#include "morton.h"
#include "sbvh/sbvh_builder.h"
#include "small_subtree.h"
#include "subtree_builder.h"

namespace bvhlab {
namespace {

using Clock = std::chrono::steady_clock;

/// The stop check of one build: runs the caller's progress callback (on the calling thread,
/// every 20 ms at most) with the fraction of primitives already in leaves. An exception from the
/// callback stops the build and is rethrown once every thread has stopped.
class BuildStop {
public:
    BuildStop(const BuildConfig& cfg, std::size_t total)
        : cancel_(cfg.progress ? Cancellation::Check([this, &cfg, total] { return !report(cfg, total); })
                               : Cancellation::Check()) {}
    Cancellation& cancel() { return cancel_; }
    std::atomic<std::uint64_t>& in_leaves() { return in_leaves_; }
    [[noreturn]] void rethrow() const {
        if (callback_error_) std::rethrow_exception(callback_error_);
        throw BuildCancelled();
    }

private:
    bool report(const BuildConfig& cfg, std::size_t total) {
        try {
            return cfg.progress(total ? double(in_leaves_.load(std::memory_order_relaxed)) / double(total) : 1.0);
        } catch (...) {
            callback_error_ = std::current_exception();
            return false;
        }
    }
    std::atomic<std::uint64_t> in_leaves_{0};
    std::exception_ptr callback_error_;
    Cancellation cancel_;
};

/// The largest range left whole to one thread of the pool. Not so small that the parts are too
/// many (n / 8T), and, where the parts stay at least 2T (balance), no node above it smaller than
/// two chunked passes' minimum (Sponza, 2 threads: defer at n / 16 = 16K left the top at 9.3 ms,
/// against 4.5 ms at 64K; the build 40.8 → 38.4 ms, when the calling thread split the nodes of
/// the top below kMinParallelRange alone; now one task of the pool splits each down to this size,
/// SubtreeRun::serial_below and build_deferred).
std::uint32_t defer_size_for(std::uint32_t n, unsigned threads) {
    const std::uint32_t balanced = n / (2 * threads), chunked = 2 * kMinParallelRange;
    return std::max({1024u, n / (8 * threads), std::min(chunked, balanced)});
}

/// The size of the parts the threads share below the top (build_deferred splits the top's deferred
/// ranges down to it): a quarter of the top's, so that each thread has many and they end
/// together. Two threads, idle at the end of the parts (both threads' summed, at defer_size and
/// at this): Sponza 1.4 → 0.4 ms, room1m 3.3 → 0.4 ms, uniform1m 5.5 → 1.3 ms.
std::uint32_t part_size_for(std::uint32_t defer_size) { return std::max(1024u, defer_size / 4); }

/// Builds the tree over prim_refs into `out`; packs out.prims too where `pack` (see BuildShared).
/// `summary`: the bounds make_prim_refs took of them.
void build_tree(BigVector<PrimRef>& prim_refs, const PrimRefsSummary& summary, const GeometryView& geometry, bool pack,
                const BuildConfig& cfg, BuildStop& stop, Bvh& out) {
    out.refs.resize(prim_refs.size());
    if (prim_refs.empty()) return;
    const auto n = static_cast<std::uint32_t>(prim_refs.size());
    const unsigned threads = ThreadPool::resolve(cfg.threads);
    BigVector<PrimRef> other(n);  // not zeroed (BigAllocator): every slot is written before it is read
    const std::function<void()> poll = [&] { stop.cancel().poll(); };
    const ParallelPasses parallel{&ThreadPool::shared(), threads, &poll, n, &stop.cancel()};
    const SplitMethodInfo& method = method_info(cfg.method);
    SplitScratch scratch;
    SplitContext ctx{{prim_refs.data(), other.data()}, cfg, scratch, &parallel};
    if (method.needs_morton_presort) {
        sort_by_morton_code(prim_refs, bounds_of(ctx, {0, n}, 0, false).centroids, threads, &stop.cancel());
        if (stop.cancel().stop_requested()) stop.rethrow();  // the references may be unsorted
        ctx.buffers[0] = prim_refs.data();                   // the sort may have swapped the storage
    }
    // The root's bounds come from make_prim_refs' pass, but for a method that also sums the
    // centroids (and LBVH, which sorted the references in between)
    WorkItem root{{0, n}, {}, 0, 0, false, 0};
    if (method.needs_centroid_sum || method.needs_morton_presort) {
        root.bounds = bounds_of(ctx, {0, n}, 0, method.needs_centroid_sum);
    } else {
        root.bounds.box = summary.box, root.bounds.centroids = summary.centroids;
    }
    BuildShared shared{{prim_refs.data(), other.data()}, out.refs.data(), cfg, method, stop.cancel(), stop.in_leaves()};
    if (pack) {
        out.prims = BigVector<PackedPrim>(n);  // every element written by the leaves (WrittenBeforeRead)
        shared.geometry = &geometry, shared.prims = out.prims.data();
    }

    // With several threads, ranges of at most `defer_size` primitives are left to the pool; the
    // nodes above them are split with every thread on each, but for those too small to cut into
    // chunks, which the pool splits one per task. The tree is the same either way.
    const std::uint32_t defer_size = threads > 1 ? defer_size_for(n, threads) : 0;
    const std::uint32_t serial_below = threads > 1 ? kMinParallelRange : 0;
    Subtree top;
    BVHLAB_WORK_MARK("phase top");  // each phase mark ends the serial part of the one before
    build_subtree(shared, scratch, root, top, {defer_size, true, &parallel, serial_below});
    // the full sweep's copies of the largest node's references (2M: 2 × 64 MB), not kept through
    // the phases below
    std::vector<PrimRef>().swap(scratch.sorted), std::vector<PrimRef>().swap(scratch.merged);
    BVHLAB_WORK_MARK("phase deferred");
    if (!top.deferred.empty() && !stop.cancel().stop_requested())
        build_deferred(shared, top, part_size_for(defer_size), threads, poll);
    if (stop.cancel().stop_requested()) stop.rethrow();
    BVHLAB_WORK_MARK("phase pack");
    pack_unpacked(shared, top);
    BVHLAB_WORK_MARK("phase assemble");
    if (top.deferred.empty()) {
        if (method.bottom_up_boxes) fill_boxes_from_children(top.nodes);
        out.nodes = std::move(top.nodes);
        out.depths = std::move(top.depths);
    } else {
        assemble(top, threads, method.bottom_up_boxes, out);
    }
}

}  // namespace

Bvh build_bvh(const GeometryView& geometry, const BuildConfig& config) {
    validate(config);  // the geometry is checked while its references are made
    auto start = Clock::now();
    Bvh bvh;
    bvh.triangle_count = static_cast<std::uint32_t>(geometry.triangle_count);
    bvh.sphere_count = static_cast<std::uint32_t>(geometry.sphere_count);
    bvh.config = config;
    bvh.config.progress = nullptr;

    // Cancellation is checked between the phases too: none of them takes long.
    BuildStop stop(config, geometry.primitive_count());
    auto check = [&] {
        if (stop.cancel().poll()) stop.rethrow();
    };
    check();
    BVHLAB_WORK_MARK("phase refs");
    // The references, the fingerprint and the root's bounds in one pass over the input, in
    // chunks on the pool, polling for a stop between chunks (check() below rethrows it).
    PrimRefsSummary summary;
    BigVector<PrimRef> prim_refs = make_prim_refs(geometry, config.threads, &summary, &stop.cancel());
    bvh.set_fingerprint(summary.fingerprint);
    check();
    BVHLAB_WORK_MARK("phase tree");
    if (config.method == SplitMethod::Sbvh) {  // its own builder: references may repeat
        build_sbvh(prim_refs, geometry, config, stop.cancel(), stop.in_leaves(), bvh);
        check();
        bvh.build_ms = std::chrono::duration<double, std::milli>(Clock::now() - start).count();
        if (config.progress && !config.progress(1.0)) throw BuildCancelled();
        return bvh;
    }
    // The leaves pack their geometry where the small-subtree builder makes them (it fetches the
    // input ahead); the other methods' trees are packed after, in leaf order.
    const bool pack_in_build = small_subtree_size(config) > 0;
    build_tree(prim_refs, summary, geometry, pack_in_build, config, stop, bvh);
    check();
    BVHLAB_WORK_MARK("phase finish");
    if (!pack_in_build) bvh.prims = pack_prims(geometry, bvh.refs, config.threads);
    bvh.build_ms = std::chrono::duration<double, std::milli>(Clock::now() - start).count();
    BVHLAB_WORK_MARK("phase end");
    if (config.progress && !config.progress(1.0)) throw BuildCancelled();  // the last word may be "stop"
    return bvh;
}

Bvh build_bvh_over_boxes(const Aabb* boxes, std::size_t count, const BuildConfig& config) {
    validate(config);
    if (count > gpu::REF_INDEX_MASK) throw std::invalid_argument("too many boxes for one tree");
    auto start = Clock::now();
    Bvh bvh;
    bvh.config = config;
    bvh.config.progress = nullptr;
    // boxes have no shape to clip: an SBVH over boxes is the binned SAH tree
    if (bvh.config.method == SplitMethod::Sbvh) bvh.config.method = SplitMethod::Sah;
    BuildStop stop(config, count);
    // The references and their bounds, as make_prim_refs gathers them for primitives.
    PrimRefsSummary summary;
    BigVector<PrimRef> prim_refs(count);
    for (std::size_t i = 0; i < count; ++i) {
        const Aabb& b = boxes[i];
        prim_refs[i] = PrimRef{{b.lo.x, b.lo.y, b.lo.z}, static_cast<std::uint32_t>(i), {b.hi.x, b.hi.y, b.hi.z}, 0};
        summary.box.grow(b);
        summary.centroids.grow(prim_refs[i].centroid());
    }
    build_tree(prim_refs, summary, GeometryView{}, false, bvh.config, stop, bvh);
    if (stop.cancel().poll()) stop.rethrow();
    bvh.build_ms = std::chrono::duration<double, std::milli>(Clock::now() - start).count();
    return bvh;
}

}  // namespace bvhlab
