// wide_traverse.inl — the closest-hit and any-hit traversals of the 8-wide tree (wide_bvh.h), one
// walk with an any-hit mode (kAnyHit: ends at the first leaf that holds a hit), written once
// against two small vector types that the including file defines in its own namespace:
//   L8: eight floats — load(const float*), splat(float), lane(k), + - *, raise(acc, t)
//       (= t > acc ? t : acc), lower(acc, t) (= t < acc ? t : acc), le_bits(a, b) (bit i set
//       when a[i] <= b[i]), store(float*);
//   L4: four floats — load, splat, set(a, b, c, d), + - * /, raise, lower, comparisons giving
//       an M4 mask, M4 & M4, M4 | M4, bits(M4), sign_bits(L4) (bit i: lane i's sign bit),
//       store, and permute(v, lanes) = (v[lanes[0]], v[lanes[1]], v[lanes[2]], v[3]) for four
//       lane indices 0..3, the last 3;
// and push_children(node, t0, t1, mask, index, t), which writes the children a ray enters
// but the nearest to the stack's arrays, farthest first, and returns the nearest's slot
// (traverse_wide.cpp), and push_entered(node, mask, index), which writes the children in `mask`
// to index[0 .. popcount(mask)) in slot order (and may write up to eight).
// traverse_wide.cpp includes it for the portable path (SSE or plain C++), traverse_wide_avx2.cpp
// for AVX2. Both compute, lane by lane, exactly what hit_box (ray.h) and the watertight
// hit_triangle (shaders/tracer/geometry.glsl) compute, so every path returns the same hit as the
// binary traversals and the brute force. Only plain data and functions of the including file are
// used here (an inline function of another header compiled for AVX2 could be picked by the
// linker for code running without AVX2): make_query repeats make_ray's per-ray arithmetic.

