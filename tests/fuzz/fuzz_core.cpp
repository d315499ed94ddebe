// fuzz_core.cpp — libFuzzer target over the core: build (every method, the SBVH with its settings
// among them, axis, leaf size, 1 or 2 threads), intersect (three traversals against a brute force
// over the same primitive tests), refit and boxes by depth, from raw bytes (fuzz_input.h). Bad
// input must give std::invalid_argument; anything else that goes wrong — an invariant, a
// disagreement, another exception, a sanitizer report — is a crash the fuzzer keeps. `make fuzz`
// runs it; `make test` replays the corpus in tests/fuzz/corpus under ASan, UBSan and
// float-cast-overflow.
#include <cstdio>
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <stdexcept>
#include <vector>

#include "bvhlab/bvh.h"
#include "bvhlab/cancel.h"
#include "bvhlab/coordinate_range.h"
#include "bvhlab/depth_order.h"
#include "bvhlab/stats.h"
#include "bvhlab/traverse.h"
#include "bvhlab/wide_bvh.h"
#include "../cpp/traverse_oracles.h"
#include "fuzz_input.h"

namespace bvhlab::fuzz {
namespace {

void require(bool ok, const char* what, long detail = -1) {
    if (ok) return;
    std::fprintf(stderr, "fuzz_core: %s (%ld)\n", what, detail);
    std::abort();
}

/// Double-precision 3-vectors: triangle points (check_clipped_leaves) and the grazing judgement (grazes).
struct D3 {
    double x, y, z;
    D3 operator-(const D3& b) const { return {x - b.x, y - b.y, z - b.z}; }
    D3 operator+(const D3& b) const { return {x + b.x, y + b.y, z + b.z}; }
    D3 operator*(double s) const { return {x * s, y * s, z * s}; }
    double dot(const D3& b) const { return x * b.x + y * b.y + z * b.z; }
    D3 cross(const D3& b) const { return {y * b.z - z * b.y, z * b.x - x * b.z, x * b.y - y * b.x}; }
    double norm() const { return std::sqrt(dot(*this)); }
    double largest() const { return std::max({std::fabs(x), std::fabs(y), std::fabs(z)}); }
};

/// Points of triangle `i` (its vertices, edges and inside, barycentrics in quarters) in double,
/// each kept inside the triangle's box (a flat triangle's points stay on its plane).
std::vector<D3> triangle_points(const GeometryView& g, std::size_t i) {
    const Vec3 v[3] = {g.vertex(i, 0), g.vertex(i, 1), g.vertex(i, 2)};
    const Aabb box = prim_box(g, std::uint32_t(i));
    std::vector<D3> out;
    for (int a = 0; a <= 4; ++a)
        for (int b = 0; a + b <= 4; ++b) {
            const double u = a / 4.0, w = b / 4.0;
            double p[3];
            for (int k = 0; k < 3; ++k)
                p[k] = std::clamp(double(v[0][k]) * (1 - u - w) + double(v[1][k]) * u + double(v[2][k]) * w,
                                  double(box.lo[k]), double(box.hi[k]));
            out.push_back({p[0], p[1], p[2]});
        }
    return out;
}

/// An SBVH leaf holds parts of its primitives (Stich et al. 2009): its box meets each one's box and
/// lies within their boxes' union, and every point of a triangle lies in the box of some leaf that
/// holds it (the parts cover the triangle; a relative 1e-12 allows the points' rounding in double).
void check_clipped_leaves(const Bvh& bvh, const GeometryView& g,
                          const std::vector<std::vector<std::uint32_t>>& leaves_of) {
    for (std::uint32_t i = 0; i < bvh.node_count(); ++i) {
        const BvhNode& node = bvh.nodes[i];
        if (!is_leaf(node)) continue;
        const Aabb box = node_box(node);
        Aabb around;
        for (std::uint32_t k = node.index; k < node.index + leaf_count(node); ++k) {
            const Aabb prim = prim_box(g, bvh.refs[k]);
            require(!Aabb{max(box.lo, prim.lo), min(box.hi, prim.hi)}.empty(), "a leaf box misses its primitive", i);
            around.grow(prim);
        }
        require(around.contains(box), "a leaf box reaches past its primitives' boxes", i);
    }
    for (std::size_t t = 0; t < g.triangle_count; ++t) {
        const Aabb box = prim_box(g, std::uint32_t(t));
        const double slack = 1e-12 * std::max({std::fabs(box.lo.x), std::fabs(box.lo.y), std::fabs(box.lo.z),
                                               std::fabs(box.hi.x), std::fabs(box.hi.y), std::fabs(box.hi.z)});
        for (const D3& p : triangle_points(g, t)) {
            bool covered = false;
            for (std::uint32_t leaf : leaves_of[t]) {
                const BvhNode& n = bvh.nodes[leaf];
                covered |= p.x >= n.lo.x - slack && p.x <= n.hi.x + slack && p.y >= n.lo.y - slack &&
                           p.y <= n.hi.y + slack && p.z >= n.lo.z - slack && p.z <= n.hi.z + slack;
            }
            require(covered, "a point of a triangle outside every leaf that holds it", long(t));
        }
    }
}

/// Every primitive in exactly one leaf (an SBVH: in at least one, never twice in one leaf, within
/// its reference budget), boxes nested and around their primitives, depths and skip indices
/// consistent, children where the layout says (walked with its own stack).
void check_tree(const Bvh& bvh, const GeometryView& g, const BuildConfig& config) {
    const std::size_t n = g.primitive_count();
    const bool repeats = config.method == SplitMethod::Sbvh;
    const std::size_t slots = bvh.refs.size();
    require(repeats ? slots >= n && slots <= sbvh_reference_limit(n, config) : slots == n, "reference count",
            long(slots));
    require(bvh.prims.size() == slots && bvh.depths.size() == bvh.nodes.size(), "array sizes");
    if (n == 0) return require(bvh.nodes.empty(), "an empty scene has nodes");
    std::vector<int> seen(n, 0);
    std::vector<std::vector<std::uint32_t>> leaves_of(n);  // the leaves holding each primitive
    struct Item {
        std::uint32_t node, depth, end;
    };  // `end`: where the subtree must end
    std::vector<Item> stack{{0, 0, bvh.node_count()}};
    while (!stack.empty()) {
        const Item it = stack.back();
        stack.pop_back();
        require(it.node < bvh.node_count() && bvh.depths[it.node] == it.depth, "node depth", it.node);
        require(it.depth < gpu::MAX_TREE_HEIGHT, "deeper than MAX_TREE_HEIGHT", it.node);
        const BvhNode& node = bvh.nodes[it.node];
        require(skip_index(node, it.node) == it.end, "skip index", it.node);
        const Aabb box = node_box(node);
        if (is_leaf(node)) {
            require(leaf_count(node) >= 1 && it.node + 1 == it.end, "leaf", it.node);
            for (std::uint32_t k = node.index; k < node.index + leaf_count(node); ++k) {
                require(k < slots && bvh.prims[k].ref == bvh.refs[k], "leaf slot", k);
                const std::uint32_t ref = bvh.refs[k];
                const std::size_t slot = ref_index(ref) + (is_sphere_ref(ref) ? g.triangle_count : 0);
                require(slot < n && (++seen[slot] == 1 || repeats), "a primitive in two leaves", long(slot));
                require(leaves_of[slot].empty() || leaves_of[slot].back() != it.node, "a primitive twice in a leaf",
                        long(slot));
                leaves_of[slot].push_back(it.node);
                require(repeats || box.contains(prim_box(g, ref)), "a leaf box misses its primitive", it.node);
            }
            continue;
        }
        const std::uint32_t first = it.node + 1, second = node.index;
        require(first < second && second < it.end, "child order", it.node);
        require(box.contains(node_box(bvh.nodes[first])) && box.contains(node_box(bvh.nodes[second])),
                "a child box outside its parent", it.node);
        stack.push_back({second, it.depth + 1, it.end});
        stack.push_back({first, it.depth + 1, second});
    }
    for (std::size_t k = 0; k < n; ++k) require(seen[k] >= 1, "a primitive in no leaf", long(k));
    if (repeats) check_clipped_leaves(bvh, g, leaves_of);
    const BvhStats s = compute_stats(bvh);
    require(s.nodes == 2 * s.leaves - 1 && s.primitives == n && s.references == slots, "stats");
}

/// The closest hit over every primitive with the same tests and tie rule as the traversals (the
/// tests' oracle on the ray as the queries scale it, its hit finished and scaled back).
Hit brute_force(const Bvh& bvh, Ray ray) {
    const float t_scale = scale_ray(ray);
    Hit hit = test::brute_force(bvh, ray);
    finish_hit(bvh, ray, hit);
    hit.t *= t_scale;
    return hit;
}

struct Hits {
    std::vector<float> t, u, v;
    std::vector<std::int32_t> prim;
    std::vector<std::uint8_t> kind;
    explicit Hits(std::size_t n) : t(n), u(n), v(n), prim(n), kind(n) {}
    HitBatch batch() { return {t.data(), prim.data(), kind.data(), u.data(), v.data(), nullptr}; }
};

bool strict() {
    static const bool value = [] {
        const char* v = std::getenv("BVHLAB_FUZZ_STRICT");
        return v && *v == '1';
    }();
    return value;
}

bool within_ulps(float a, float b, float ulps) {
    return a == b ||
           std::fabs(a - b) <= ulps * std::numeric_limits<float>::epsilon() * std::fmax(std::fabs(a), std::fabs(b));
}

double segment_distance(const D3& p, const D3& a, const D3& b) {
    const D3 e = b - a;
    const double len2 = e.dot(e), u = len2 > 0 ? std::clamp((p - a).dot(e) / len2, 0.0, 1.0) : 0.0;
    return (p - (a + e * u)).norm();
}

/// True when, in double precision, the ray passes within a relative 1e-5 of primitive `k`'s
/// boundary (an edge, the silhouette), runs (nearly) in its plane, or starts (nearly) on it,
/// relative to the largest coordinate involved: there float32 rounding may decide either way
/// between a hit and a miss.
bool grazes(const Bvh& bvh, std::uint32_t k, const Ray& r) {
    const PackedPrim& p = bvh.prims[k];
    const D3 o{r.origin.x, r.origin.y, r.origin.z}, d{r.dir.x, r.dir.y, r.dir.z}, v0{p.v0.x, p.v0.y, p.v0.z};
    if (is_sphere_ref(p.ref)) {
        // Haines et al.'s sphere test (geometry.glsl sphere_roots) resolves the ray's distance from
        // the centre to a few ulps of |origin - centre| (the old b² - a·c only to sqrt(eps) of it:
        // corpus/found_sphere_halo, test_intersect.py); a relative 1e-5 is tolerated, as for triangles.
        const double radius = p.v1.x, near = 1e-5 * std::max(o.largest(), v0.largest() + radius);
        const D3 closest = o + d * ((v0 - o).dot(d) / d.dot(d));
        return std::fabs((v0 - closest).norm() - radius) <= near || std::fabs((o - v0).norm() - radius) <= near;
    }
    const D3 v1{p.v1.x, p.v1.y, p.v1.z}, v2{p.v2.x, p.v2.y, p.v2.z};
    const double near = 1e-5 * std::max({o.largest(), v0.largest(), v1.largest(), v2.largest()});
    const D3 n = (v1 - v0).cross(v2 - v0);
    const double denom = n.dot(d);
    if (std::fabs(denom) <= 1e-6 * n.norm() * d.norm()) return true;  // degenerate, or along its plane
    const double t = n.dot(v0 - o) / denom;
    const D3 hit = o + d * t;
    return std::fabs(t) * d.norm() <= near || segment_distance(hit, v0, v1) <= near ||
           segment_distance(hit, v1, v2) <= near || segment_distance(hit, v2, v0) <= near;
}

/// The closest hit of ray i through the tree is the brute force's (the same primitive tests over
/// every primitive), exactly, except where float32 rounding may decide (set BVHLAB_FUZZ_STRICT=1
/// to demand exactness there too): a grazing ray (grazes()) may be a hit for the primitive test
/// and a miss for its box, or the reverse. The conservative box test (Ize 2013, gpu::BOX_FAR_SCALE)
/// and the watertight triangle test made the cases found so far exact (strict passes on
/// corpus/found_tie_at_box_entry, found_grazing_underflow, found_grazing_sliver); found_start_on_plane
/// (a ray starting on a triangle's plane, t within rounding of 0) still needs the tolerance.
void check_hit(const Bvh& bvh, const FuzzCase& c, std::size_t i, const Hits& hits) {
    const float* o = &c.origins[3 * i];
    const float* d = &c.directions[3 * i];
    const Ray ray{{o[0], o[1], o[2]}, {d[0], d[1], d[2]}, 0.0f, kInfinity};
    const Hit want = brute_force(bvh, ray);
    const std::int32_t want_prim = want.ref == kNoHit ? -1 : std::int32_t(ref_index(want.ref));
    const std::uint8_t want_kind = want.ref != kNoHit && is_sphere_ref(want.ref) ? 1 : 0;
    if (hits.prim[i] == want_prim && hits.kind[i] == want_kind && hits.t[i] == want.t &&
        (want.ref == kNoHit || (hits.u[i] == want.u && hits.v[i] == want.v)))
        return;
    require(!strict(), "the traversal's hit differs from the brute force's", long(i));
    require(want.ref != kNoHit, "the traversal hits where the brute force misses", long(i));
    if (hits.prim[i] < 0 || !within_ulps(hits.t[i], want.t, 4)) {  // the nearest hit was culled
        require(grazes(bvh, want.slot, ray), "the traversal missed a clear hit", long(i));
        return;
    }
    if (hits.prim[i] == want_prim && hits.kind[i] == want_kind) return;  // t, u, v off by rounding
    // another primitive at the same distance: it must really be hit there
    const std::uint32_t ref = std::uint32_t(hits.prim[i]) | (hits.kind[i] ? gpu::REF_SPHERE_BIT : 0u);
    Ray scaled = ray;
    const float t_scale = scale_ray(scaled);
    Hit alone;
    for (std::uint32_t k = 0; k < bvh.prims.size(); ++k)
        if (bvh.prims[k].ref == ref && hit_prim(bvh.prims[k], RayQuery(scaled), alone)) alone.t *= t_scale;
    require(alone.ref == ref && within_ulps(alone.t, hits.t[i], 4), "the traversal's primitive is not hit there",
            long(i));
}

/// The three traversals find the brute force's closest hit (check_hit); rays that check_rays
/// refuses are refused by intersect_batch, with std::invalid_argument.
void check_rays(const Bvh& bvh, const FuzzCase& c) {
    const std::size_t n = c.origins.size() / 3;
    const RayBatch rays{c.origins.data(), c.directions.data(), n, 0.0f, kInfinity};
    bool valid = true;
    try {
        bvhlab::check_rays(rays);
    } catch (const std::invalid_argument&) { valid = false; }
    const WideBvh wide = make_wide(bvh);
    for (Traversal mode : {Traversal::Stack, Traversal::Stackless, Traversal::Wide}) {
        Hits hits(n);
        try {
            intersect_batch(bvh, rays, hits.batch(), mode, c.threads, &wide);
            require(valid, "intersect_batch accepted a ray check_rays refuses");
        } catch (const std::invalid_argument&) {
            require(!valid, "intersect_batch refused rays check_rays accepts");
            continue;
        }
        for (std::size_t i = 0; i < n; ++i) check_hit(bvh, c, i, hits);
    }
}

/// Boxes by depth: one offset and count per depth range, sorted by depth, exactly the nodes there.
void check_depth_order(const Bvh& bvh, const FuzzCase& c) {
    const DepthOrder order = make_depth_order(bvh);
    const auto [first, last] = order.range(c.depth_min, c.depth_max);
    require(first <= last && last <= order.nodes.size(), "depth range");
    std::size_t expected = 0;
    for (std::uint8_t d : bvh.depths) expected += d >= c.depth_min && d <= c.depth_max;
    require(last - first == expected, "depth range count", long(expected));
    for (std::uint32_t k = first; k < last; ++k) {
        const std::uint8_t d = bvh.depths[order.nodes[k]];
        require(d >= c.depth_min && d <= c.depth_max && (k == first || d >= bvh.depths[order.nodes[k - 1]]),
                "depth order");
    }
}

/// Refit to the geometry moved by an offset: the same invariants hold, or the moved geometry is
/// refused with std::invalid_argument and the tree is unchanged.
void check_refit(Bvh& bvh, FuzzCase& c) {
    for (float& f : c.triangles) f += c.refit_offset;
    for (std::size_t i = 0; i < c.spheres.size(); i += 4)
        for (int k = 0; k < 3; ++k) c.spheres[i + k] += c.refit_offset;
    const auto before = bvh.nodes.size() ? bvh.nodes[0].lo.x : 0.0f;
    try {
        refit(bvh, c.view());
    } catch (const std::invalid_argument&) {
        require(!bvh.nodes.size() || bvh.nodes[0].lo.x == before, "a refused refit changed the tree");
        return;
    }
    check_tree(bvh, c.view(), c.config);
    check_rays(bvh, c);
}

void check_cancel(const FuzzCase& c, const Bvh& bvh) {
    BuildConfig cfg = c.config;
    cfg.progress = [](double) { return false; };
    bool cancelled = false;
    try {
        build_bvh(c.view(), cfg);
    } catch (const BuildCancelled&) { cancelled = true; }
    require(cancelled, "a progress callback returning false did not cancel the build");
    Cancellation stop([] { return true; });
    Hits hits(c.origins.size() / 3);
    const RayBatch rays{c.origins.data(), c.directions.data(), c.origins.size() / 3, 0.0f, kInfinity};
    try {
        intersect_batch(bvh, rays, hits.batch(), Traversal::Stack, c.threads, nullptr, &stop);
        require(false, "a cancelled intersect_batch returned normally");
    } catch (const Cancelled&) {
    } catch (const std::invalid_argument&) {  // refused rays are checked before the work starts
    }
}

}  // namespace
}  // namespace bvhlab::fuzz

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    using namespace bvhlab;
    fuzz::FuzzCase c = fuzz::read_case(data, size);
    Bvh bvh;
    try {
        bvh = build_bvh(c.view(), c.config);
    } catch (const std::invalid_argument&) {
        return 0;  // bad geometry: refused, as it should be
    }
    fuzz::check_tree(bvh, c.view(), c.config);
    fuzz::check_rays(bvh, c);
    fuzz::check_depth_order(bvh, c);
    fuzz::check_cancel(c, bvh);
    fuzz::check_refit(bvh, c);
    return 0;
}
