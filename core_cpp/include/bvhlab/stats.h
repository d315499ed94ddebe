// stats.h — what a tree looks like, in numbers (the report's Table 1 columns and more).
#pragma once
#include <cstdint>
#include <vector>
#include "bvhlab/bvh.h"

namespace bvhlab {

struct BvhStats {
    std::uint64_t primitives = 0, triangles = 0, spheres = 0;
    std::uint64_t references = 0;  ///< slots in the leaves: the primitives, more in an SBVH (references repeat)
    std::uint64_t nodes = 0, leaves = 0;
    std::uint32_t height = 0;  ///< largest leaf depth + 1 (root depth 0); 0 for an empty tree
    double sah_cost = 0;       ///< see sah_cost()
    double build_ms = 0;
    double avg_leaf_size = 0;
    std::uint32_t max_leaf_size = 0;
    std::vector<std::uint64_t> nodes_per_depth;      ///< [d] = nodes at depth d
    std::vector<std::uint64_t> leaves_per_depth;     ///< [d] = leaves at depth d
    std::vector<std::uint64_t> leaf_size_histogram;  ///< [k] = leaves holding k primitives
    std::uint64_t memory_bytes = 0;                  ///< nodes, references, depths and leaf-ordered geometry
};

BvhStats compute_stats(const Bvh& bvh);

/// The SAH cost of a whole tree with root box R (docs/design.md "Conventions", one formula everywhere):
///   C = Σ_internal A(n)/A(R)·C_trav + Σ_leaf A(n)/A(R)·N(n)·C_isect,  C_trav = C_isect = 1.
/// 0 for an empty tree; a root of zero area counts every node as hit.
double sah_cost(const Bvh& bvh);

/// Half the surface area of a node's box, in double (the stats must not depend on float rounding).
/// Inline, as sah_term: compute_stats and node_data call them for every node (out of line, called
/// through the Python module's PLT, a 1M-triangle tree's stats took twice as long: 33.8 → 16.9 ms).
inline double node_half_area(const BvhNode& n) {
    const double x = double(n.hi.x) - n.lo.x, y = double(n.hi.y) - n.lo.y, z = double(n.hi.z) - n.lo.z;
    return x * y + y * z + z * x;
}
/// A node's term of sah_cost(): A(n)/A(R) for an internal node, A(n)/A(R)·N(n) for a leaf, with
/// R's half area `root_half_area` (a root of zero area counts every node as hit).
inline double sah_term(const BvhNode& n, double root_half_area) {
    const double p = root_half_area > 0 ? node_half_area(n) / root_half_area : 1.0;
    return is_leaf(n) ? p * leaf_count(n) : p;
}

}  // namespace bvhlab
