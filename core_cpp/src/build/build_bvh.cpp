// build_bvh.cpp — build_bvh: input checks, primitive references, the top-down build (on several threads when
// asked), and the finishing touches (skip indices, leaf-ordered geometry).
#include <chrono>
#include <memory>
#include <mutex>
#include <stdexcept>
#include <thread>

#include "bvhlab/bvh.h"
#include "bvhlab/cancel.h"
#include "morton.h"
#include "subtree_builder.h"

namespace bvhlab {
namespace {

using Clock = std::chrono::steady_clock;

std::uint32_t thread_count(const BuildConfig& cfg) {
    if (cfg.threads > 0) return cfg.threads;
    return std::max(1u, std::thread::hardware_concurrency());
}

/// Calls the user's progress callback at most every 50 ms, from the calling thread only.
class ProgressReporter {
public:
    ProgressReporter(BuildShared& shared, std::size_t total) : shared_(shared), total_(total) {}
    void operator()() {
        if (!shared_.config.progress) return;
        auto now = Clock::now();
        if (now - last_ < std::chrono::milliseconds(50)) return;
        last_ = now;
        double done = total_ ? double(shared_.primitives_in_leaves.load()) / double(total_) : 1.0;
        if (!shared_.config.progress(done)) shared_.cancelled = true;
    }

private:
    BuildShared& shared_;
    std::size_t total_;
    Clock::time_point last_{};  // the first check reports at once
};

/// Builds the deferred ranges of `top` on `threads` threads; results in the order of top.deferred.
std::vector<Subtree> build_deferred(BuildShared& shared, const Subtree& top, std::uint32_t threads,
                                    ProgressReporter& progress) {
    std::vector<Subtree> parts(top.deferred.size());
    std::atomic<std::size_t> next{0};
    auto worker = [&](bool reports) {
        SplitScratch scratch;
        for (std::size_t k; (k = next.fetch_add(1)) < parts.size() && !shared.cancelled;) {
            WorkItem root = top.deferred[k].second;
            root.second_child = false;  // its parent lives in `top`, which already points at it
            build_subtree(shared, scratch, root, parts[k], 0, [&] { if (reports) progress(); });
            if (reports) progress();
        }
    };
    std::vector<std::thread> pool;
    for (std::uint32_t t = 1; t < threads; ++t) pool.emplace_back(worker, false);
    worker(true);
    for (auto& t : pool) t.join();
    return parts;
}

/// Splices the deferred subtrees into the placeholders of `top`, keeping depth-first order.
void assemble(Subtree& top, std::vector<Subtree>& parts, Bvh& out) {
    std::size_t total = top.nodes.size();
    for (auto& p : parts) total += p.nodes.size() - 1;
    // final index of each top node: shifted by the extra nodes of the placeholders before it
    std::vector<std::uint32_t> final_index(top.nodes.size());
    std::vector<int> part_of(top.nodes.size(), -1);
    for (std::size_t k = 0; k < top.deferred.size(); ++k) part_of[top.deferred[k].first] = int(k);
    std::uint32_t shift = 0;
    for (std::size_t i = 0; i < top.nodes.size(); ++i) {
        final_index[i] = std::uint32_t(i) + shift;
        if (part_of[i] >= 0) shift += std::uint32_t(parts[part_of[i]].nodes.size() - 1);
    }
    out.nodes.resize(total);
    out.depths.resize(total);
    for (std::size_t i = 0; i < top.nodes.size(); ++i) {
        std::uint32_t base = final_index[i];
        if (part_of[i] < 0) {
            BvhNode n = top.nodes[i];
            if (!is_leaf(n)) n.index = final_index[n.index];
            out.nodes[base] = n;
            out.depths[base] = top.depths[i];
            continue;
        }
        const Subtree& p = parts[part_of[i]];
        for (std::size_t j = 0; j < p.nodes.size(); ++j) {
            BvhNode n = p.nodes[j];
            if (!is_leaf(n)) n.index += base;
            out.nodes[base + j] = n;
            out.depths[base + j] = p.depths[j];
        }
    }
}

/// Skip index of every internal node: the skip of its second child (leaves skip to i + 1).
void fill_skip_indices(BigVector<BvhNode>& nodes) {
    for (std::size_t i = nodes.size(); i-- > 0;) {
        BvhNode& n = nodes[i];
        if (is_leaf(n)) continue;
        n.info = gpu::NODE_INTERNAL_BIT | skip_index(nodes[n.index], n.index);
    }
}

void build_tree(BigVector<PrimRef>& prim_refs, const BuildConfig& cfg, Bvh& out) {
    out.refs.resize(prim_refs.size());
    if (prim_refs.empty()) return;
    const auto n = static_cast<std::uint32_t>(prim_refs.size());
    WorkItem root{{0, n}, bounds_of(prim_refs.data(), n), 0, 0, false, 0};
    if (cfg.method == SplitMethod::Lbvh) sort_by_morton_code(prim_refs, root.bounds.centroids);

    BigVector<PrimRef> other(n);  // not zeroed (BigAllocator): every slot is written before it is read
    BuildShared shared{{prim_refs.data(), other.data()}, out.refs.data(), cfg};
    ProgressReporter progress(shared, n);
    const std::uint32_t threads = thread_count(cfg);
    // With several threads, the top of the tree is built here and ranges of at most
    // `defer_size` primitives are left to the pool; the tree is the same either way.
    const std::uint32_t defer_size = threads > 1 ? std::max<std::uint32_t>(1024, n / (8 * threads)) : 0;
    SplitScratch scratch;
    Subtree top;
    build_subtree(shared, scratch, root, top, defer_size, [&] { progress(); });
    std::vector<Subtree> parts;
    if (!top.deferred.empty() && !shared.cancelled) parts = build_deferred(shared, top, threads, progress);
    if (shared.cancelled) throw BuildCancelled();
    if (parts.empty()) {
        out.nodes = std::move(top.nodes);
        out.depths = std::move(top.depths);
    } else {
        assemble(top, parts, out);
    }
    fill_skip_indices(out.nodes);
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

    BigVector<PrimRef> prim_refs = make_prim_refs(geometry);
    build_tree(prim_refs, config, bvh);
    bvh.prims = pack_prims(geometry, bvh.refs);
    bvh.geometry_fingerprint = bvhlab::geometry_fingerprint(geometry);
    bvh.build_ms = std::chrono::duration<double, std::milli>(Clock::now() - start).count();
    if (config.progress && !config.progress(1.0)) throw BuildCancelled();  // the last word may be "stop"
    return bvh;
}

}  // namespace bvhlab