namespace {

/// The ray as the kernel needs it: origin and inverse direction for the boxes; the watertight
/// test's axis order, the origin in that order and the shear for the triangles (make_query).
/// Four floats where three are used, so that each is one vector store.
struct Query {
    float o[4], inv[4];
    /// −1/d and −(1/d)·BOX_FAR_SCALE, the box test's factors (traverse_nodes), made here by two
    /// vector products rather than as six scalar products and negations at the start of the walk
    float neg_inv[4], neg_inv_far[4];
    float o_axes[4];  ///< o[kx], o[ky], o[kz]
    float shear[4];
    /// tmin in eight lanes: the first raise of every node's box test reads it as it is (a
    /// memory operand; a broadcast a node before)
    alignas(32) float tmin8[8];
    /// 16·kx, 16·ky, 16·kz (AxisOrder::at): where axis k's four lanes start in a PrimPacket
    /// vertex (v[i][k]), in bytes, so that each of a packet's nine loads is one addressing mode
    /// (base + offset + vertex), without a shift or an address computed first
    const std::ptrdiff_t* axis_at;
    int octant;  ///< bit a set where 1/dir[a] is negative: kPlanes' row, any_hit_walk's copy
    float tmin;
    const Ray* ray;  ///< for the spheres (hit_packet_sphere)
};

/// The watertight test's axis order (geometry.glsl make_ray) for one kz and sign of dir[kz]: kx
/// and ky the two axes after kz, swapped when dir[kz] < 0. As lane indices of the permutes that
/// put the origin and direction in that order, and as byte offsets in a PrimPacket vertex.
struct AxisOrder {
    alignas(16) std::int32_t origin[4];  ///< kx, ky, kz, 3
    alignas(16) std::int32_t dir[4];     ///< kx, ky, 3, 3
    alignas(16) std::int32_t inv[4];     ///< kz, kz, kz, 3
    std::ptrdiff_t at[3];                ///< 16·kx, 16·ky, 16·kz: axis k's lanes in a PrimPacket vertex
};

constexpr AxisOrder axis_order(int kz, bool flip) {
    const int next = kz == 2 ? 0 : kz + 1, last = 3 - kz - next;
    const int kx = flip ? last : next, ky = flip ? next : last;
    constexpr std::ptrdiff_t bytes = sizeof(PrimPacket::v[0][0]);
    return {{kx, ky, kz, 3}, {kx, ky, 3, 3}, {kz, kz, kz, 3}, {bytes * kx, bytes * ky, bytes * kz}};
}

/// AxisOrder by 2·kz + (dir[kz] < 0): looked up rather than worked out by integer arithmetic and
/// lane inserts for every ray (Sponza instructions a ray: design.md, traversal's fourth pass).
constexpr AxisOrder kAxisOrders[6] = {axis_order(0, false), axis_order(0, true),  axis_order(1, false),
                                      axis_order(1, true),  axis_order(2, false), axis_order(2, true)};

/// The per-ray constants as geometry.glsl make_ray computes them, by the same float operations
/// (so the same values; every test comparing the wide traversal with the brute force, which goes
/// through make_ray, checks that bit for bit): 1/d is IEEE's, ±inf for ±0 as inverse_or_infinity;
/// kz the axis of the largest |component| (ties to the later axis), kx and ky the next two,
/// swapped when dir[kz] < 0; the shear as products with 1/dir[kz]. Computed here from the ray's
/// fields rather than copied out of a TraceRay, which cost cheap rays a third of their time.
/// Without branches: the axes come from comparison flags and the components in axis order from
/// a permute. Selects by the axis compiled to branches, which random directions mispredicted
/// (1.4 a ray, a tenth of a random ray's time in room1m).
Query make_query(const Ray& ray) {
    const Vec3 o = ray.origin, d = ray.dir;
    const float x = std::fabs(d.x), y = std::fabs(d.y), z = std::fabs(d.z);
    const int x_largest = int(x > y) & int(x > z), y_largest = (1 - x_largest) & int(y > z);
    const int kz = 2 - 2 * x_largest - y_largest;
    const L4 dir = L4::set(d.x, d.y, d.z, 1.0f), origin = L4::set(o.x, o.y, o.z, 0.0f);
    const int flip = (bits(L4::splat(0.0f) > dir) >> kz) & 1;  // dir[kz] < 0
    const AxisOrder& axes = kAxisOrders[2 * kz + flip];
    const L4 inv = L4::splat(1.0f) / dir;
    Query q;
    origin.store(q.o), inv.store(q.inv);
    (inv * L4::splat(-1.0f)).store(q.neg_inv), (inv * L4::splat(-gpu::BOX_FAR_SCALE)).store(q.neg_inv_far);
    // (dir[kx], dir[ky], 1, 1) times 1 / dir[kz]: the shear, and 1 / dir[kz] itself in lane 2
    // (1 · x is x, except a denormal x under denormals-are-zero: 0, which is what the one use of
    // shear[2], a product, reads x as in that mode anyway)
    permute(origin, axes.origin).store(q.o_axes);
    (permute(dir, axes.dir) * permute(inv, axes.inv)).store(q.shear);
    L8::splat(ray.tmin).store(q.tmin8);
    q.axis_at = axes.at;
    q.octant = sign_bits(inv) & 7;
    q.tmin = ray.tmin, q.ray = &ray;
    return q;
}

struct Entry {
    std::uint32_t index;  ///< a WideNode child word: a node's line, or kLeafChild | a leaf's first packet's
    float t;              ///< where the ray enters the box
};

/// Pushed entries (wide_kernel.h, plain data: the TLAS walk keeps one between calls).
using Stack = WideStack;

/// closer_hit (ray.h), repeated here for the reason given at the top of this file.
bool closer(float t, std::uint32_t ref, const Hit& hit) {
    return t < hit.t || (t == hit.t && hit.ref != kNoHit && ref < hit.ref);
}

/// The watertight test (geometry.glsl hit_triangle) on four triangles at once, its operations in
/// its order lane by lane; the lanes that pass become hits in lane order under the closest-hit rule.
/// kAnyHit: the first lane that passes is the hit (its t and ref only; the query wants no more).
template <bool kAnyHit>
void test_triangles(const PrimPacket& k, const Query& q, Hit& hit) {
    const std::ptrdiff_t kx = q.axis_at[0], ky = q.axis_at[1], kz = q.axis_at[2];
    const L4 ox = L4::splat(q.o_axes[0]), oy = L4::splat(q.o_axes[1]), oz = L4::splat(q.o_axes[2]);
    const L4 sx = L4::splat(q.shear[0]), sy = L4::splat(q.shear[1]);
    // v[i][axis] is v[i][0] + 16·axis bytes
    const auto vertex = [&k](int i) { return reinterpret_cast<const char*>(k.v[i][0]); };
    const auto at = [](const char* p, std::ptrdiff_t offset) { return reinterpret_cast<const float*>(p + offset); };
    const char *a = vertex(0), *b = vertex(1), *c = vertex(2);
    const L4 az = L4::load(at(a, kz)) - oz, bz = L4::load(at(b, kz)) - oz, cz = L4::load(at(c, kz)) - oz;
    const L4 ax = (L4::load(at(a, kx)) - ox) - sx * az, ay = (L4::load(at(a, ky)) - oy) - sy * az;
    const L4 bx = (L4::load(at(b, kx)) - ox) - sx * bz, by = (L4::load(at(b, ky)) - oy) - sy * bz;
    const L4 cx = (L4::load(at(c, kx)) - ox) - sx * cz, cy = (L4::load(at(c, ky)) - oy) - sy * cz;
    const L4 u = cx * by - cy * bx, v = ax * cy - ay * cx, w = bx * ay - by * ax;
    const L4 zero = L4::splat(0.0f);
    // "not (some negative and some positive)"; a NaN lane has a NaN t and fails below
    const M4 one_sign = (lower(lower(u, v), w) >= zero) | (raise(raise(u, v), w) <= zero);
    const L4 det = (u + v) + w;
    const M4 inside = one_sign & (det != zero);
    if (!bits(inside)) return;  // most packets a ray reaches: no division to wait for
    const L4 t = (((u * az + v * bz) + w * cz) / det) * L4::splat(q.shear[2]);
    if constexpr (kAnyHit) {
        // no hit yet (the walk ends at the first): closer() is t < hit.t, the ray's tmax
        const int lanes = bits(inside & (t > L4::load(q.tmin8)) & (L4::splat(hit.t) > t));
        if (!lanes) return;
        alignas(16) float ts[4];
        t.store(ts);
        const int l = __builtin_ctz(unsigned(lanes));
        hit.t = ts[l], hit.ref = k.ref[l];
        return;
    }
    int lanes = bits(inside & (t > L4::load(q.tmin8)) & (t <= L4::splat(hit.t)));
    if (!lanes) return;
    alignas(16) float ts[4], vs[4], ws[4], dets[4];
    t.store(ts), v.store(vs), w.store(ws), det.store(dets);
    for (; lanes; lanes &= lanes - 1) {
        const int l = __builtin_ctz(unsigned(lanes));
        if (!closer(ts[l], k.ref[l], hit)) continue;
        hit.t = ts[l], hit.ref = k.ref[l], hit.u = vs[l] / dets[l], hit.v = ws[l] / dets[l];
        hit.slot = k.slot[l];
    }
}

/// The start of line `i` of the wide tree.
const unsigned char* line_at(const WideView& wide, std::uint32_t i) {
    return wide.lines + std::size_t(i) * sizeof(WideLine);
}

/// The packets of a leaf, from line `first` on, up to the one without `more`; kAnyHit: up to the
/// first packet with a hit.
template <bool kAnyHit>
void test_leaf(const WideView& wide, std::uint32_t first, const Query& q, Hit& hit) {
    for (const unsigned char* at = line_at(wide, first);; at += sizeof(PrimPacket)) {
        const PrimPacket& k = *reinterpret_cast<const PrimPacket*>(at);
        // [[likely]]: the sphere calls out of line; laid out as the rare case, the leaf's entry
        // spills fewer of the node loop's registers (uniform1m random rays: 3,549 → 3,486
        // instructions a ray, Sponza 1,077 → 1,067)
        if (!(k.ref[0] & gpu::REF_SPHERE_BIT)) [[likely]] {
            test_triangles<kAnyHit>(k, q, hit);
        } else {
            for (int l = 0; l < 4 && k.ref[l] != kNoHit; ++l)
                if (hit_packet_sphere(k, l, *q.ray, hit)) hit.slot = k.slot[l];
        }
        if (kAnyHit && hit.ref != kNoHit) return;
        if (!k.more) return;
    }
}

/// Starts the loads of an entry pushed for later: the four lines from its line on, a node's, or
/// a leaf's first packet and the line after it (the next packet's, or what follows the leaf in
/// preorder). In a tree larger than the caches a popped entry is a miss, and its lines are on
/// their way by then (random rays, against Embree measured alongside: uniform1m 0.60 → 0.71,
/// Sponza 0.96 → 1.01; room1m unchanged). Nodes and packets being lines of one block, no
/// branch on the kind.
void prefetch(const WideView& wide, std::uint32_t child) {
    const unsigned char* p = line_at(wide, child & ~kLeafChild);
    __builtin_prefetch(p), __builtin_prefetch(p + 64), __builtin_prefetch(p + 128), __builtin_prefetch(p + 192);
}

/// The node at `line`.
const WideNode& node_at(const WideView& wide, std::uint32_t line) {
    return *reinterpret_cast<const WideNode*>(line_at(wide, line));
}

/// Float offsets in a WideNode of the near plane arrays of x, y, z (lo_x = 0, hi_x = 8, ...), then
/// of the far ones, by the ray's octant (bit a set where 1/dir[a] is negative). Pointer-sized and
/// both sides kept, so that a node's six loads take them as they are (as ints, near ^ 8 and a
/// sign extension were redone at every node; Sponza instructions a ray: random 959 → 952, primary
/// 1,860 → 1,824), and looked up rather than worked out for every ray (random 918 → 906, primary
/// 1,741 → 1,729).
struct PlaneTable {
    std::ptrdiff_t at[8][6];
    constexpr PlaneTable() : at{} {
        for (int octant = 0; octant < 8; ++octant)
            for (int a = 0; a < 3; ++a)
                at[octant][a] = 16 * a + 8 * (octant >> a & 1), at[octant][3 + a] = at[octant][a] ^ 8;
    }
    constexpr const std::ptrdiff_t* operator[](int octant) const { return at[octant]; }
};
constexpr PlaneTable kPlanes;

/// kAnyOctant as a walk's octant: the plane offsets are read from kPlanes by the ray's octant.
constexpr int kAnyOctant = -1;

/// The offset of plane `i` (0-2 near x, y, z; 3-5 far) for a walk of `kOctant`: a constant in a
/// walk compiled for one octant (tinybvh 1.9 BVH8_CPU's IntersectOctant), so that each of a
/// node's six loads takes it as an immediate, else from `plane` (kPlanes[octant]).
template <int kOctant>
[[gnu::always_inline]] inline std::ptrdiff_t plane_at(const std::ptrdiff_t* plane, int i) {
    if constexpr (kOctant == kAnyOctant) return plane[i];
    else return kPlanes.at[kOctant][i];
}

/// One step of the traversal: tests the eight child boxes of `node` (as hit_box does) and pushes
/// the children the ray enters before hit.t, nearest last, the nearest going to `cur` rather than
/// the stack. Returns false when the ray enters none.
/// `neg_inv` is the negated inverse direction (traverse_nodes says why), `neg_inv_far` that times
/// gpu::BOX_FAR_SCALE, `tmin8` the ray's tmin in eight lanes in memory, which the box test's first
/// raise reads as it is (a broadcast a node fewer), and `far_limit` the closest hit so far times
/// the scale, broadcast from a register at every node (read from memory as tmin is, the far limit
/// was written there after every leaf and read back at the next node: primary rays slower in time
/// though fewer instructions, design.md's fourth pass): the far end widened
/// as hit_box widens it (Ize 2013), with the scale folded into per-ray constants rather than a
/// multiply on every node's dependency chain. One rounding more than hit_box's product, which the
/// scale covers with room to spare (16 ε against 7 ε).
/// "Nearest" is by the middle of the span the ray spends in each box (entry + exit), not by the
/// entry alone: a ray starting inside several boxes enters them all at tmin, and the entry then
/// says nothing of where their contents lie (the cost-optimal collapse puts large leaves beside
/// deep subtrees, which entry order visited first). Only the order changes: the entry is still
/// what the stack compares with the closest hit, so the hit is the same.
/// The order comes from push_children, which sorts the entered slots by a key of their middle
/// and pushes them, without branches where it can (AVX2: one comparison for two, else a sorting network, and two permutes):
/// which children a ray enters, and in what order, is data that no branch predictor learns.
/// Inlined into each walk (closest and any hit), as it was into the one walk before the any-hit
/// mode came (shared by two, the compiler called it per node).
/// kAnyHit: no order to keep, as any hit ends the walk (tinybvh's IsOccluded pushes unordered
/// too): the highest entered slot goes to `cur`, the others are pushed in slot order, without the
/// sort (shadow rays against the sorted push, two interleaved runs: uniform1m +19% and +42%,
/// Sponza +9% and +15%), by push_entered (AVX2: one permute by a table of the mask, as tinybvh's
/// IsOccluded does). No entry distance is pushed: any entered box passes the pop's test, tmax
/// being fixed, so the any-hit walk pops without one.
/// kPrefetch false (the TLAS's walk, next_tlas_leaf): no prefetches, as a TLAS is small enough to
/// stay in the caches and its leaf words are no lines.
template <bool kAnyHit, int kOctant, bool kPrefetch = true>
[[gnu::always_inline]] inline bool enter_children(const WideView& wide, const WideNode& node, const L8 origin[3],
                                                  const L8 neg_inv[3], const L8 neg_inv_far[3],
                                                  const std::ptrdiff_t* plane, const float* tmin8, float far_limit,
                                                  Stack& stack, std::uint32_t& sp, Entry& cur) {
    const float* f = node.lo_x;
    // The children's indices are the node's fourth cache line, read only once the box tests say
    // which: started now, its load overlaps the bounds' instead of following them (a second miss
    // in a row where the node was not in the caches; uniform1m random rays +4-5% best of
    // interleaved runs, Sponza and room1m unchanged).
    if constexpr (kPrefetch) {
        __builtin_prefetch(node.child);
        // And the six lines after the node: in preorder its first leaves' packets, or its first
        // inner child (uniform1m +4.2% random, +4.9% primary, Sponza +4% random, best of
        // interleaved runs; room1m, whose tree the caches hold better, -2.5%).
        const char* after = reinterpret_cast<const char*>(&node + 1);
        for (int line = 0; line < 6; ++line) __builtin_prefetch(after + 64 * line);
    }
    // the same order of raises and lowers as hit_box: NaN from 0·inf on a face is ignored
    L8 t0 = L8::load(tmin8), t1 = L8::splat(far_limit);
    for (int a = 0; a < 3; ++a) t0 = raise(t0, (origin[a] - L8::load(f + plane_at<kOctant>(plane, a))) * neg_inv[a]);
    for (int a = 0; a < 3; ++a)
        t1 = lower(t1, (origin[a] - L8::load(f + plane_at<kOctant>(plane, 3 + a))) * neg_inv_far[a]);
    const int mask = le_bits(t0, t1);
    if (!mask) return false;
    if (!(mask & (mask - 1))) {
        const int k = __builtin_ctz(unsigned(mask));
        cur = {node.child[k], t0.lane(k)};
        return true;
    }
    if constexpr (kAnyHit) {
        const auto h = std::uint32_t(__builtin_popcount(unsigned(mask)));
        push_entered(node, mask, stack.index + sp);
        sp += h - 1;
        cur = {stack.index[sp], tmin8[0]};
        prefetch(wide, stack.index[sp - 1]);
        return true;
    }
    const int k = push_children(node, t0, t1, mask, stack.index + sp, stack.t + sp);
    const auto h = std::uint32_t(__builtin_popcount(unsigned(mask)));
    cur = {node.child[k], t0.lane(k)};
    if constexpr (!kPrefetch) {
        sp += h - 1;
        return true;
    }
    // the pushed entries (sp .. sp + h - 2), nearest first: one where two were entered (over
    // half the pushes of random rays; push_children's AVX2 path has branched on it already, so
    // this branch follows that one), else three without a loop (where fewer were pushed, the
    // nearest is prefetched again): a loop's exit is as unpredictable as h. (Two entered had
    // the one entry prefetched three times: Sponza instructions a ray, random 952 → 918,
    // primary 1,824 → 1,741.)
    if (h == 2) {
        prefetch(wide, stack.index[sp]);
    } else {
        const std::uint32_t third = sp + h - 3 - std::uint32_t(h >= 4);
        prefetch(wide, stack.index[sp + h - 2]), prefetch(wide, stack.index[sp + h - 3]);
        prefetch(wide, stack.index[third]);
        if (h > 4) [[unlikely]]
            for (std::uint32_t j = sp; j + 4 < sp + h; ++j) prefetch(wide, stack.index[j]);
    }
    sp += h - 1;
    return true;
}

/// Nearest child first, from the root. `far_limit`, the closest hit so far times the box scale,
/// lives in a register and is renewed after a leaf, the one place the hit changes. kAnyHit: the
/// walk ends at the first leaf with a hit (the boxes' far limit stays the ray's tmax).
/// kRecord: each node's entered children and each leaf's effect on the hit go to `record` (the
/// inspector's record, wide_kernel.h WideRecorder); without it the calls compile away and the walk
/// is the plain one.
template <bool kAnyHit, int kOctant, bool kRecord = false>
std::uint32_t traverse_nodes(const WideView& wide, const Query& q, Hit& hit, WideRecorder* record = nullptr) {
    const L8 origin[3] = {L8::splat(q.o[0]), L8::splat(q.o[1]), L8::splat(q.o[2])};
    // The planes' distances as (origin - plane) · (-1/d), which are hit_box's (plane - origin) ·
    // 1/d (negating is exact, and a zero's sign, the only difference, changes no comparison), so
    // that the node's bounds can be the subtraction's memory operand: one load fewer per axis
    // and side (uniform1m random rays: 6 instructions fewer a node).
    // −(1/d · s) is (1/d)·(−s) bit for bit: a rounding is symmetric about zero
    const L8 neg_inv[3] = {L8::splat(q.neg_inv[0]), L8::splat(q.neg_inv[1]), L8::splat(q.neg_inv[2])};
    const L8 neg_inv_far[3] = {L8::splat(q.neg_inv_far[0]), L8::splat(q.neg_inv_far[1]), L8::splat(q.neg_inv_far[2])};
    const float s = gpu::BOX_FAR_SCALE;
    const std::ptrdiff_t* plane = kPlanes[q.octant];
    Stack stack;
    std::uint32_t sp = 0, visited = 0;
    Entry cur{0, q.tmin};
    float far_limit = hit.t * s;
    for (;;) {
        if (cur.index & kLeafChild) {
            if constexpr (kRecord) {
                const Hit before = hit;
                test_leaf<kAnyHit>(wide, cur.index & ~kLeafChild, q, hit);
                record->leaf(cur.index & ~kLeafChild, before, hit);
            } else {
                test_leaf<kAnyHit>(wide, cur.index & ~kLeafChild, q, hit);
            }
            if constexpr (kAnyHit) {  // no hit: tmax, and so the far limit, stays what it was
                if (hit.ref != kNoHit) return visited;
            } else {
                far_limit = hit.t * s;
            }
        } else {
            ++visited;
            [[maybe_unused]] const std::uint32_t line = cur.index, pushed = sp;
            const bool entered =
                enter_children<kAnyHit, kOctant>(wide, node_at(wide, cur.index), origin, neg_inv, neg_inv_far, plane,
                                                 q.tmin8, far_limit, stack, sp, cur);
            if constexpr (kRecord) record->node(line, entered ? cur.index : kNoHit, stack.index + pushed, sp - pushed);
            if (entered) continue;
        }
        if constexpr (kAnyHit) {  // every entry passes may_hold_closer: hit.t is still tmax
            if (sp == 0) return visited;
            --sp;
            cur = {stack.index[sp], q.tmin};
            continue;
        }
        do {  // pop, skipping entries farther than the closest hit so far (ray.h may_hold_closer)
            if (sp == 0) return visited;
            --sp;
        } while (!(stack.t[sp] <= far_limit));
        cur = {stack.index[sp], stack.t[sp]};
    }
}

/// The any-hit walk for the ray's octant: one copy per octant, each with its plane offsets as
/// constants (tinybvh 1.9's IsOccludedOctant). The closest-hit walk is one copy for every octant:
/// eight of it (2.5 KiB each) made random rays slower, though fewer instructions (callgrind
/// instructions a ray and Mrays/s ÷ the best peer, CPU time of one pinned core, two interleaved
/// runs: Sponza random 884 → 866, 1.11-1.13 → 1.06-1.07; primary 1,699 → 1,628, 0.93 → 0.94-0.96;
/// room1m random 1.03-1.07 → 0.98-1.00).
[[maybe_unused]] std::uint32_t any_hit_walk(const WideView& wide, const Query& q, Hit& hit) {
    using Walk = std::uint32_t (*)(const WideView&, const Query&, Hit&, WideRecorder*);
    static constexpr Walk kWalks[8] = {traverse_nodes<true, 0>, traverse_nodes<true, 1>, traverse_nodes<true, 2>,
                                       traverse_nodes<true, 3>, traverse_nodes<true, 4>, traverse_nodes<true, 5>,
                                       traverse_nodes<true, 6>, traverse_nodes<true, 7>};
    return kWalks[q.octant](wide, q, hit, nullptr);
}

}  // namespace

