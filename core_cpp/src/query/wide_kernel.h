// wide_kernel.h — what the traversal kernels of the wide tree (wide_traverse.inl, one copy per
// instruction set) see: plain pointers, and the helpers they call out of line.
#pragma once
#include <atomic>
#include <cstdint>
#include <cstring>

#include "bvhlab/traverse.h"
#include "bvhlab/wide_bvh.h"

namespace bvhlab {

/// A WideBvh as a plain pointer to its lines (null when the tree is empty).
struct WideView {
    const unsigned char* lines;
};

/// A WideBvh as the kernels see it (null lines for an empty tree).
inline WideView view_of(const WideBvh& wide) { return {wide.lines.empty() ? nullptr : wide.lines.data()->bytes}; }

/// A hit of the wide walk made what every entry point returns: a miss's t is infinity; finish_hit's
/// work is a sphere's u, v, so a triangle's hit (or a miss) skips the call.
inline void finish_wide_hit(const Bvh& bvh, const Ray& ray, Hit& hit) {
    if (hit.ref == kNoHit) hit.t = kInfinity;
    else if (hit.ref & gpu::REF_SPHERE_BIT) [[unlikely]] finish_hit(bvh, ray, hit);
}

/// hit_sphere (ray.h) on lane `lane` of a sphere packet; updates hit (t, ref) as it does.
bool hit_packet_sphere(const PrimPacket& k, int lane, const Ray& ray, Hit& hit);

/// What the recorded walk of the wide tree reports (the inspector's record, ray_record.h; the
/// walk calls it only in its recorded instantiation, wide_traverse.inl traverse_nodes).
class WideRecorder {
public:
    /// The node at `line` was visited: `nearest` is the child word of the child the walk goes to
    /// next (kNoHit where the ray entered none), `pushed[0, count)` those pushed for later.
    virtual void node(std::uint32_t line, std::uint32_t nearest, const std::uint32_t* pushed, std::uint32_t count) = 0;
    /// The leaf whose first packet is at `line` was tested; the closest hit before and after.
    virtual void leaf(std::uint32_t line, const Hit& before, const Hit& after) = 0;

protected:
    ~WideRecorder() = default;
};

/// The wide walk's stack: pushed entries, a field to an array, so that the AVX2 path pushes a
/// node's children as two vector stores of eight (push_children); eight slots of room past the
/// deepest push.
struct WideStack {
    static constexpr std::uint32_t kSize = 7 * gpu::MAX_TREE_HEIGHT + 8;
    alignas(32) std::uint32_t index[kSize];
    alignas(32) float t[kSize];
};

/// The wide TLAS walk (tlas.h Tlas::wide), suspended at a leaf so that its caller can enter the
/// leaf's instances (traverse_two_level.cpp) and resume it with the closest hit found since: the
/// stack, the entry to go on from, and the world ray as the box test needs it (wide_traverse.inl
/// make_query's fields). Plain data, filled by start_tlas_walk.
struct TlasWalk {
    WideStack stack;
    alignas(32) float tmin8[8];
    float o[4], neg_inv[4], neg_inv_far[4];
    std::uint32_t sp, cur, visited;  ///< visited: child boxes tested (the binary walk's box tests)
    float cur_t;
    int octant;
    bool resumed;  ///< false until the first leaf is handed out: the next call pops
};

/// A direction's octant from the bits of its components: bit a set where dir[a]'s sign bit is
/// (make_query's octant, the sign of 1/dir[a]; -0 counts as negative). From bits already read
/// (ray_batch.h prepare_piece), or from the floats (octant_of: group_by_octant, ray_order.h RayKeys).
inline std::uint32_t octant_of_bits(std::uint32_t x, std::uint32_t y, std::uint32_t z) {
    return x >> 31 | (y >> 31) << 1 | (z >> 31) << 2;
}
inline std::uint32_t octant_of(const float* dir) {
    std::uint32_t d[3];
    std::memcpy(d, dir, sizeof d);
    return octant_of_bits(d[0], d[1], d[2]);
}

/// Orders rays [0, count) by octant[i] by a stable counting sort: order[start[k], start[k + 1])
/// the rays of octant k in input order, start[0] = 0 and start[8] = count.
void order_by_octant(const std::uint8_t* octant, std::uint32_t count, std::uint32_t* order, std::uint32_t start[9]);

/// Groups rays[0, count) (count ≤ kWideBatch) by octant (bit a set where dir[a]'s sign bit is:
/// make_query's octant, the sign of 1/dir[a]) by order_by_octant.
void group_by_octant(const Ray* rays, std::uint32_t count, std::uint32_t* order, std::uint32_t start[9]);

namespace detail {
/// Pieces traced through the interleaved walk (intersect_wide_grouped with WideWalk::Interleaved),
/// counted for the tests that check a batch query passes its block's choice on
/// (test_ray_order.cpp); a piece of 256 rays adds one.
inline std::atomic<std::uint64_t> interleaved_pieces{0};
}  // namespace detail

/// intersect_wide_batch and occluded_wide_batch on rays already grouped (order and start as
/// group_by_octant writes them; start[8] rays): hits[i] (nodes_visited[i] where not null) and
/// occluded[i] for rays[i]. The hits are left unfinished: a miss's t is the ray's tmax and a
/// sphere's u, v are not made (ray_batch.h write_hits<true> finishes them as it writes them).
void intersect_wide_grouped(const WideBvh& wide, const Ray* rays, const std::uint32_t* order,
                            const std::uint32_t* start, Hit* hits, std::uint32_t* nodes_visited,
                            WideWalk walk = WideWalk::Alone);
void occluded_wide_grouped(const WideBvh& wide, const Ray* rays, const std::uint32_t* order, const std::uint32_t* start,
                           bool* occluded);

/// The kernels of one instruction set's build of wide_traverse.inl, in namespace `ns` (portable,
/// avx2, avx512): the single-ray walks, the recorded walk, the TLAS walk's steps, and the batch
/// kernels (wide_batch.inl: the rays grouped by group_by_octant, each group through its octant's
/// walk, results in each ray's slot (hits[i], nodes_visited[i] where not null, occluded[i]); a
/// miss's t is the ray's tmax, as intersect_wide_kernel's).
#define BVHLAB_DECLARE_WIDE_KERNELS(ns)                                                                               \
    namespace ns {                                                                                                    \
    Hit intersect_wide_kernel(const WideView& wide, const Ray& ray, std::uint32_t* nodes_visited);                    \
    Hit record_wide_kernel(const WideView& wide, const Ray& ray, WideRecorder& record, std::uint32_t* nodes_visited); \
    bool occluded_wide_kernel(const WideView& wide, const Ray& ray);                                                  \
    void start_tlas_walk(const Ray& ray, TlasWalk& walk);                                                             \
    std::uint32_t next_tlas_leaf(const WideView& wide, TlasWalk& walk, float hit_t, WideRecorder* record);            \
    void intersect_wide_batch_kernel(const WideView& wide, const Ray* rays, const std::uint32_t* order,               \
                                     const std::uint32_t* start, Hit* hits, std::uint32_t* nodes_visited,             \
                                     WideWalk walk);                                                                  \
    void occluded_wide_batch_kernel(const WideView& wide, const Ray* rays, const std::uint32_t* order,                \
                                    const std::uint32_t* start, bool* occluded);                                      \
    }
BVHLAB_DECLARE_WIDE_KERNELS(portable)
BVHLAB_DECLARE_WIDE_KERNELS(avx2)
BVHLAB_DECLARE_WIDE_KERNELS(avx512)
#undef BVHLAB_DECLARE_WIDE_KERNELS

/// The wide TLAS walk on the active instruction set (isa.h): start_tlas_walk sets `walk` up for
/// the (scaled) world ray; each next_tlas_leaf goes on to the next TLAS leaf the ray enters before
/// `hit_t` (nearest first, as the BLAS's wide walk) and returns where its instances start in
/// Tlas::leaf_instances (its first ref's position), or kNoHit when the walk is done. `record`, if
/// given, is told of every wide node visited (WideRecorder::node; ::leaf is never called).
void start_tlas_walk(const Ray& ray, TlasWalk& walk);
std::uint32_t next_tlas_leaf(const WideBvh& wide, TlasWalk& walk, float hit_t, WideRecorder* record = nullptr);

}  // namespace bvhlab
