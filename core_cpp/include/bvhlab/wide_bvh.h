// wide_bvh.h — an 8-wide copy of a built binary tree for fast CPU traversal: one vector test
// checks eight child boxes, and leaves hold triangles four to a packet, tested together (the
// layouts Embree's and tinybvh's CPU kernels use). It is a conversion of the tree, not a rebuild
// (tinybvh's habit): the same boxes, the binary nodes between them collapsed eight children at a
// time, and small subtrees merged into one leaf.
#pragma once
#include <cstdint>

#include "bvhlab/big_vector.h"
#include "bvhlab/bvh.h"
#include "bvhlab/ray.h"

namespace bvhlab {

/// Bit 31 of a WideNode child: the child is a leaf. One word says what a child is and where, so
/// that the traversal's stack entries are a word and a distance (one permute and store fewer a
/// push, one load fewer a pop than with a packet count beside the line; tinybvh's BVH8_CPU marks
/// its leaves in the child index the same way).
inline constexpr std::uint32_t kLeafChild = 1u << 31;

/// Eight child boxes in structure-of-arrays form, 256 bytes (four cache lines). An unused slot
/// has an inverted box (lo = +inf, hi = -inf), which no ray enters.
struct alignas(64) WideNode {
    float lo_x[8], hi_x[8], lo_y[8], hi_y[8], lo_z[8], hi_z[8];
    /// The line (WideBvh::lines) of an inner child, or kLeafChild | the line of a leaf's first
    /// packet (its further packets follow it: PrimPacket::more)
    std::uint32_t child[8];
    std::uint32_t unused[8];  ///< keeps the node four whole lines
    bool leaf(int k) const { return (child[k] & kLeafChild) != 0; }
    std::uint32_t line(int k) const { return child[k] & ~kLeafChild; }
};
static_assert(sizeof(WideNode) == 256);

/// Four primitives of one kind, structure of arrays (192 bytes, three cache lines):
/// v[vertex][axis][lane]. Triangles: the three vertices, as PackedPrim has them (the watertight
/// test reads vertices, so the kernel loads each axis by the ray's axis order). Spheres: centre in
/// v[0], radius in v[1][0]. An empty lane has ref = kNoHit and NaN vertices (the triangle test's
/// sign test fails on NaN, before it would make a point's zero edge functions again). `slot` is
/// each lane's position in Bvh::prims (finish_hit), in the packet because a packet takes three
/// lines whether it holds it or not.
struct alignas(64) PrimPacket {
    float v[3][3][4];
    std::uint32_t ref[4];
    std::uint32_t slot[4];
    std::uint32_t more;  ///< 1 when the next packet belongs to the same leaf, else 0
    std::uint32_t unused[3];
};
static_assert(sizeof(PrimPacket) == 192);

/// The unit of WideBvh::lines: one cache line.
struct alignas(64) WideLine {
    unsigned char bytes[64];
};
inline constexpr std::uint32_t kNodeLines = sizeof(WideNode) / sizeof(WideLine);
inline constexpr std::uint32_t kPacketLines = sizeof(PrimPacket) / sizeof(WideLine);

/// The wide tree in one block, in depth-first preorder: each node followed by the packets of its
/// leaf children, in slot order, then by its inner children's subtrees, as Embree's allocator
/// lays out its trees. A ray that enters a node and then one of its leaves reads neighbouring
/// memory, and a node's four lines, read in a row, start the hardware's stream prefetch of the
/// leaves after them. A WideNode's child is a line index (of a node, or, with kLeafChild, of a
/// leaf's first packet, the others following it).
struct WideBvh {
    BigVector<WideLine> lines;  ///< root node at line 0; none when the tree is empty
    std::uint32_t node_count = 0, packet_count = 0;

    const WideNode& node(std::uint32_t line) const { return *reinterpret_cast<const WideNode*>(&lines[line]); }
    const PrimPacket& packet(std::uint32_t line) const { return *reinterpret_cast<const PrimPacket*>(&lines[line]); }
};

/// Collapses the binary tree: a subtree of at most four primitives becomes one leaf, and the
/// binary inner nodes that become wide nodes are those of least total surface area (the
/// cost-optimal collapse of Ylitie et al. 2017; each wide node holds up to eight children). A
/// tree that is one leaf gets a root node with that leaf as its only child, so its box is tested
/// as every other traversal tests it.
WideBvh make_wide(const Bvh& bvh);

/// The TLAS's wide copy (tlas.h Tlas::wide): the same collapse over a tree of instances, without
/// merging (each binary leaf stays a child of its own; a leaf child is kLeafChild | the position
/// of the leaf's first ref, where its instances start in Tlas::leaf_instances) and without
/// packets: WideNodes only, each with the count of its children in unused[0] and the binary node
/// it was made from in unused[1].
WideBvh make_wide_tlas(const Bvh& tlas);

/// Closest hit through the wide tree (nearest child first, by the middle of the ray's span in
/// each box): the same hit as intersect() on the binary tree, bit for bit, on every instruction
/// set path (isa.h).
Hit intersect_wide(const WideBvh& wide, const Bvh& bvh, const Ray& ray, std::uint32_t* nodes_visited = nullptr);

/// Any hit through the wide tree (occluded, traverse.h): the walk of intersect_wide, ended at the
/// first leaf with a hit nearer than ray.tmax; exactly when intersect_wide's t < ray.tmax.
bool occluded_wide(const WideBvh& wide, const Ray& ray);

/// The batch's piece that intersect_wide_batch and occluded_wide_batch group by octant at once
/// (intersect_batch's pieces, ray_batch.h prepare_piece, are this size): 256 rays keep a piece's
/// rays, order and hits (16 KiB) in the first-level cache beside the tree's nodes (1,024 took 65
/// KiB: repeat1m primary rays 3.45 simulated D1 misses a ray through the batch, 0.79 ray by ray).
inline constexpr std::uint32_t kWideBatch = 256;

/// How a batch's closest-hit walk takes the rays that go alone (not as a packet): one after
/// another, or several at a time on one thread, each walk stepped in turn so that their cache
/// misses overlap (src/query/wide_interleaved.inl). The same hits either way, bit for bit;
/// Interleaved pays where the rays wait on memory and costs where the tree stays in the caches
/// (intersect_batch chooses per block: src/query/ray_batch.h for_each_block).
enum class WideWalk { Alone, Interleaved };

/// intersect_wide for each of rays[0, count): hits[i] (and nodes_visited[i], where given) for
/// rays[i], the same hit bit for bit. The rays are traced grouped by octant (the sign bits of
/// their direction), each group by the walk compiled for that octant, in pieces of kWideBatch
/// rays: no walk chosen per ray by an indirect call, one walk's code in use at a time. On the AVX2
/// path, without nodes_visited, eight rays of a group in a row with one origin and directions
/// within ~5.7° (a camera's neighbouring pixels) go through the tree as one packet
/// (src/query/wide_packet.inl); nodes_visited asked for, every ray goes alone. The rays that go
/// alone go one after another or interleaved (`walk`).
void intersect_wide_batch(const WideBvh& wide, const Bvh& bvh, const Ray* rays, std::size_t count, Hit* hits,
                          std::uint32_t* nodes_visited = nullptr, WideWalk walk = WideWalk::Alone);

/// occluded_wide for each of rays[0, count), to occluded[i], grouped by octant as
/// intersect_wide_batch (one ray after another: the any-hit walk is not interleaved).
void occluded_wide_batch(const WideBvh& wide, const Ray* rays, std::size_t count, bool* occluded);

}  // namespace bvhlab
