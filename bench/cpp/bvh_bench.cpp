// bvh_bench — times builders and single-ray traversal of several systems in one process,
// interleaved (every repetition runs each system once, in turn), and prints JSON (builds: wall
// seconds, CPU seconds of all threads, minor page faults, per repetition).
//   bvh_bench build MESH.f32 --peer SPEC [--peer SPEC ...] [--repeat R] [--threads T]
//   bvh_bench trace MESH.f32 RAYS.f32 [RAYS.f32 | --shadow SHADOW.f32 ...] --peer SPEC ... [--repeat R]
//   bvh_bench once MESH.f32 [RAYS.f32 | --shadow SHADOW.f32] --peer SPEC [--threads T]   (one build,
//   or one pass over the rays, between callgrind's start and stop)
// RAYS: N×6 (origin, direction), closest hits; SHADOW: N×7 (origin, direction, tmax), any hits.
// SPEC: see bench_data.h. bench/build.py and bench/traverse.py drive it.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include <sys/resource.h>

#include "bench_data.h"
#include "callgrind_marks.h"

namespace bench {
namespace {

struct Args {
    std::string mode, mesh;
    std::vector<std::string> rays, peers;
    std::vector<bool> shadow;  ///< per ray set: shadow rays (any hit) rather than closest hits
    int repeat = 5;
    unsigned threads = 1;
};

Args parse(int argc, char** argv) {
    Args a;
    if (argc < 3)
        throw std::invalid_argument("usage: bvh_bench build|trace|once MESH.f32 [RAYS.f32...] --peer SPEC ...");
    a.mode = argv[1], a.mesh = argv[2];
    for (int i = 3; i < argc; ++i) {
        std::string s = argv[i];
        auto value = [&] {
            if (i + 1 >= argc) throw std::invalid_argument(s + " needs a value");
            return std::string(argv[++i]);
        };
        if (s == "--peer") a.peers.push_back(value());
        else if (s == "--repeat") a.repeat = std::stoi(value());
        else if (s == "--threads") a.threads = unsigned(std::stoul(value()));
        else if (s == "--shadow") a.rays.push_back(value()), a.shadow.push_back(true);
        else a.rays.push_back(s), a.shadow.push_back(false);
    }
    if (a.peers.empty()) throw std::invalid_argument("no --peer given");
    return a;
}

/// CPU time (user and system, every thread of the process) and minor page faults so far: with
/// the wall time they show a parallel build's idle and extra work, and fresh memory it faults in.
struct Usage {
    double cpu_seconds;
    long faults;
};
Usage usage() {
    rusage u{};
    getrusage(RUSAGE_SELF, &u);
    const auto sec = [](timeval t) { return double(t.tv_sec) + 1e-6 * double(t.tv_usec); };
    return {sec(u.ru_utime) + sec(u.ru_stime), u.ru_minflt};
}

void print_times(const std::vector<double>& times, const char* format = "%s%.6f") {
    std::printf("[");
    for (std::size_t i = 0; i < times.size(); ++i) std::printf(format, i ? ", " : "", times[i]);
    std::printf("]");
}

/// Builds with every peer, in turn, until the memory they use has been touched: a round in which
/// no build faults in more than kFreshPages pages (1 MiB), or kMaxRounds rounds. One round is not
/// enough when several trees stay alive: their blocks are reserved for the largest tree a range
/// can make (2n - 1 nodes) and written only as far as each tree goes, so as the blocks pass from
/// one peer to the next, the first touches go on for rounds (room1m, six bvhlab trees: 21,943
/// faults in the default's second build, then 4K-7K a build, for up to five more rounds, in the
/// default's and the report configuration's; Sponza: 734 in every default build of the first
/// five rounds, which a bound of 16 MiB let through into the timed builds). A peer that takes
/// fresh memory in every build (Embree LOW: about 500 pages) keeps the warm-up to kMaxRounds.
/// Returns the rounds run.
int warm_up(const std::vector<std::unique_ptr<Peer>>& peers, const Mesh& mesh) {
    constexpr long kFreshPages = 256;
    constexpr int kMaxRounds = 8;
    for (int round = 1;; ++round) {
        long most = 0;
        for (auto& p : peers) {
            const long before = usage().faults;
            p->build(mesh);
            most = std::max(most, usage().faults - before);
        }
        if (most <= kFreshPages || round == kMaxRounds) return round;
    }
}

int run_build(const Args& a) {
    Mesh mesh = load_mesh(a.mesh);
    std::vector<std::unique_ptr<Peer>> peers;
    for (const auto& spec : a.peers) peers.push_back(make_peer(spec, a.threads));
    std::vector<std::vector<double>> times(peers.size()), cpu(peers.size()), faults(peers.size());
    const int warmups = warm_up(peers, mesh);
    // where the timed builds begin and end, on CLOCK_MONOTONIC (`perf record -k CLOCK_MONOTONIC`
    // samples on the same clock: bench/build_threads.py --perf counts only the samples between)
    timespec timed_from{};
    clock_gettime(CLOCK_MONOTONIC, &timed_from);
    for (int r = 0; r < a.repeat; ++r)
        for (std::size_t k = 0; k < peers.size(); ++k) {
            const Usage u0 = usage();
            auto t0 = std::chrono::steady_clock::now();
            peers[k]->build(mesh);
            times[k].push_back(seconds_since(t0));
            const Usage u1 = usage();
            cpu[k].push_back(u1.cpu_seconds - u0.cpu_seconds), faults[k].push_back(double(u1.faults - u0.faults));
        }
    timespec timed_to{};
    clock_gettime(CLOCK_MONOTONIC, &timed_to);
    std::printf(
        "{\"triangles\": %zu, \"threads\": %u, \"warm_up_rounds\": %d, \"timed\": [%lld.%09ld, %lld.%09ld], "
        "\"peers\": [",
        mesh.count(), a.threads, warmups, (long long)timed_from.tv_sec, timed_from.tv_nsec, (long long)timed_to.tv_sec,
        timed_to.tv_nsec);
    for (std::size_t k = 0; k < peers.size(); ++k) {
        TreeInfo info = peers[k]->info();
        std::printf(
            "%s\n {\"spec\": \"%s\", \"name\": \"%s\", \"sah\": %s, \"nodes\": %llu, \"references\": %llu, "
            "\"seconds\": ",
            k ? "," : "", a.peers[k].c_str(), peers[k]->name().c_str(),
            std::isnan(info.sah) ? "null" : std::to_string(info.sah).c_str(), (unsigned long long)info.nodes,
            (unsigned long long)info.references);
        print_times(times[k]);
        std::printf(", \"cpu_seconds\": ");
        print_times(cpu[k]);
        std::printf(", \"page_faults\": ");
        print_times(faults[k], "%s%.0f");
        std::printf("}");
    }
    std::printf("]}\n");
    return 0;
}

/// Rays whose hit distance differs from the first peer's by more than a relative 1e-4 (or hit/miss).
std::size_t disagreements(const std::vector<float>& a, const std::vector<float>& b) {
    std::size_t n = 0;
    for (std::size_t i = 0; i < a.size(); ++i) {
        bool ma = std::isinf(a[i]), mb = std::isinf(b[i]);
        if (ma != mb || (!ma && std::fabs(a[i] - b[i]) > 1e-4f * std::max(1.0f, std::fabs(a[i])))) ++n;
    }
    return n;
}

/// Rays that a peer says are occluded and the first peer not, or the other way round.
std::size_t disagreements(const std::vector<std::uint8_t>& a, const std::vector<std::uint8_t>& b) {
    std::size_t n = 0;
    for (std::size_t i = 0; i < a.size(); ++i) n += (a[i] != 0) != (b[i] != 0);
    return n;
}

/// One ray set through every peer, interleaved: closest hits (t) or, for shadow rays, any hits.
/// Prints its JSON object.
void trace_set(const Args& a, std::size_t s, const std::vector<std::unique_ptr<Peer>>& peers) {
    const bool shadow = a.shadow[s];
    const Rays rays = shadow ? load_shadow_rays(a.rays[s]) : load_rays(a.rays[s]);
    std::vector<std::vector<float>> t(peers.size(), std::vector<float>(rays.count()));
    std::vector<std::vector<std::uint8_t>> blocked(peers.size(), std::vector<std::uint8_t>(rays.count()));
    std::vector<std::uint32_t> prim(rays.count());
    std::vector<std::vector<double>> times(peers.size()), cpu(peers.size());
    for (const auto& peer : peers) peer->prepare_rays(rays);
    for (int r = 0; r < a.repeat; ++r)
        for (std::size_t k = 0; k < peers.size(); ++k) {
            const double c0 = thread_cpu_seconds();
            auto t0 = std::chrono::steady_clock::now();
            if (shadow) peers[k]->occluded(rays, blocked[k].data());
            else peers[k]->trace(rays, t[k].data(), prim.data());
            times[k].push_back(seconds_since(t0));
            cpu[k].push_back(thread_cpu_seconds() - c0);
        }
    std::printf("%s\n {\"rays\": \"%s\", \"shadow\": %s, \"count\": %zu, \"peers\": [", s ? "," : "", a.rays[s].c_str(),
                shadow ? "true" : "false", rays.count());
    for (std::size_t k = 0; k < peers.size(); ++k) {
        const std::size_t hits =
            shadow ? std::size_t(std::count(blocked[k].begin(), blocked[k].end(), 1))
                   : std::size_t(std::count_if(t[k].begin(), t[k].end(), [](float x) { return !std::isinf(x); }));
        const std::size_t differ = shadow ? disagreements(blocked[0], blocked[k]) : disagreements(t[0], t[k]);
        std::printf(
            "%s\n  {\"spec\": \"%s\", \"name\": \"%s\", \"hits\": %zu, \"disagree_with_first\": %zu, "
            "\"seconds\": ",
            k ? "," : "", a.peers[k].c_str(), peers[k]->name().c_str(), hits, differ);
        print_times(times[k]);
        std::printf(", \"cpu_seconds\": ");
        print_times(cpu[k]);
        std::printf("}");
    }
    std::printf("]}");
}

int run_trace(const Args& a) {
    Mesh mesh = load_mesh(a.mesh);
    std::vector<std::unique_ptr<Peer>> peers;
    for (const auto& spec : a.peers) {
        peers.push_back(make_peer(spec, a.threads));
        peers.back()->build(mesh);
        peers.back()->prepare_trace();
    }
    std::printf("{\"triangles\": %zu, \"ray_sets\": [", mesh.count());
    for (std::size_t s = 0; s < a.rays.size(); ++s) trace_set(a, s, peers);
    std::printf("]}\n");
    return 0;
}

int run_once(const Args& a) {
    Mesh mesh = load_mesh(a.mesh);
    auto peer = make_peer(a.peers.at(0), a.threads);
    if (!a.rays.empty()) {  // count the tracing of the first ray set instead of the build
        peer->build(mesh);
        peer->prepare_trace();
        const bool shadow = a.shadow[0];
        Rays rays = shadow ? load_shadow_rays(a.rays[0]) : load_rays(a.rays[0]);
        std::vector<float> t(rays.count());
        std::vector<std::uint32_t> prim(rays.count());
        std::vector<std::uint8_t> blocked(rays.count());
        peer->prepare_rays(rays);
        CALLGRIND_START_INSTRUMENTATION;
        if (shadow) peer->occluded(rays, blocked.data());
        else peer->trace(rays, t.data(), prim.data());
        CALLGRIND_STOP_INSTRUMENTATION;
        const TreeInfo info = peer->info();
        std::printf(
            "{\"spec\": \"%s\", \"rays\": %zu, \"sah\": %f, \"nodes\": %llu, \"wide_nodes\": %llu, "
            "\"packets\": %llu}\n",
            a.peers[0].c_str(), rays.count(), info.sah, (unsigned long long)info.nodes,
            (unsigned long long)info.wide_nodes, (unsigned long long)info.packets);
        return 0;
    }
    CALLGRIND_START_INSTRUMENTATION;
    peer->build(mesh);
    CALLGRIND_STOP_INSTRUMENTATION;
    TreeInfo info = peer->info();
    std::printf(
        "{\"spec\": \"%s\", \"triangles\": %zu, \"sah\": %f, \"nodes\": %llu, \"references\": %llu, "
        "\"digest\": \"%016llx\"}\n",
        a.peers[0].c_str(), mesh.count(), info.sah, (unsigned long long)info.nodes, (unsigned long long)info.references,
        (unsigned long long)info.digest);
    return 0;
}

}  // namespace
}  // namespace bench

int main(int argc, char** argv) {
    try {
        bench::Args a = bench::parse(argc, argv);
        if (a.mode == "build") return bench::run_build(a);
        if (a.mode == "trace") return bench::run_trace(a);
        if (a.mode == "once") return bench::run_once(a);
        throw std::invalid_argument("unknown mode " + a.mode);
    } catch (const std::exception& e) {
        std::fprintf(stderr, "bvh_bench: %s\n", e.what());
        return 2;
    }
}
