// wide_traverse.inl — the traversals of the 8-wide tree (wide_bvh.h): the closest-hit walk (here),
// the any-hit walk (wide_any_hit.inl: ends at the first leaf that holds a hit) and the TLAS's
// walk, with the ray and triangle test they share (wide_ray.inl), written once against two small
// vector types that the including file defines in its own namespace:
//   L8: eight floats — load(const float*), splat(float), lane(k), + - *, raise(acc, t)
//       (= t > acc ? t : acc), lower(acc, t) (= t < acc ? t : acc), le_bits(a, b) (bit i set
//       when a[i] <= b[i]), store(float*);
//   L4: four floats — load, splat, set(a, b, c, d), + - * /, raise, lower, comparisons giving
//       an M4 mask, M4 & M4, M4 | M4, bits(M4), sign_bits(L4) (bit i: lane i's sign bit),
//       store, and permute(v, lanes) = (v[lanes[0]], v[lanes[1]], v[lanes[2]], v[3]) for four
//       lane indices 0..3, the last 3;
// and push_children(node, t0, t1, mask, index, t), which writes the children a ray enters
// but the nearest to the stack's arrays, farthest first, and returns the nearest's slot
// (traverse_wide.cpp), farthest_slot(t0, t1, mask), the slot of two or more in `mask` that
// push_children would put farthest, push_entered(node, mask, index), which writes the children
// in `mask` to index[0 .. popcount(mask)) in slot order (and may write up to eight), and
// leaf_bits(node) (bit k set where slot k is a leaf).
// traverse_wide.cpp includes it for the portable path (SSE or plain C++), traverse_wide_avx2.cpp
// for AVX2 (and, built again, for AVX-512: traverse_wide_avx512.cpp). Both compute, lane by lane, exactly what hit_box (ray.h) and the watertight
// hit_triangle (shaders/tracer/geometry.glsl) compute, so every path returns the same hit as the
// binary traversals and the brute force. Only plain data and functions of the including file are
// used here (an inline function of another header compiled for AVX2 could be picked by the
// linker for code running without AVX2): make_query repeats make_ray's per-ray arithmetic.