#ifndef BVHLAB_RECORDED_WIDE_WALK
Hit intersect_wide_kernel(const WideView& wide, const Ray& ray, std::uint32_t* nodes_visited) {
    Hit hit{ray.tmax, kNoHit, 0.0f, 0.0f, kNoHit};
    const Query q = make_query(ray);
    const std::uint32_t visited = wide.lines ? traverse_nodes<false, kAnyOctant>(wide, q, hit) : 0;
    if (nodes_visited) *nodes_visited = visited;
    return hit;
}

bool occluded_wide_kernel(const WideView& wide, const Ray& ray) {
    Hit hit{ray.tmax, kNoHit, 0.0f, 0.0f, kNoHit};
    if (wide.lines) any_hit_walk(wide, make_query(ray), hit);
    return hit.ref != kNoHit;
}

/// make_query's box factors alone (the same operations, so the same bits): a TLAS has no triangles.
void start_tlas_walk(const Ray& ray, TlasWalk& walk) {
    const L4 inv = L4::splat(1.0f) / L4::set(ray.dir.x, ray.dir.y, ray.dir.z, 1.0f);
    L4::set(ray.origin.x, ray.origin.y, ray.origin.z, 0.0f).store(walk.o);
    (inv * L4::splat(-1.0f)).store(walk.neg_inv), (inv * L4::splat(-gpu::BOX_FAR_SCALE)).store(walk.neg_inv_far);
    L8::splat(ray.tmin).store(walk.tmin8);
    walk.octant = sign_bits(inv) & 7;
    walk.sp = 0, walk.cur = 0, walk.cur_t = ray.tmin, walk.visited = 0, walk.resumed = false;
}

