// bench_data.h — what the C++ benchmark driver reads (raw float32 files written by bench/*.py) and
// the peers it times side by side (bvhlab, Embree 3, tinybvh when present).
#pragma once
#include <time.h>

#include <chrono>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace bench {

/// Triangles as T×3×3 float32 (numpy's `tris.tofile(path)`).
struct Mesh {
    std::vector<float> xyz;
    std::size_t count() const { return xyz.size() / 9; }
};

/// Rays as N×6 float32: origin, direction; shadow rays also have each ray's tmax (the segment's end,
/// in units of the direction), read from N×7 files (origin, direction, tmax).
struct Rays {
    std::vector<float> od;
    std::vector<float> tmax;  ///< shadow rays only
    std::size_t count() const { return od.size() / 6; }
};

/// A file of whole rows of `width` floats (`what` names them in the error otherwise).
std::vector<float> load_rows(const std::string& path, std::size_t width, const char* what);
Mesh load_mesh(const std::string& path);
/// The rays' origins and directions apart (N×3 each), as the batch queries take them.
void split_rays(const Rays& rays, std::vector<float>& origins, std::vector<float>& directions);
Rays load_rays(const std::string& path);
Rays load_shadow_rays(const std::string& path);

/// What one peer reports about the tree it built (NaN / 0 where it cannot tell).
struct TreeInfo {
    double sah = 0.0 / 0.0;  ///< bvhlab's convention: Σ_internal A/A_root + Σ_leaf A/A_root·N
    std::uint64_t nodes = 0;
    std::uint64_t references = 0;  ///< primitive slots in the leaves (more than the triangles with spatial splits)
    std::uint64_t digest = 0;      ///< bvhlab: FNV-1a of the nodes and references, to compare builds bit for bit
    std::uint64_t wide_nodes = 0;  ///< bvhlab, after prepare_trace: the 8-wide copy's nodes
    std::uint64_t packets = 0;     ///< bvhlab, after prepare_trace: its leaves' packets of four primitives
};

/// One system under test. build() is what is timed; trace() answers closest hits one ray at a time
/// (t = inf and prim = ~0u on a miss).
class Peer {
public:
    virtual ~Peer() = default;
    virtual std::string name() const = 0;
    virtual void build(const Mesh& mesh) = 0;
    virtual TreeInfo info() const = 0;
    /// Work a system does once before tracing that is not part of its build (e.g. a wide copy).
    virtual void prepare_trace() {}
    /// Work a system does once for a ray set before it is traced (untimed): bvhlab batch=1 splits
    /// the rays into the arrays of its batch queries.
    virtual void prepare_rays(const Rays&) {}
    virtual void trace(const Rays& rays, float* t, std::uint32_t* prim) = 0;
    /// Any-hit queries (shadow rays) one ray at a time: occluded[i] = 1 when ray i hits anything at
    /// t in (0, rays.tmax[i]).
    virtual void occluded(const Rays& rays, std::uint8_t* occluded) = 0;
};

/// "bvhlab:key=value,..." (method, bins, axis, leaf, threads; query=stack|stackless|wide),
/// "embree:low|medium|high", "tinybvh:option,..." (hq: BuildHQ, opt or opt=N: Optimize, bvh4:
/// BVH4_CPU rather than BVH8_CPU traversal). Throws std::invalid_argument for unknown names.
std::unique_ptr<Peer> make_peer(const std::string& spec, unsigned threads);

std::unique_ptr<Peer> make_bvhlab_peer(const std::string& options, unsigned threads);
std::unique_ptr<Peer> make_embree_peer(const std::string& quality, unsigned threads);   // peer_embree.cpp
std::unique_ptr<Peer> make_tinybvh_peer(const std::string& variant, unsigned threads);  // peer_tinybvh.cpp

inline double seconds_since(std::chrono::steady_clock::time_point t0) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

/// CPU time of the calling thread (rays are traced on one thread): on a loaded machine, where the
/// wall time of a pass includes the time other processes held its core.
inline double thread_cpu_seconds() {
    timespec ts{};
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
    return double(ts.tv_sec) + 1e-9 * double(ts.tv_nsec);
}

}  // namespace bench
