// bvhlab as a benchmark peer: build_bvh with the options of the spec, single rays (closest hit,
// or any hit for shadow rays: occluded) through the wide tree (the fastest CPU traversal) or the
// traversal named by query=. Spec options, comma separated (BuildConfig's fields): method=, axis=,
// bins=, span=box|centroids, leaf= (max leaf size), block= (sah_block), trav= and isect= (the
// SAH's costs), alpha=, budget=, unsplit=0|1 (method sbvh); query=stack|stackless|wide; batch=1 traces each set by the
// batch queries users call (intersect_batch, occluded_batch: checked, scaled, grouped by octant)
// on one thread rather than ray by ray; isa=portable|avx2|avx512 traces on that path (isa.h; the
// build runs on the library's choice), so that one run interleaves the paths; opt=N
// optimises the built tree by reinsertion for at
// most N batches (optimize.h), part of the build's time.
#include <sstream>
#include <stdexcept>
#include <vector>

#include "bench_data.h"
#include "bvhlab/bvh.h"
#include "bvhlab/isa.h"
#include "bvhlab/optimize.h"
#include "bvhlab/render_settings.h"
#include "bvhlab/stats.h"
#include "bvhlab/traverse.h"
#include "bvhlab/wide_bvh.h"

namespace bench {
namespace {

/// The traversal of query= in `options` (wide without one), whether batch=1 is there and the
/// value of isa= (empty without one), all taken out of `options`.
bvhlab::Traversal take_query(std::string& options, bool& batch, std::string& isa) {
    std::stringstream ss(options);
    std::string rest;
    bvhlab::Traversal query = bvhlab::Traversal::Wide;
    batch = false;
    for (std::string kv; std::getline(ss, kv, ',');) {
        if (kv.rfind("query=", 0) == 0) query = bvhlab::parse_traversal(kv.substr(6));
        else if (kv.rfind("batch=", 0) == 0) batch = kv.substr(6) != "0";
        else if (kv.rfind("isa=", 0) == 0) isa = kv.substr(4);
        else rest += (rest.empty() ? "" : ",") + kv;
    }
    options = rest;
    return query;
}

struct Options {
    bvhlab::BuildConfig build;
    std::uint32_t optimize = 0;  ///< batches of Bvh optimisation after the build (0: none)
};

Options parse_options(const std::string& options, unsigned threads) {
    Options out;
    bvhlab::BuildConfig& cfg = out.build;
    cfg.threads = threads;
    std::stringstream ss(options);
    for (std::string kv; std::getline(ss, kv, ',');) {
        if (kv.empty()) continue;
        const auto eq = kv.find('=');
        const std::string key = kv.substr(0, eq), value = eq == std::string::npos ? "" : kv.substr(eq + 1);
        if (key == "method") cfg.method = bvhlab::parse_split_method(value);
        else if (key == "axis") cfg.axis = bvhlab::parse_axis_policy(value);
        else if (key == "bins") cfg.bins = std::stoul(value);
        else if (key == "span") cfg.bin_bounds = bvhlab::parse_bin_bounds(value);
        else if (key == "leaf") cfg.max_leaf_size = std::stoul(value);
        else if (key == "block") cfg.sah_block = std::stoul(value);
        else if (key == "trav") cfg.traversal_cost = std::stof(value);
        else if (key == "isect") cfg.intersection_cost = std::stof(value);
        else if (key == "alpha") cfg.sbvh_alpha = std::stof(value);
        else if (key == "budget") cfg.sbvh_budget = std::stof(value);
        else if (key == "unsplit") cfg.sbvh_unsplit = value != "0";
        else if (key == "opt") out.optimize = std::stoul(value);
        else throw std::invalid_argument("unknown bvhlab option '" + key + "'");
    }
    return out;
}

class BvhlabPeer : public Peer {
public:
    BvhlabPeer(const std::string& options, unsigned threads) : options_(options) {
        std::string build_options = options;
        std::string isa;
        query_ = take_query(build_options, batch_, isa);
        if (isa.empty()) isa_ = bvhlab::active_isa();
        else if (isa == "portable") isa_ = bvhlab::Isa::Portable;
        else if (isa == "avx2") isa_ = bvhlab::Isa::Avx2;
        else if (isa == "avx512") isa_ = bvhlab::Isa::Avx512;
        else throw std::invalid_argument("unknown isa '" + isa + "'");
        if (!bvhlab::isa_supported(isa_)) throw std::invalid_argument("isa " + isa + " is not available here");
        config_ = parse_options(build_options, threads);
    }
    std::string name() const override { return "bvhlab " + (options_.empty() ? std::string("defaults") : options_); }
    void build(const Mesh& mesh) override {
        bvh_ = bvhlab::build_bvh({mesh.xyz.data(), mesh.count()}, config_.build);
        if (config_.optimize) {
            bvhlab::OptimizeConfig opt;
            opt.iterations = config_.optimize;
            bvh_ = bvhlab::optimized(bvh_, opt);
        }
    }
    TreeInfo info() const override {
        return {bvhlab::sah_cost(bvh_), bvh_.nodes.size(), bvh_.refs.size(), digest(),
                wide_.node_count,       wide_.packet_count};
    }
    void prepare_trace() override { wide_ = bvhlab::make_wide(bvh_); }
    void prepare_rays(const Rays& rays) override {
        if (!batch_) return;
        split_rays(rays, origins_, directions_);
    }
    bvhlab::RayBatch batch(const Rays& rays) const {
        bvhlab::RayBatch b;
        b.origins = origins_.data(), b.directions = directions_.data(), b.count = rays.count();
        if (!rays.tmax.empty()) b.tmax_of = rays.tmax.data();
        return b;
    }
    void trace(const Rays& rays, float* t, std::uint32_t* prim) override {
        const OnIsa on(isa_);
        if (batch_) {
            bvhlab::HitBatch hits;
            hits.t = t, hits.prim = reinterpret_cast<std::int32_t*>(prim);  // -1 on a miss: ~0u
            return bvhlab::intersect_batch(bvh_, batch(rays), hits, query_, 1, &wide_);
        }
        for (std::size_t i = 0; i < rays.count(); ++i) {
            const float* r = rays.od.data() + 6 * i;
            bvhlab::Ray ray{{r[0], r[1], r[2]}, {r[3], r[4], r[5]}};
            bvhlab::Hit h = query_ == bvhlab::Traversal::Wide ? bvhlab::intersect_wide(wide_, bvh_, ray)
                                                              : bvhlab::intersect(bvh_, ray, query_);
            t[i] = h.t, prim[i] = h.ref;
        }
    }
    void occluded(const Rays& rays, std::uint8_t* out) override {
        static_assert(sizeof(bool) == sizeof(std::uint8_t));
        const OnIsa on(isa_);
        if (batch_) return bvhlab::occluded_batch(bvh_, batch(rays), reinterpret_cast<bool*>(out), query_, 1, &wide_);
        for (std::size_t i = 0; i < rays.count(); ++i) {
            const float* r = rays.od.data() + 6 * i;
            bvhlab::Ray ray{{r[0], r[1], r[2]}, {r[3], r[4], r[5]}, 0.0f, rays.tmax[i]};
            out[i] = query_ == bvhlab::Traversal::Wide ? bvhlab::occluded_wide(wide_, ray)
                                                       : bvhlab::occluded(bvh_, ray, query_);
        }
    }

private:
    /// The path of isa= for the lifetime of one trace (set_isa: one load more a ray set).
    struct OnIsa {
        bvhlab::Isa before = bvhlab::active_isa();
        explicit OnIsa(bvhlab::Isa isa) { bvhlab::set_isa(isa); }
        ~OnIsa() { bvhlab::set_isa(before); }
    };

    std::uint64_t digest() const {
        std::uint64_t h = 0xcbf29ce484222325ull;
        auto add = [&](const void* data, std::size_t bytes) {
            for (std::size_t i = 0; i < bytes; ++i)
                h = (h ^ static_cast<const unsigned char*>(data)[i]) * 0x100000001b3ull;
        };
        add(bvh_.nodes.data(), bvh_.nodes.size() * sizeof(bvhlab::BvhNode));
        add(bvh_.refs.data(), bvh_.refs.size() * sizeof(std::uint32_t));
        return h;
    }

    std::string options_;
    bvhlab::Traversal query_;
    bool batch_ = false;
    bvhlab::Isa isa_ = bvhlab::Isa::Portable;  ///< the trace's path (isa=, else the library's choice)
    std::vector<float> origins_, directions_;  ///< batch=1: the ray set's, split (prepare_rays)
    Options config_;
    bvhlab::Bvh bvh_;
    bvhlab::WideBvh wide_;
};

}  // namespace

std::unique_ptr<Peer> make_bvhlab_peer(const std::string& options, unsigned threads) {
    return std::make_unique<BvhlabPeer>(options, threads);
}

}  // namespace bench
