// node_data.h — what every node of a tree is and costs, computed for all nodes at once (issue 35):
// the numbers an inspector shows beside a box, as arrays indexed by node (depth-first order).
#pragma once
#include <cstdint>
#include <vector>

#include "bvhlab/bvh.h"
#include "bvhlab/cancel.h"

namespace bvhlab {

/// Per-node arrays, one entry per node of Bvh::nodes (3 per node for lo and hi). Costs use the
/// tree's one SAH formula (stats.h sah_cost: C_trav = C_isect = 1, areas relative to the root).
struct NodeData {
    std::vector<float> lo, hi;              ///< the box, N×3
    std::vector<std::uint8_t> depth;        ///< root 0
    std::vector<std::int32_t> parent;       ///< -1 for the root
    std::vector<std::int32_t> left, right;  ///< children (left = i + 1); -1 for a leaf
    std::vector<std::uint32_t> prim_count;  ///< primitives in the node's subtree
    std::vector<double> area;               ///< surface area of the box (full, not half)
    std::vector<double> sah_term;           ///< the node's own term of sah_cost()
    std::vector<double> subtree_sah;        ///< Σ sah_term over the node's subtree (root: sah_cost())
    std::vector<double> sah_share;          ///< subtree_sah / sah_cost() (root: 1)
    std::vector<double> child_overlap;      ///< area(box(left) ∩ box(right)) / area(node); 0 for a leaf
    std::vector<double> epo;                ///< the node's end-point overlap term, see epo_terms()
    double sah_cost = 0, epo_cost = 0;      ///< Σ sah_term, Σ epo
    double surface_area = 0;                ///< A(Q): the triangles' area, EPO's normaliser
};

/// Every node's data; `threads` as in BuildConfig (0 = all). The EPO pass clips each triangle
/// by the boxes it overlaps: O(triangles × overlapped nodes), which on a soup of large
/// overlapping triangles nears triangles² (15,000 in a unit cube: 30 s; a 1M-triangle knot: 1.44 s,
/// 0.17 s without it); `cancel` (may be null) stops it (throws Cancelled). Without `epo` it is not
/// made: epo holds NaNs and epo_cost is NaN (what a pick needs, at once).
NodeData compute_node_data(const Bvh& bvh, unsigned threads = 0, Cancellation* cancel = nullptr, bool epo = true);

/// End-point overlap (Aila, Karras and Laine 2013, "On Quality Metrics of Bounding Volume
/// Hierarchies", eq. 3): EPO = Σ_n C_n · A((Q \ Q_n) ∩ n) / A(Q), where Q is the scene's surface,
/// Q_n the surface in n's subtree, A(· ∩ n) the area of surface inside n's box, and C_n the
/// node's SAH cost factor (1 for an internal node, its primitive count for a leaf, as in
/// sah_cost()). Only triangles count: spheres are neither clipped nor in A(Q).
/// Returns the term of each node (their sum is the tree's EPO).
std::vector<double> epo_terms(const Bvh& bvh, unsigned threads = 0, Cancellation* cancel = nullptr);

/// A(Q) of epo_terms(): the area of the tree's triangles (each reference once; spheres not counted).
double surface_area(const Bvh& bvh);

/// The area of the part of triangle (a, b, c) inside box [lo, hi] (Sutherland–Hodgman clipping
/// by the six planes of the box), in double.
double clipped_triangle_area(const double a[3], const double b[3], const double c[3], const double lo[3],
                             const double hi[3]);

}  // namespace bvhlab