namespace {

#include "wide_ray.inl"

/// The start of line `i` of the wide tree.
const unsigned char* line_at(const WideView& wide, std::uint32_t i) {
    return wide.lines + std::size_t(i) * sizeof(WideLine);
}

/// The packets of a leaf, from line `first` on, up to the one without `more` (the any-hit walk's
/// is leaf_occludes, wide_any_hit.inl).
[[gnu::always_inline]] inline void test_leaf(const WideView& wide, std::uint32_t first, const Query& q, Hit& hit) {
    for (const unsigned char* at = line_at(wide, first);; at += sizeof(PrimPacket)) {
        const PrimPacket& k = *reinterpret_cast<const PrimPacket*>(at);
        // [[likely]]: the sphere calls out of line; laid out as the rare case, the leaf's entry
        // spills fewer of the node loop's registers (uniform1m random rays: 3,549 → 3,486
        // instructions a ray, Sponza 1,077 → 1,067)
        if (!(k.ref[0] & gpu::REF_SPHERE_BIT)) [[likely]] {
            test_triangles<false>(k, q, hit);
        } else {
            for (int l = 0; l < 4 && k.ref[l] != kNoHit; ++l)
                if (hit_packet_sphere(k, l, *q.ray, hit)) hit.slot = k.slot[l];
        }
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
/// Inlined into each walk (the closest-hit walk and the TLAS's).
/// kPrefetch false (the TLAS's walk, next_tlas_leaf): no prefetches, as a TLAS is small enough to
/// stay in the caches and its leaf words are no lines.
template <bool kPrefetch = true>
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
    for (int a = 0; a < 3; ++a) t0 = raise(t0, (origin[a] - L8::load(f + plane[a])) * neg_inv[a]);
    for (int a = 0; a < 3; ++a) t1 = lower(t1, (origin[a] - L8::load(f + plane[3 + a])) * neg_inv_far[a]);
    const int mask = le_bits(t0, t1);
    if (!mask) return false;
    if (!(mask & (mask - 1))) {
        const int k = __builtin_ctz(unsigned(mask));
        cur = {node.child[k], t0.lane(k)};
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
/// lives in a register and is renewed after a leaf, the one place the hit changes.
/// kRecord: each node's entered children and each leaf's effect on the hit go to `record` (the
/// inspector's record, wide_kernel.h WideRecorder); without it the calls compile away and the walk
/// is the plain one.
/// kOctant: the ray's octant where the caller knows it at compile time (the batch walks,
/// closest_of_octant below: plane offsets as constants), -1 to read it from the query.
/// `root`: the node to start from (the packet walk, wide_packet.inl, hands a subtree that few of
/// its rays enter to each of them alone, with the hit found so far), the tree's root by default.
template <bool kRecord = false, int kOctant = -1>
std::uint32_t traverse_nodes(const WideView& wide, const Query& q, Hit& hit, WideRecorder* record = nullptr,
                             std::uint32_t root = 0) {
    const L8 origin[3] = {L8::splat(q.o[0]), L8::splat(q.o[1]), L8::splat(q.o[2])};
    // The planes' distances as (origin - plane) · (-1/d), which are hit_box's (plane - origin) ·
    // 1/d (negating is exact, and a zero's sign, the only difference, changes no comparison), so
    // that the node's bounds can be the subtraction's memory operand: one load fewer per axis
    // and side (uniform1m random rays: 6 instructions fewer a node).
    // −(1/d · s) is (1/d)·(−s) bit for bit: a rounding is symmetric about zero
    const L8 neg_inv[3] = {L8::splat(q.neg_inv[0]), L8::splat(q.neg_inv[1]), L8::splat(q.neg_inv[2])};
    const L8 neg_inv_far[3] = {L8::splat(q.neg_inv_far[0]), L8::splat(q.neg_inv_far[1]), L8::splat(q.neg_inv_far[2])};
    const float s = gpu::BOX_FAR_SCALE;
    const std::ptrdiff_t* plane = kOctant < 0 ? kPlanes[q.octant] : kPlanes.at[kOctant & 7];
    Stack stack;
    std::uint32_t sp = 0, visited = 0;
    Entry cur{root, q.tmin};
    float far_limit = hit.t * s;
    for (;;) {
        if (cur.index & kLeafChild) {
            if constexpr (kRecord) {
                const Hit before = hit;
                test_leaf(wide, cur.index & ~kLeafChild, q, hit);
                record->leaf(cur.index & ~kLeafChild, before, hit);
            } else {
                test_leaf(wide, cur.index & ~kLeafChild, q, hit);
            }
            far_limit = hit.t * s;
        } else {
            ++visited;
            [[maybe_unused]] const std::uint32_t line = cur.index, pushed = sp;
            const bool entered = enter_children(wide, node_at(wide, cur.index), origin, neg_inv, neg_inv_far, plane,
                                                q.tmin8, far_limit, stack, sp, cur);
            if constexpr (kRecord) record->node(line, entered ? cur.index : kNoHit, stack.index + pushed, sp - pushed);
            if (entered) continue;
        }
        do {  // pop, skipping entries farther than the closest hit so far (ray.h may_hold_closer)
            if (sp == 0) return visited;
            --sp;
        } while (!(stack.t[sp] <= far_limit));
        cur = {stack.index[sp], stack.t[sp]};
    }
}

#include "wide_any_hit.inl"

/// N objects of type T for the calling thread, made at its first use and kept until it ends: the
/// batch walks' large state (the packet walk's stack, the interleaved walkers), off the thread's
/// stack (a thread of 32 KiB runs every batch query: design.md, "Threading model") and not
/// allocated anew a piece. A thread runs one batch walk at a time (a walk calls no batch query),
/// so one set a thread serves them all.
template <class T, int N>
T* thread_room() {
    thread_local const std::unique_ptr<T[]> room(new T[N]);
    return room.get();
}

/// The single-ray any-hit walk (wide_any_hit.inl): one copy for every octant, its plane offsets
/// read from kPlanes by the ray's octant, as the single-ray closest-hit walk does (a batch's rays go
/// through per-octant copies, grouped: wide_batch.inl). Eight copies picked per ray by an indirect
/// call were mispredicted where octants vary from ray to ray, most of all in the two-level query,
/// which walks a BLAS for every instance a shadow ray enters, its object-space octant turned by each
/// instance's rotation: 1.8 (many) and 2.1 (hundred) mispredicted calls a ray of 2.3 and 2.7 made
/// (callgrind's branch model, 5,000 shadow rays of bench/two_level.py), gone for 39 instructions a
/// ray more (+1.7%; a flat shadow ray +25-55, 3%); in time, interleaved on one pinned core,
/// two-level shadow rays ÷ Embree 3 instanced 0.70-0.75 → 0.75-0.76 (many), 0.79-0.80 → 0.82-0.86
/// (hundred), the mover and flat shadow rays (Sponza, room1m, vast1m, rods1m) unchanged within the
/// runs' spread (design.md, "Shadow rays through 10,000 instances").
[[maybe_unused]] bool any_hit_walk(const WideView& wide, const Query& q) { return any_hit_nodes<-1>(wide.lines, q); }

#ifndef BVHLAB_RECORDED_WIDE_WALK
#include "wide_batch.inl"
#endif

}  // namespace

#ifndef BVHLAB_RECORDED_WIDE_WALK
void intersect_wide_batch_kernel(const WideView& wide, const Ray* rays, const std::uint32_t* order,
                                 const std::uint32_t* start, Hit* hits, std::uint32_t* nodes_visited, WideWalk walk) {
    if (wide.lines) return closest_of_batch(wide, rays, order, start, hits, nodes_visited, walk);
    for (std::uint32_t i = 0; i < start[8]; ++i) {
        hits[i] = Hit{rays[i].tmax, kNoHit, 0.0f, 0.0f, kNoHit};
        if (nodes_visited) nodes_visited[i] = 0;
    }
}

void occluded_wide_batch_kernel(const WideView& wide, const Ray* rays, const std::uint32_t* order,
                                const std::uint32_t* start, bool* occluded) {
    if (wide.lines) return occluded_of_batch(wide, rays, order, start, occluded);
    for (std::uint32_t i = 0; i < start[8]; ++i) occluded[i] = false;
}

Hit intersect_wide_kernel(const WideView& wide, const Ray& ray, std::uint32_t* nodes_visited) {
    Hit hit{ray.tmax, kNoHit, 0.0f, 0.0f, kNoHit};
    const Query q = make_query(ray);
    const std::uint32_t visited = wide.lines ? traverse_nodes(wide, q, hit) : 0;
    if (nodes_visited) *nodes_visited = visited;
    return hit;
}

bool occluded_wide_kernel(const WideView& wide, const Ray& ray) {
    return wide.lines && any_hit_walk(wide, make_query(ray));
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
/// leaf, which is handed to the caller (its child word is kLeafChild | its first instance's
/// position in Tlas::leaf_instances); resumed by popping, with the closest hit the caller has
/// found since.
std::uint32_t next_tlas_leaf(const WideView& wide, TlasWalk& w, float hit_t, WideRecorder* record) {
    const float far_limit = hit_t * gpu::BOX_FAR_SCALE;
    std::uint32_t sp = w.sp;
    // pops, skipping entries farther than the closest hit so far (ray.h may_hold_closer); false
    // when none is left
    const auto pop = [&](Entry& e) {
        do {
            if (sp == 0) return false;
            --sp;
        } while (!(w.stack.t[sp] <= far_limit));
        e = {w.stack.index[sp], w.stack.t[sp]};
        return true;
    };
    Entry cur{w.cur, w.cur_t};
    if (w.resumed && !pop(cur)) {
        w.sp = 0;
        return kNoHit;
    }
    w.resumed = true;
    // A resumed walk mostly pops a leaf (the next instance a ray enters), handed out before the
    // node loop's set-up (its nine broadcasts, the register saves)
    if (cur.index & kLeafChild) {
        w.sp = sp;
        return cur.index & ~kLeafChild;
    }
    const L8 origin[3] = {L8::splat(w.o[0]), L8::splat(w.o[1]), L8::splat(w.o[2])};
    const L8 neg_inv[3] = {L8::splat(w.neg_inv[0]), L8::splat(w.neg_inv[1]), L8::splat(w.neg_inv[2])};
    const L8 neg_inv_far[3] = {L8::splat(w.neg_inv_far[0]), L8::splat(w.neg_inv_far[1]), L8::splat(w.neg_inv_far[2])};
    const std::ptrdiff_t* plane = kPlanes[w.octant];
    for (;;) {
        if (cur.index & kLeafChild) {
            w.sp = sp;
            return cur.index & ~kLeafChild;
        }
        const WideNode& node = node_at(wide, cur.index);
        w.visited += node.unused[0];
        const std::uint32_t line = cur.index, pushed = sp;
        const bool entered = enter_children<false>(wide, node, origin, neg_inv, neg_inv_far, plane, w.tmin8, far_limit,
                                                   w.stack, sp, cur);
        if (record) record->node(line, entered ? cur.index : kNoHit, w.stack.index + pushed, sp - pushed);
        if (!entered && !pop(cur)) {
            w.sp = 0;
            return kNoHit;
        }
    }
}
#else
// The recorded walk, in translation units of its own (traverse_wide_record*.cpp): compiled beside
// the plain walks, its calls of the same leaf and triangle functions changed how the compiler
// inlined those into them (their machine code differed from the walk's without a recorded mode).
Hit record_wide_kernel(const WideView& wide, const Ray& ray, WideRecorder& record, std::uint32_t* nodes_visited) {
    Hit hit{ray.tmax, kNoHit, 0.0f, 0.0f, kNoHit};
    const Query q = make_query(ray);
    const std::uint32_t visited = wide.lines ? traverse_nodes<true>(wide, q, hit, &record) : 0;
    if (nodes_visited) *nodes_visited = visited;
    return hit;
}
#endif