/// The TLAS's wide walk (wide_kernel.h next_tlas_leaf): traverse_nodes' steps on a tree whose
/// nodes are WideNodes with the count of their children in unused[0] (make_wide_tlas), up to a
/// leaf, which is handed to the caller (its child word is kLeafChild | the binary leaf's index);
/// resumed by popping, with the closest hit the caller has found since.
std::uint32_t next_tlas_leaf(const WideView& wide, TlasWalk& w, float hit_t, WideRecorder* record) {
    const L8 origin[3] = {L8::splat(w.o[0]), L8::splat(w.o[1]), L8::splat(w.o[2])};
    const L8 neg_inv[3] = {L8::splat(w.neg_inv[0]), L8::splat(w.neg_inv[1]), L8::splat(w.neg_inv[2])};
    const L8 neg_inv_far[3] = {L8::splat(w.neg_inv_far[0]), L8::splat(w.neg_inv_far[1]), L8::splat(w.neg_inv_far[2])};
    const std::ptrdiff_t* plane = kPlanes[w.octant];
    const float far_limit = hit_t * gpu::BOX_FAR_SCALE;
    Entry cur{w.cur, w.cur_t};
    std::uint32_t sp = w.sp;
    bool pop = w.resumed;
    w.resumed = true;
    for (;;) {
        if (!pop) {
            if (cur.index & kLeafChild) {
                w.sp = sp;
                return cur.index & ~kLeafChild;
            }
            const WideNode& node = node_at(wide, cur.index);
            w.visited += node.unused[0];
            const std::uint32_t line = cur.index, pushed = sp;
            const bool entered = enter_children<false, kAnyOctant, false>(wide, node, origin, neg_inv, neg_inv_far,
                                                                          plane, w.tmin8, far_limit, w.stack, sp, cur);
            if (record) record->node(line, entered ? cur.index : kNoHit, w.stack.index + pushed, sp - pushed);
            if (entered) continue;
        }
        pop = false;
        do {  // pop, skipping entries farther than the closest hit so far (ray.h may_hold_closer)
            if (sp == 0) {
                w.sp = 0;
                return kNoHit;
            }
            --sp;
        } while (!(w.stack.t[sp] <= far_limit));
        cur = {w.stack.index[sp], w.stack.t[sp]};
    }
}
#else
// The recorded walk, in translation units of its own (traverse_wide_record*.cpp): compiled beside
// the plain walks, its calls of the same leaf and triangle functions changed how the compiler
// inlined those into them (their machine code differed from the walk's without a recorded mode).
Hit record_wide_kernel(const WideView& wide, const Ray& ray, WideRecorder& record, std::uint32_t* nodes_visited) {
    Hit hit{ray.tmax, kNoHit, 0.0f, 0.0f, kNoHit};
    const Query q = make_query(ray);
    const std::uint32_t visited = wide.lines ? traverse_nodes<false, kAnyOctant, true>(wide, q, hit, &record) : 0;
    if (nodes_visited) *nodes_visited = visited;
    return hit;
}
#endif
