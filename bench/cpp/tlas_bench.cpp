// tlas_bench — rays through an instanced scene (issue 34): two-level trees (bvhlab's TLAS
// over BLASes, Embree 3's instances) beside one flat tree over the same triangles moved into the
// world (bvh_bench's peers), interleaved, and prints JSON.
//   tlas_bench trace --mesh M.f32 [--mesh M.f32 ...] --instances I.f32 RAYS.f32 [--shadow S.f32 ...]
//              --peer SPEC [--peer SPEC ...] [--repeat R]
//   tlas_bench once  (the same, one peer, one ray set: one pass between callgrind's marks)
//   tlas_bench build [--mesh M.f32] [--counts 1000,10000,100000] [--repeat R]
//              (build_tlas over N placements of one mesh, bench/instancing.py's layout: the whole
//              build, its binary tree and its wide copy, interleaved over the counts, one thread)
// M: a mesh's triangles, T×3×3 float32; I: N×13 float32 (the mesh index, then the 3×4 row-major
// object-to-world transform); RAYS and SHADOW as bvh_bench reads them.
// SPEC: "flat/" + a bvh_bench spec (bvhlab:..., embree:...), built over the flattened triangles;
// "two/bvhlab[:query=stack|stackless|wide][,batch=1]" (batch=1: the batch queries on one thread,
// the Python API's); "two/embree" (rtcNewScene per mesh, instanced by RTC_GEOMETRY_TYPE_INSTANCE
// into a top scene, both MEDIUM).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>
#include <random>
#include <sys/resource.h>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "bench_data.h"
#include "callgrind_marks.h"
#include "bvhlab/render_settings.h"
#include "bvhlab/tlas.h"
#include "bvhlab/wide_bvh.h"
#include "tlas_bench.h"

namespace bench {

Mesh InstancedScene::flattened() const {
    Mesh out;
    for (std::size_t i = 0; i < mesh_of.size(); ++i) {
        const float* m = transforms[i].data();
        for (std::size_t k = 0; k < meshes[mesh_of[i]].xyz.size(); k += 3) {
            const float* p = meshes[mesh_of[i]].xyz.data() + k;
            for (int r = 0; r < 3; ++r)
                out.xyz.push_back(m[4 * r] * p[0] + m[4 * r + 1] * p[1] + m[4 * r + 2] * p[2] + m[4 * r + 3]);
        }
    }
    return out;
}

namespace {

/// bvhlab's TLAS over one BLAS per mesh (the default builds), queried one ray at a time, or with
/// batch=1 through the batch queries on one thread (intersect_batch_two_level: the Python API's).
class BvhlabTwoLevel : public InstancedPeer {
public:
    explicit BvhlabTwoLevel(const std::string& options) : options_(options) {
        std::istringstream in(options);
        for (std::string option; std::getline(in, option, ',');) {
            if (option.rfind("query=", 0) == 0) mode_ = bvhlab::parse_traversal(option.substr(6));
            else if (option == "batch=1") batch_ = true;
            else if (!option.empty()) throw std::invalid_argument("two/bvhlab takes query= and batch=1 only");
        }
    }
    std::string name() const override { return "bvhlab two-level " + options_; }
    void build(const InstancedScene& s) override {
        bvhlab::BuildConfig config;
        config.threads = 1;
        blases_.clear(), wides_.clear();
        for (const Mesh& m : s.meshes) blases_.push_back(bvhlab::build_bvh({m.xyz.data(), m.count()}, config));
        for (const bvhlab::Bvh& b : blases_) wides_.push_back(bvhlab::make_wide(b));
        std::vector<const bvhlab::Bvh*> trees;
        for (const bvhlab::Bvh& b : blases_) trees.push_back(&b);
        std::vector<bvhlab::Transform> transforms(s.transforms.size());
        for (std::size_t i = 0; i < transforms.size(); ++i)
            std::copy(s.transforms[i].begin(), s.transforms[i].end(), transforms[i].m.begin());
        tlas_ = bvhlab::build_tlas(trees, s.mesh_of, transforms);
        scene_ = {&tlas_, {}};
        for (std::size_t k = 0; k < blases_.size(); ++k) scene_.blases.push_back({&blases_[k], &wides_[k]});
        bvhlab::check_two_level(scene_, mode_);
    }
    void trace(const Rays& rays, float* t, std::uint32_t* prim) override {
        if (batch_) {
            std::vector<std::int32_t> found(rays.count());
            bvhlab::HitBatch out;
            out.t = t, out.prim = found.data();
            bvhlab::intersect_batch_two_level(scene_, {origins_.data(), directions_.data(), rays.count()}, out, nullptr,
                                              mode_, 1);
            for (std::size_t i = 0; i < rays.count(); ++i) prim[i] = std::uint32_t(found[i]);
            return;
        }
        for (std::size_t i = 0; i < rays.count(); ++i) {
            const float* r = rays.od.data() + 6 * i;
            const bvhlab::InstanceHit h =
                bvhlab::intersect_two_level(scene_, {{r[0], r[1], r[2]}, {r[3], r[4], r[5]}}, mode_);
            t[i] = h.hit.t, prim[i] = h.hit.ref;
        }
    }
    void occluded(const Rays& rays, std::uint8_t* out) override {
        if (batch_) {
            bvhlab::RayBatch batch{origins_.data(), directions_.data(), rays.count()};
            batch.tmax_of = rays.tmax.data();
            const std::unique_ptr<bool[]> blocked(new bool[rays.count()]);
            bvhlab::occluded_batch_two_level(scene_, batch, blocked.get(), mode_, 1);
            for (std::size_t i = 0; i < rays.count(); ++i) out[i] = blocked[i];
            return;
        }
        for (std::size_t i = 0; i < rays.count(); ++i) {
            const float* r = rays.od.data() + 6 * i;
            out[i] =
                bvhlab::occluded_two_level(scene_, {{r[0], r[1], r[2]}, {r[3], r[4], r[5]}, 0.0f, rays.tmax[i]}, mode_);
        }
    }

