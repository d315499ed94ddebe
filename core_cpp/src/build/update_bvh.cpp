// update_bvh.cpp — the update policies of update.h, their names and checks, and the per-node
// costs they compare.
#include "bvhlab/update.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <stdexcept>

#include "bvhlab/stats.h"
#include "rebuild_subtrees.h"
#include "rebuild_top.h"

namespace bvhlab {
namespace {

using Clock = std::chrono::steady_clock;

constexpr std::string_view kNames[] = {"rebuild", "refit", "partial", "adaptive"};

/// Where adaptive's reference was taken: the root's cost then (relative to its box), the root's
/// half area then and its primitives' surface area then (primitives_surface_area; < 0: not known). Carried
/// after the nodes' costs in `built` (update.h): entries n and n + 1.
struct Reference {
    double cost = 0, area = 0, primitives = -1;
};

/// The surface area of a tree's primitives (its packed geometry; a triangle of zero area is packed
/// as a point): what grows with the geometry's scale and not as it turns or moves apart.
double primitives_surface_area(const Bvh& bvh) {
    constexpr double kFourPi = 12.566370614359172;
    double sum = 0;
    for (const PackedPrim& p : bvh.prims) {
        if (is_sphere_ref(p.ref)) {
            sum += kFourPi * double(p.v1.x) * double(p.v1.x);
        } else {
            const Vec3 a{p.v0.x, p.v0.y, p.v0.z}, e1 = Vec3{p.v1.x, p.v1.y, p.v1.z} - a,
                                                  e2 = Vec3{p.v2.x, p.v2.y, p.v2.z} - a;
            sum += 0.5 * double(length(cross(e1, e2)));
        }
    }
    return sum;
}

/// Adaptive's reference for the root now, of half area `now`, whose primitives' surface area is
/// `primitives` (primitives_surface_area; < 0: not measured): an estimate of a fresh build's cost. A cost
/// relative to the root's box falls where the geometry spreads and its parts stay as they were,
/// while a fresh build's area-weighted cost A·cost stays about the same (slabs of a knot moved
/// apart by 0.6: A·cost 2,545 to 2,660, +4.5%, its cost 35.11 to 33.27, -5.2%, as the root's area
/// grew 10.3%); compared with the cost when built, a restructured tree sat at 1.13 of a fresh
/// build's. But where the geometry grows as a whole (a mesh scaled up), the cost stays and its
/// A·cost grows with the root: kept at its A·cost, every update of a mesh scaled up by 1.1 a frame
/// was a full rebuild to the same cost (45.47, 12 frames of 12). The primitives' surface area tells
/// the two apart: it grows with the geometry's scale, not as its parts move apart, turn or tear
/// leaves apart (the primitives' boxes grew as much as the root's where long thin triangles turned:
/// taken for growth, a turning slab of them stayed refitted at 1.19 of a fresh build's cost). So
/// where the root is larger than when the reference was taken, the reference's A·cost grows as the
/// surface did, at most as the root's (the cost kept) and at least not at all (the estimate errs
/// low: a rebuild sooner, which takes the fresh cost as the new reference). Small parts flying
/// apart (50,000 triangles, by 1.1 a frame, their refit within 1.02 of a fresh build's) still
/// rebuild at every update: keeping the inner nodes' cost relative to the root instead (their
/// boxes taken to grow with it) erred high elsewhere (spheres moved apart stayed refitted at 1.13
/// of a fresh build's cost, test_update_top.cpp). Where the root is smaller, the cost stays (a
/// fresh build's cost rises where parts come together, and a uniform shrink leaves it as it was).
/// Kept with its areas, not rescaled frame by frame: a root that grows and shrinks back (the
/// crowd's, ±1.2%) would ratchet it down (6 rebuilds of 23 frames on the generated crowd, 3 on the
/// wave).
double reference_cost(const Reference& ref, double now, double primitives) {
    if (!(now > ref.area && ref.area > 0)) return ref.cost;
    const double grown =
        ref.primitives > 0 && primitives >= 0 ? std::clamp(primitives / ref.primitives, 1.0, now / ref.area) : 1.0;
    return ref.cost * grown * (ref.area / now);
}

/// The restructuring after a refit: rebuild `roots` and splice them in; returns the new tree's
/// SAH cost (from the old one's and what the new subtrees took off: no pass over the tree).
double restructure(Bvh& tree, NodeCostArray& built, const NodeCosts& now, const std::vector<std::uint32_t>& roots,
                   const GeometryView& g, UpdateStats& stats) {
    double saved = 0;
    stats.primitives_rebuilt = rebuild_subtrees(tree, built, roots, g, now, saved);
    stats.subtrees_rebuilt = static_cast<std::uint32_t>(roots.size());
    if (now.area[0] > 0) return (now.area_cost(0) - saved) / now.area[0];
    return node_costs(tree).root_cost;  // a root of zero area: its cost counts nodes
}

/// The boxes per primitive above which adaptive's first cut is coarsened to top_coarse_cut_
/// primitives (update.h). The cut of top_cut_primitives with the intact subtrees whole held, per
/// primitive, 0.152-0.165 boxes on the waves (no subtree as built but the rebuilt parts) and
/// 0.024-0.061 on the crowds (bench/updates.py's four animations, every top of 23 frames): the
/// top's build costs about as much per box as a build per primitive, so only the dense cuts are
/// worth coarsening, and the crowds' tops stay as they were (coarser, they cost more SAH).
constexpr double kDenseCut = 0.1;

/// Adaptive past target_growth (its caller's check), after a refit whose measured costs are
/// `now`: first the subtrees that take most of the excess off per primitive are rebuilt from their
/// primitives (subtrees_by_excess: Yoon, Curtis and Manocha 2007 restructure only where culling
/// efficiency dropped; the SAH cost is that measure), at most restructure_share of the primitives;
/// then, while the tree still costs more than top_growth × its cost when built, the levels above
/// the topmost subtrees of at most top_cut_primitives are rebuilt over those subtrees' boxes
/// (rebuild_top: the excess of the large nodes, which no subtree of a share of the primitives
/// holds, is how the parts are grouped; its one copy of the nodes splices the rebuilt subtrees
/// too, else splice_parts does). A full rebuild instead when the tree still costs more
/// than tree_growth × its cost when built. Returns what ran; `sah`
/// receives the tree's cost after it. bench/updates.py has the figures.
UpdatePolicy adaptive(Bvh& tree, NodeCostArray& built, const NodeCosts& now, const GeometryView& g,
                      const UpdateConfig& config, UpdateStats& stats, double& sah) {
    // a root of zero area costs 0 (node_costs), so its caller's check never sends one here; kept
    // for callers that would: no areas to weigh the subtrees by
    if (now.area[0] <= 0) return UpdatePolicy::Rebuild;
    const double goal = built[0];
    const double excess = double(now.area[0]) * (double(now.cost[0]) - goal);
    double covered = 0;
    const std::vector<std::uint32_t> roots =
        subtrees_by_excess(tree, now, built, excess, config.min_subtree_primitives,
                           std::uint64_t(config.restructure_share * now.count[0]), covered);
    double saved = 0;
    const std::vector<RebuiltPart> parts = build_parts(tree, roots, g, now, saved);
    place_part_slots(tree, parts);
    if (!parts.empty()) sah = (now.area_cost(0) - saved) / now.area[0];
    stats.subtrees_rebuilt = static_cast<std::uint32_t>(parts.size()), stats.primitives_rebuilt = primitives_in(parts);
    if (config.top_cut_primitives > 0 && sah > config.top_growth * goal) {
        const PartedTree parted(tree, now, parts, &built);
        // first over a coarser cut: the intact subtrees of top_intact_primitives whole, and where
        // that cut is still dense (the waves: no subtree as built but the parts), subtrees of
        // top_coarse_cut_primitives; over the fine cut of top_cut_primitives alone where that top
        // would leave the tree past tree_growth (a full rebuild otherwise)
        const std::uint32_t fine = config.top_cut_primitives;
        const bool may_coarsen = config.top_coarse_cut_primitives > fine;
        for (const bool first : {true, false}) {
            // the first cut and, where it is dense, its coarser version, from one scan (top_cuts)
            std::vector<PartNode> cut, coarse;
            bool coarser = first && config.top_intact_primitives > fine;
            if (first && may_coarsen) {
                const auto dense = std::size_t(std::floor(kDenseCut * now.count[0]));  // size > kDenseCut · count
                if (top_cuts(parted, fine, config.top_coarse_cut_primitives, config.top_intact_primitives, dense, cut,
                             coarse))
                    cut = std::move(coarse), coarser = true;
            } else {
                cut = top_cut(parted, fine, first ? config.top_intact_primitives : 0u);
            }
            if (cut.size() > 1) {
                const CutInfo info = cut_info(parted, cut);
                const Bvh top = built_top(tree.config, info);
                if (coarser && top_sah_cost(top, info) > config.tree_growth * goal) continue;
                if (rebuild_top(tree, built, parted, cut, info, top, sah)) {
                    stats.top_boxes = std::uint32_t(cut.size());
                    break;
                }
            }
            if (!coarser) break;  // the fine cut: tried once
        }
    }
    if (stats.top_boxes == 0) splice_parts(tree, built, parts);  // the top rebuild splices them itself
    if (parts.empty() && stats.top_boxes == 0 && sah <= config.tree_growth * goal) return UpdatePolicy::Refit;
    return sah > config.tree_growth * goal ? UpdatePolicy::Rebuild : UpdatePolicy::Partial;
}

}  // namespace

NodeCosts node_costs(const Bvh& bvh) {
    // S(n); for a node of zero area no cost (0: S/A has no value there, and a count of nodes, the
    // cost were every node hit, stood as a reference no tree spread out again came under: a mesh
    // grown from scale 0 stayed a refit at 122× a fresh build's SAH); the root's cost unrounded,
    // and for a root of zero area U(n) (every node counted as hit: its inner nodes, (size - 1) / 2
    // of its subtree's `size` nodes, and its primitives), sah_cost's convention
    BigVector<double> area_cost(bvh.nodes.size());
    NodeCosts out{NodeCostArray(bvh.nodes.size()), NodeCostArray(bvh.nodes.size()),
                  BigVector<std::uint32_t>(bvh.nodes.size())};
    // node i + 1's S and count (the first child's) are the last iteration's, kept in registers:
    // read back from the arrays, each inner node waited on the store just made (the chain of
    // first children runs through them)
    double next_area_cost = 0;
    std::uint32_t next_count = 0;
    for (std::uint32_t i = bvh.node_count(); i-- > 0;) {
        const BvhNode& n = bvh.nodes[i];
        const double area = node_box(n).half_area();
        if (is_leaf(n)) {
            next_area_cost = area * leaf_count(n), next_count = leaf_count(n);
        } else {
            next_area_cost = area + next_area_cost + area_cost[n.index];
            next_count = next_count + out.count[n.index];
        }
        area_cost[i] = next_area_cost, out.count[i] = next_count;
        // a leaf's S/A is its count exactly (A·N is exact in double for N < 2^29): no division,
        // which took a third of this pass's time
        const bool exact = is_leaf(n) && leaf_count(n) < (1u << 29);
        out.cost[i] = float(area > 0 ? (exact ? double(leaf_count(n)) : area_cost[i] / area) : 0.0);
        out.area[i] = float(area);
    }
    if (bvh.node_count() > 0) {  // the root's cost unrounded (its U(n) where it has no area)
        const double area = node_box(bvh.nodes[0]).half_area();
        out.root_cost =
            area > 0 ? area_cost[0] / area : double((skip_index(bvh.nodes[0], 0) - 1) / 2) + double(out.count[0]);
    }
    return out;
}

NodeCostArray subtree_costs(const Bvh& bvh) { return node_costs(bvh).cost; }

Bvh update_bvh(const Bvh& old, const NodeCostArray& built, const GeometryView& g, const UpdateConfig& config,
               NodeCostArray& built_out, UpdateStats* stats_out) {
    validate(config);
    const std::size_t n = old.nodes.size();
    if (built.size() < n || built.size() > n + 2)
        throw std::invalid_argument("update: the built costs must have one entry per node of the tree");
    // adaptive's reference: the root's cost when built, its half area and the surface area then
    // (`old`'s where it is the tree as built; not known where only the area was carried)
    const bool adaptive_policy = config.policy == UpdatePolicy::Adaptive;
    Reference ref{n ? built[0] : 0.0, n ? node_box(old.nodes[0]).half_area() : 0.0};
    if (built.size() > n) ref.area = built[n];
    if (built.size() > n + 1) ref.primitives = built[n + 1];
    else if (built.size() == n && adaptive_policy) ref.primitives = primitives_surface_area(old);
    const auto start = Clock::now();
    UpdateStats stats;
    stats.policy = config.policy;
    Bvh tree;
    BuildConfig whole = old.config;  // a whole build's config: the tree's own, with the update's progress
    whole.progress = config.progress;
    auto rebuild = [&] {
        tree = build_bvh(g, whole);
        const NodeCosts fresh = node_costs(tree);
        built_out = fresh.cost;
        stats.sah_cost = tree.empty() ? 0.0 : fresh.root_cost;
        ref = {stats.sah_cost, tree.empty() ? 0.0 : fresh.area[0],
               adaptive_policy ? primitives_surface_area(tree) : -1.0};
        stats.policy = UpdatePolicy::Rebuild, stats.subtrees_rebuilt = 1,
        stats.primitives_rebuilt = g.primitive_count();
    };
    // an SBVH refits by a rebuild (refitted), and its subtrees' references are not whole primitives;
    // its refit, partial and adaptive keep the primitives as any tree's do (they rebuilt over other
    // counts, where refit refused them)
    if (config.policy != UpdatePolicy::Rebuild && old.config.method == SplitMethod::Sbvh) check_same_primitives(old, g);
    if (config.policy == UpdatePolicy::Rebuild || old.config.method == SplitMethod::Sbvh) {
        rebuild();
    } else {
        tree = refitted(old, g, old.config.threads);
        const NodeCosts now = node_costs(tree);
        stats.sah_cost = tree.empty() ? 0.0 : now.root_cost;
        // A tree built (or last rebuilt) over geometry of no area (a mesh scaled to 0, squashed onto
        // a line or a point) has costs that count nodes, not areas, and a shape that says nothing of
        // the geometry spread out again: partial's and adaptive's references from then were never
        // passed (a mesh grown from scale 0 stayed a refit at 122× a fresh build's SAH). Once the
        // geometry has area again, they rebuild.
        const bool restructures = config.policy == UpdatePolicy::Partial || config.policy == UpdatePolicy::Adaptive;
        if (restructures && ref.area <= 0 && !tree.empty() && now.area[0] > 0) {
            rebuild();
        } else {
            built_out = built;
            // what adaptive aims for: the primitives measured only where the root grew and its
            // cost is past the reference kept at its A·cost (a pass over them)
            double primitives = -1, goal = 0;
            if (adaptive_policy && !tree.empty()) {
                goal = reference_cost(ref, now.area[0], primitives);
                if (now.cost[0] > config.target_growth * goal && now.area[0] > ref.area) {
                    primitives = primitives_surface_area(tree);
                    goal = reference_cost(ref, now.area[0], primitives);
                }
                built_out[0] = float(goal);
            }
            double sah = stats.sah_cost;
            UpdatePolicy ran = UpdatePolicy::Refit;
            if (config.policy == UpdatePolicy::Partial) {
                const std::vector<std::uint32_t> roots =
                    subtrees_past(tree, now, built, config.subtree_growth, config.min_subtree_primitives);
                if (!roots.empty()) sah = restructure(tree, built_out, now, roots, g, stats);
                ran = UpdatePolicy::Partial;
            } else if (config.policy == UpdatePolicy::Adaptive && !tree.empty() &&
                       now.cost[0] > config.target_growth * built_out[0]) {
                ran = adaptive(tree, built_out, now, g, config, stats, sah);
            }
            if (ran == UpdatePolicy::Rebuild) {
                stats.subtrees_rebuilt = 0, stats.top_boxes = 0;
                rebuild();
            } else {
                // the reference follows the best a restructured tree reached: the geometry's own
                // shape may have made a good tree cheaper than the first build
                if (config.policy == UpdatePolicy::Adaptive && !tree.empty()) {
                    if (ran == UpdatePolicy::Partial && sah < goal)
                        ref = {sah, now.area[0], primitives >= 0 ? primitives : primitives_surface_area(tree)};
                    built_out[0] = float(ref.cost);
                }
                stats.sah_cost = sah, stats.policy = ran;
            }
        }
    }
    built_out.resize(tree.nodes.size() + 2);         // the reference's area after the nodes' costs
    built_out[tree.nodes.size()] = float(ref.area);  // and the primitives' surface area
    built_out[tree.nodes.size() + 1] = float(ref.primitives);
    stats.ms = std::chrono::duration<double, std::milli>(Clock::now() - start).count();
    if (config.measure_fresh) {  // not part of the update's time
        const Bvh fresh = stats.policy == UpdatePolicy::Rebuild ? Bvh{} : build_bvh(g, whole);
        stats.fresh_sah_cost = stats.policy == UpdatePolicy::Rebuild ? stats.sah_cost : sah_cost(fresh);
    }
    if (stats_out) *stats_out = stats;
    return tree;
}

std::vector<std::string_view> update_policy_names() { return {std::begin(kNames), std::end(kNames)}; }

UpdatePolicy parse_update_policy(std::string_view name) {
    for (std::size_t i = 0; i < std::size(kNames); ++i)
        if (kNames[i] == name) return static_cast<UpdatePolicy>(i);
    throw std::invalid_argument("unknown update policy '" + std::string(name) +
                                "'; expected one of: rebuild, refit, partial, adaptive");
}

std::string to_string(UpdatePolicy policy) { return std::string(kNames[static_cast<int>(policy)]); }

void validate(const UpdateConfig& config) {
    if (!(config.subtree_growth >= 1.0f) || !std::isfinite(config.subtree_growth))
        throw std::invalid_argument("subtree_growth must be a finite number of at least 1");
    if (!(config.tree_growth >= 1.0f) || !std::isfinite(config.tree_growth))
        throw std::invalid_argument("tree_growth must be a finite number of at least 1");
    if (!(config.target_growth >= 1.0f) || !std::isfinite(config.target_growth))
        throw std::invalid_argument("target_growth must be a finite number of at least 1");
    if (!(config.top_growth >= 1.0f) || !std::isfinite(config.top_growth))
        throw std::invalid_argument("top_growth must be a finite number of at least 1");
    if (!(config.restructure_share > 0.0f && config.restructure_share <= 1.0f))
        throw std::invalid_argument("restructure_share must be a number in (0, 1]");
    if (static_cast<unsigned>(config.policy) >= std::size(kNames)) throw std::invalid_argument("unknown update policy");
}

}  // namespace bvhlab
