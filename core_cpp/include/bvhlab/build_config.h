// build_config.h — everything a build can be asked to do, with documented defaults.
#pragma once
#include <cstdint>
#include <functional>
#include <string>
#include <string_view>
#include <vector>

namespace bvhlab {

/// How a node's primitives are split in two (one small function each, see split_*.cpp).
enum class SplitMethod {
    Median,    ///< equal counts at the median centroid, std::nth_element, O(n) (report §2.3.1)
    Mean,      ///< partition at the mean centroid (report §2.3.1)
    Midpoint,  ///< partition at the middle of the centroid bounds (PBRT "Middle")
    Sah,       ///< binned surface area heuristic, O(n + B) sweep (report §2.3.2, PBRT)
    SweepSah,  ///< exact SAH over centroids sorted on the axis (every split position)
    Lbvh,      ///< linear BVH: Morton-sorted centroids split at the highest differing bit (report §5.2)
    Sbvh,      ///< spatial splits (Stich, Friedrich and Dietrich 2009): binned SAH object splits, and
               ///< spatial splits that clip triangles into bins; references may repeat (src/build/sbvh/)
};

/// Which axis a node is split on (report §2.3).
enum class AxisPolicy {
    Largest,  ///< largest centroid extent (PBRT; the report's default)
    Random,   ///< a seeded random axis per node (Shirley 2020), reproducible
    Best,     ///< try all three and keep the lowest SAH (the report's unimplemented option)
    Auto,     ///< the method's own: Best for the SAH methods (which weigh all axes in one pass), else Largest
};

/// What the B equal buckets of the binned SAH divide on each axis (report §2.3.2).
enum class BinBounds {
    Centroids,  ///< the node's centroid bounds, "from the centroid with the lowest to the highest
                ///< coordinate" (report §2.3.2; PBRT): the report's buckets
    Box,        ///< the node's box (tinybvh BuildAVX)
};

/// Progress callback: fraction done in [0, 1]; return false to cancel the build (Embree's shape).
using ProgressCallback = std::function<bool(double)>;

/// Build arguments. The defaults give the tree that traces fastest for the least build time:
/// binned SAH over all three axes with 12 buckets dividing the node's box (with 8 on Sponza, SAH
/// 70.6 against 77.6 over the centroid bounds; on 1M-triangle meshes within 0.3%), leaves of up to four
/// primitives where the SAH finds them cheaper (report §5.1; the CPU traversal tests four
/// triangles at once), primitives counted one by one (sah_block 1). The report's own settings
/// (Table 1) are method sah with 12 or 32 bins over the centroid bounds, axis largest, one
/// primitive per leaf, sah_block 1: pass them explicitly.
///
/// Why 12 buckets and sah_block 1 (issue 36; SAH in sah_cost's convention, bench/build.py's
/// scenes and a 1.04M-triangle mesh repeated 20 times in a row, against tinybvh 1.9 BuildSIMD):
/// with 8 buckets and blocks of four, uniform1m 394.1 against tinybvh's 385.5, the row of meshes
/// 67.1 against 66.1, room1m 31.75 against 31.59; blocks of four cost 2.5% on uniform1m even with
/// the exact SAH (sweep_sah 392.8 against 378.8), and blocks of one alone leave room1m at 31.70.
/// 12 buckets and blocks of one: 382.5, 65.6, 31.13, Sponza 70.9 (tinybvh 71.6): every scene
/// below tinybvh's. room1m's SAH moves either way with the bucket count (4: 31.54, 8: 31.70,
/// 16: 31.88, 32: 33.76: which top split carves the walls from the model). The wide traversal
/// runs about as many instructions a ray on either tree (callgrind, random rays: Sponza +3.7%,
/// room1m -0.4%, uniform1m -4.2%, the row -1.4%) and the build about as many (Sponza +2.5%,
/// room1m -1.6%, uniform1m +1.4%). Tried since and not taken (docs/design.md "Bucket counts and the
/// greedy SAH"): 14 buckets (every bench scene at or below tinybvh, but Sponza's traversal +1.4%),
/// finer buckets for small ranges only (7-19% more build instructions for 0.1-0.4% on repeat1m).
struct BuildConfig {
    SplitMethod method = SplitMethod::Sah;
    AxisPolicy axis = AxisPolicy::Auto;
    std::uint32_t bins = 12;                ///< binned SAH buckets, kMinBins..kMaxBins
    BinBounds bin_bounds = BinBounds::Box;  ///< what the binned SAH's buckets divide
    std::uint32_t max_leaf_size = 4;        ///< leaves hold at most this many primitives (>= 1)
    std::uint64_t seed = 0;                 ///< for AxisPolicy::Random
    std::uint32_t threads = 0;              ///< 0 = every hardware thread; the tree never depends on it
    float traversal_cost = 1.0f;            ///< C_trav of the SAH
    float intersection_cost = 1.0f;         ///< C_isect of the SAH
    /// The SAH counts primitives in blocks of this many (a power of two, 1..kMaxSahBlock) above a
    /// node of one block (sah.h): 4 fills the wide CPU traversal's packets of four triangles
    /// (Sponza: 3.8 triangles per packet of four against 3.3 with 1) but gives a worse tree by
    /// sah_cost (see above); 1, the default, is the report's SAH.
    std::uint32_t sah_block = 1;
    /// method sbvh: spatial splits are tried where the object split's children overlap by more than
    /// this fraction of the root's surface area (Stich et al. 2009 §4.5, α; the paper's 1e-5 binned
    /// 1.7× the references for a slightly worse Sponza tree: docs/design.md, "Spatial splits").
    float sbvh_alpha = 3e-4f;
    /// method sbvh: the tree holds at most this many references per primitive (>= 1); once they
    /// are spent, only object splits. 1.5, as Embree's SBVH builder allows.
    float sbvh_budget = 1.5f;
    /// method sbvh: reference unsplitting (Stich et al. 2009 §4.4): a reference that straddles a
    /// spatial split goes to one side whole where that is cheaper than two halves.
    bool sbvh_unsplit = true;
    ProgressCallback progress;  ///< optional; called from the calling thread only
};

inline constexpr std::uint32_t kMinBins = 2;
inline constexpr std::uint32_t kMaxBins = 256;
inline constexpr std::uint32_t kMaxSahBlock = 64;
inline constexpr std::uint32_t kMaxLeafSize = 0x7fffffff;  ///< a leaf's count must fit the node's 31 bits

/// Names as the Python API and the CLI spell them (from the table of methods, split.h).
/// parse_* throw std::invalid_argument listing the valid names.
std::vector<std::string_view> split_method_names();
std::vector<std::string_view> axis_policy_names();
std::vector<std::string_view> bin_bounds_names();
SplitMethod parse_split_method(std::string_view name);
AxisPolicy parse_axis_policy(std::string_view name);
BinBounds parse_bin_bounds(std::string_view name);
std::string to_string(SplitMethod method);
std::string to_string(AxisPolicy axis);
std::string to_string(BinBounds bounds);

/// Throws std::invalid_argument when a field is out of range.
void validate(const BuildConfig& config);

/// The most references an SBVH over `primitives` primitives may hold: sbvh_budget per primitive,
/// rounded down, never fewer than the primitives nor more than a reference slot can index.
std::uint64_t sbvh_reference_limit(std::uint64_t primitives, const BuildConfig& config);

/// True for the methods that evaluate the SAH (and may stop early at a leaf, PBRT §4.3.2).
bool uses_sah(SplitMethod m);

}  // namespace bvhlab