    /// batch=1: the rays' origins and directions as the batch queries take them (untimed, as
    /// bvh_bench's batch peer).
    void prepare_rays(const Rays& rays) override {
        if (!batch_) return;
        split_rays(rays, origins_, directions_);
    }

private:
    std::string options_;
    bvhlab::Traversal mode_ = bvhlab::Traversal::Wide;
    bool batch_ = false;
    std::vector<float> origins_, directions_;
    std::vector<bvhlab::Bvh> blases_;
    std::vector<bvhlab::WideBvh> wides_;
    bvhlab::Tlas tlas_;
    bvhlab::TwoLevel scene_;
};

/// A bvh_bench peer over the flattened triangles.
class FlatPeer : public InstancedPeer {
public:
    explicit FlatPeer(const std::string& spec) : peer_(make_peer(spec, 1)) {}
    std::string name() const override { return "flat " + peer_->name(); }
    void build(const InstancedScene& s) override {
        peer_->build(s.flattened());
        peer_->prepare_trace();
    }
    void prepare_rays(const Rays& rays) override { peer_->prepare_rays(rays); }
    void trace(const Rays& rays, float* t, std::uint32_t* prim) override { peer_->trace(rays, t, prim); }
    void occluded(const Rays& rays, std::uint8_t* out) override { peer_->occluded(rays, out); }

private:
    std::unique_ptr<Peer> peer_;
};

std::unique_ptr<InstancedPeer> make_instanced_peer(const std::string& spec) {
    if (spec.rfind("flat/", 0) == 0) return std::make_unique<FlatPeer>(spec.substr(5));
    if (spec.rfind("two/bvhlab", 0) == 0) {
        const auto colon = spec.find(':');
        return std::make_unique<BvhlabTwoLevel>(colon == std::string::npos ? "" : spec.substr(colon + 1));
    }
    if (spec == "two/embree") return make_embree_two_level();
    throw std::invalid_argument("unknown spec '" + spec + "' (flat/..., two/bvhlab[:query=...], two/embree)");
}

InstancedScene load_scene(const std::vector<std::string>& meshes, const std::string& instances) {
    InstancedScene s;
    for (const auto& m : meshes) s.meshes.push_back(load_mesh(m));
    const std::vector<float> rows = load_rows(instances, 13, "instances");  // a mesh index and a 3×4 transform
    for (std::size_t i = 0; i + 13 <= rows.size(); i += 13) {
        const auto mesh = std::uint32_t(rows[i]);
        if (mesh >= s.meshes.size()) throw std::invalid_argument("an instance of a missing mesh");
        s.mesh_of.push_back(mesh);
        std::array<float, 12> t;
        std::copy(rows.begin() + std::ptrdiff_t(i + 1), rows.begin() + std::ptrdiff_t(i + 13), t.begin());
        s.transforms.push_back(t);
    }
    return s;
}

struct Args {
    std::string mode, instances;
    std::vector<std::string> meshes, rays, peers;
    std::vector<bool> shadow;
    int repeat = 5;
};

Args parse(int argc, char** argv) {
    if (argc < 2) throw std::invalid_argument("usage: tlas_bench trace|once --mesh M.f32 --instances I.f32 ...");
    Args a;
    a.mode = argv[1];
    for (int i = 2; i < argc; ++i) {
        const std::string s = argv[i];
        auto value = [&] {
            if (i + 1 >= argc) throw std::invalid_argument(s + " needs a value");
            return std::string(argv[++i]);
        };
        if (s == "--mesh") a.meshes.push_back(value());
        else if (s == "--instances") a.instances = value();
        else if (s == "--peer") a.peers.push_back(value());
        else if (s == "--repeat") a.repeat = std::stoi(value());
        else if (s == "--threads") value();  // one thread always (bench/_peers.py passes it)
        else if (s == "--shadow") a.rays.push_back(value()), a.shadow.push_back(true);
        else a.rays.push_back(s), a.shadow.push_back(false);
    }
    if (a.peers.empty() || a.meshes.empty() || a.instances.empty() || a.rays.empty())
        throw std::invalid_argument("tlas_bench needs --mesh, --instances, rays and --peer");
    return a;
}

/// Rays whose hit distance differs from the first peer's by more than a relative 1e-4 (or hit/miss).
std::size_t disagreements(const std::vector<float>& a, const std::vector<float>& b) {
    std::size_t n = 0;
    for (std::size_t i = 0; i < a.size(); ++i) {
        const bool ma = std::isinf(a[i]), mb = std::isinf(b[i]);
        if (ma != mb || (!ma && std::fabs(a[i] - b[i]) > 1e-4f * std::max(1.0f, std::fabs(a[i])))) ++n;
    }
    return n;
}

void run_set(const Args& a, std::size_t s, const std::vector<std::unique_ptr<InstancedPeer>>& peers, bool once) {
    const bool shadow = a.shadow[s];
    const Rays rays = shadow ? load_shadow_rays(a.rays[s]) : load_rays(a.rays[s]);
    std::vector<std::vector<float>> t(peers.size(), std::vector<float>(rays.count()));
    std::vector<std::uint32_t> prim(rays.count());
    std::vector<std::uint8_t> blocked(rays.count());
    std::vector<std::vector<double>> times(peers.size());
    for (const auto& peer : peers) peer->prepare_rays(rays);
    for (int r = 0; r < (once ? 1 : a.repeat); ++r)
        for (std::size_t k = 0; k < peers.size(); ++k) {
            const auto t0 = std::chrono::steady_clock::now();
            if (once) CALLGRIND_START_INSTRUMENTATION;
            if (shadow) peers[k]->occluded(rays, blocked.data());
            else peers[k]->trace(rays, t[k].data(), prim.data());
            if (once) CALLGRIND_STOP_INSTRUMENTATION;
            times[k].push_back(seconds_since(t0));
            if (shadow)  // as distances: 0 occluded, inf not (disagreements counts either way)
                for (std::size_t i = 0; i < rays.count(); ++i)
                    t[k][i] = blocked[i] ? 0.0f : std::numeric_limits<float>::infinity();
        }
    std::printf("%s\n {\"rays\": \"%s\", \"shadow\": %s, \"count\": %zu, \"peers\": [", s ? "," : "", a.rays[s].c_str(),
                shadow ? "true" : "false", rays.count());
    for (std::size_t k = 0; k < peers.size(); ++k) {
        const auto hits = std::count_if(t[k].begin(), t[k].end(), [](float x) { return !std::isinf(x); });
        std::printf(
            "%s\n  {\"spec\": \"%s\", \"name\": \"%s\", \"hits\": %zu, \"disagree_with_first\": %zu, \"seconds\": [",
            k ? "," : "", a.peers[k].c_str(), peers[k]->name().c_str(), std::size_t(hits), disagreements(t[0], t[k]));
        for (std::size_t r = 0; r < times[k].size(); ++r) std::printf("%s%.6f", r ? ", " : "", times[k][r]);
        std::printf("]}");
    }
    std::printf("]}");
}

/// N placements as bench/instancing.py's _placements lays them out (rotated about z, scaled
/// 0.5-2, spread over a square of side 4·sqrt(N), flat in z), from std::mt19937.
std::vector<bvhlab::Transform> placements(std::size_t n, unsigned seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> unit(0.0f, 1.0f);
    const float side = std::sqrt(float(n)) * 4.0f;
    std::vector<bvhlab::Transform> out(n);
    for (bvhlab::Transform& t : out) {
        const float angle = unit(rng) * 6.2831853f, scale = 0.5f + 1.5f * unit(rng);
        t.m = {std::cos(angle) * scale,
               -std::sin(angle) * scale,
               0,
               unit(rng) * side,
               std::sin(angle) * scale,
               std::cos(angle) * scale,
               0,
               unit(rng) * side,
               0,
               0,
               scale,
               unit(rng) * side * 0.1f};
    }
    return out;
}

/// 480 random triangles in the unit cube (no mesh file): the TLAS build reads only the BLAS's top boxes.
Mesh default_mesh() {
    std::mt19937 rng(1);
    std::uniform_real_distribution<float> unit(-1.0f, 1.0f);
    Mesh m;
    for (int k = 0; k < 480; ++k) {
        const float c[3] = {unit(rng), unit(rng), unit(rng)};
        for (int v = 0; v < 3; ++v)
            for (int a = 0; a < 3; ++a) m.xyz.push_back(c[a] + 0.1f * unit(rng));
    }
    return m;
}

/// build_tlas timed: the whole call, its binary tree (Bvh::build_ms) and a second make_wide_tlas of
/// the same tree; each count in turn, R rounds, the least and the median of each.
int build_mode(int argc, char** argv) {
    std::vector<std::size_t> counts{1000, 10000, 100000};
    std::string mesh_path;
    int repeat = 7;
    for (int i = 2; i < argc; ++i) {
        const std::string s = argv[i];
        if (i + 1 >= argc) throw std::invalid_argument(s + " needs a value");
        const std::string v = argv[++i];
        if (s == "--mesh") mesh_path = v;
        else if (s == "--repeat") repeat = std::stoi(v);
        else if (s == "--counts") {
            counts.clear();
            std::stringstream in(v);
            for (std::string c; std::getline(in, c, ',');) counts.push_back(std::stoul(c));
        } else throw std::invalid_argument("unknown option " + s);
    }
    const Mesh mesh = mesh_path.empty() ? default_mesh() : load_mesh(mesh_path);
    bvhlab::BuildConfig config;
    config.threads = 1;
    const bvhlab::Bvh blas = bvhlab::build_bvh({mesh.xyz.data(), mesh.count()}, config);
    const std::vector<const bvhlab::Bvh*> blases{&blas};
    std::vector<std::vector<bvhlab::Transform>> placed;
    for (std::size_t n : counts) placed.push_back(placements(n, unsigned(n)));
    bvhlab::BuildConfig tlas_config = bvhlab::default_tlas_config();
    tlas_config.threads = 1;
    struct Times {
        std::vector<double> total, tree, wide, faults;
        std::size_t nodes = 0, wide_nodes = 0;
        double sah = 0;
        std::uint64_t digest = 0;
    };
    auto minor_faults = [] {
        rusage u{};
        getrusage(RUSAGE_SELF, &u);
        return double(u.ru_minflt);
    };
    std::vector<Times> times(counts.size());
    bvhlab::Tlas previous;  // alive while the next is built, as InstancedBvh.place keeps its last
    for (int r = 0; r < repeat; ++r)
        for (std::size_t c = 0; c < counts.size(); ++c) {
            const std::vector<std::uint32_t> blas_of(counts[c], 0);
            const double faults = minor_faults();
            auto t0 = std::chrono::steady_clock::now();
            bvhlab::Tlas tlas = bvhlab::build_tlas(blases, blas_of, placed[c], tlas_config);
            times[c].total.push_back(seconds_since(t0) * 1e3);
            times[c].faults.push_back(minor_faults() - faults);
            times[c].tree.push_back(tlas.tree.build_ms);
            t0 = std::chrono::steady_clock::now();
            const bvhlab::WideBvh wide = bvhlab::make_wide_tlas(tlas.tree);
            times[c].wide.push_back(seconds_since(t0) * 1e3);
            times[c].nodes = tlas.tree.nodes.size(), times[c].wide_nodes = wide.node_count;
            std::uint64_t h = 0xcbf29ce484222325ull;  // FNV-1a of the tree, the wide copy and the world boxes
            auto add = [&h](const void* data, std::size_t bytes) {
                for (std::size_t i = 0; i < bytes; ++i)
                    h = (h ^ static_cast<const unsigned char*>(data)[i]) * 0x100000001b3ull;
            };
            add(tlas.tree.nodes.data(), tlas.tree.nodes.size() * sizeof(bvhlab::BvhNode));
            add(tlas.tree.refs.data(), tlas.tree.refs.size() * 4);
            add(tlas.wide.lines.data(), tlas.wide.lines.size() * sizeof(bvhlab::WideLine));
            for (const bvhlab::Instance& inst : tlas.instances) add(&inst.world_box, sizeof inst.world_box);
            times[c].digest = h;
            double sah = 0;  // the tree's summed inner-node area over the root's (a quality check)
            for (const auto& n : tlas.tree.nodes)
                if (!bvhlab::is_leaf(n)) sah += bvhlab::node_box(n).half_area();
            times[c].sah = sah / bvhlab::node_box(tlas.tree.nodes[0]).half_area();
            previous = std::move(tlas);
        }
    auto least = [](std::vector<double> v) { return *std::min_element(v.begin(), v.end()); };
    auto median = [](std::vector<double> v) {
        std::sort(v.begin(), v.end());
        return v[v.size() / 2];
    };
    std::printf("{\"builds\": [");
    for (std::size_t c = 0; c < counts.size(); ++c) {
        const Times& t = times[c];
        std::printf(
            "%s\n {\"instances\": %zu, \"nodes\": %zu, \"wide_nodes\": %zu, \"inner_area_over_root\": %.2f, "
            "\"build_tlas_ms\": [%.3f, %.3f], \"tree_ms\": [%.3f, %.3f], \"wide_ms\": [%.3f, %.3f], "
            "\"page_faults\": %.0f, \"digest\": \"%016llx\"}",
            c ? "," : "", counts[c], t.nodes, t.wide_nodes, t.sah, least(t.total), median(t.total), least(t.tree),
            median(t.tree), least(t.wide), median(t.wide), median(t.faults), (unsigned long long)t.digest);
    }
    std::printf("]}\n  (each: [least, median] of %d rounds; build_tlas_ms includes the wide copy)\n", repeat);
    return 0;
}

}  // namespace
}  // namespace bench

int main(int argc, char** argv) {
    try {
        if (argc > 1 && std::string(argv[1]) == "build") return bench::build_mode(argc, argv);
        const bench::Args a = bench::parse(argc, argv);
        if (a.mode != "trace" && a.mode != "once") throw std::invalid_argument("unknown mode " + a.mode);
        const bool once = a.mode == "once";
        const bench::InstancedScene scene = bench::load_scene(a.meshes, a.instances);
        std::vector<std::unique_ptr<bench::InstancedPeer>> peers;
        for (const auto& spec : a.peers) {
            peers.push_back(bench::make_instanced_peer(spec));
            peers.back()->build(scene);
        }
        std::printf("{\"instances\": %zu, \"ray_sets\": [", scene.mesh_of.size());
        for (std::size_t s = 0; s < (once ? 1 : a.rays.size()); ++s) bench::run_set(a, s, peers, once);
        std::printf("]}\n");
        return 0;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "tlas_bench: %s\n", e.what());
        return 2;
    }
}
