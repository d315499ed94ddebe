// wide_any_hit.inl — the any-hit walk of the 8-wide tree (occluded_wide_kernel): included by
// wide_traverse.inl, inside the including file's namespace, with its vector types and helpers.

/// Whether a leaf's packets, from `at` on, hold a primitive the ray hits at t in (tmin, tmax):
/// test_leaf's loop up to the first packet with a hit, the hit kept here rather than the walk's,
/// so that the walk keeps one value fewer across the call (its registers are full: what does not
/// fit is written and read back at every node). A hit counts by the closest-hit rule against one
/// at tmax, so occluded is exactly intersect's t < tmax.
/// kBoxesOnly: q holds the box fields alone (make_box_query), and the watertight test's are made
/// here from q.ray, at each leaf the walk reaches rather than for each ray (the layout's order:
/// any_hit_nodes).
template <bool kBoxesOnly>
bool leaf_occludes(const unsigned char* at, const Query& boxes) {
    Query lazy;
    if constexpr (kBoxesOnly) make_triangle_query(*boxes.ray, lazy);
    const Query& q = kBoxesOnly ? lazy : boxes;
    Hit hit{q.ray->tmax, kNoHit, 0.0f, 0.0f, kNoHit};
    for (;; at += sizeof(PrimPacket)) {
        const PrimPacket& k = *reinterpret_cast<const PrimPacket*>(at);
        if (!(k.ref[0] & gpu::REF_SPHERE_BIT)) [[likely]] {
            test_triangles<true>(k, q, hit);
        } else {
            for (int l = 0; l < 4 && k.ref[l] != kNoHit; ++l) hit_packet_sphere(k, l, *q.ray, hit);
        }
        if (hit.ref != kNoHit) return true;
        if (!k.more) return false;
    }
}

/// The any-hit walk for one octant: tests a node's eight boxes, then at once the leaves among the
/// children the ray enters, in slot order, ending at the first packet with a hit; of the inner
/// children entered, the farthest (by the middle of the ray's span in its box, farthest_slot:
/// push_children's key) goes next, the others are pushed unordered below it (any hit ends the
/// walk; tinybvh 1.9's IsOccluded pushes unordered too). Farthest first because shadow rays end at
/// a light: the lines near their far end are read by every ray toward that light and stay in the
/// caches, those near each ray's origin (a surface point; its own leaf never occludes) by that ray
/// alone, so an occluder found from the far end is mostly found in cached lines (repeat1m shadow
/// rays, callgrind on 20,000: 31.3 → 12.6 D1 and 8.3 → 2.1 last-level misses a ray against the
/// lowest slot next, 0.58 → 1.13 of the best peer; nearest first doubled the misses; design.md,
/// "Where repeat1m's shadow rays lose"). A leaf is never pushed or popped, so every entry is a
/// node and the loop has no branch on the kind, and a leaf's packets, laid after their node
/// (wide_bvh.h), are read while the node's prefetch of the lines after it is fresh (Sponza
/// shadow rays +16% against the walk that pushed leaves as nodes; design.md, "Any-hit queries";
/// every child farthest first, leaves pushed as nodes, was 0.80 there: design.md).
/// No entry distance is kept: the boxes' far limit is the ray's tmax throughout, which every
/// pushed entry passes.
/// kOctant: the batch's octant, its plane offsets then constants (one copy per octant, tinybvh
/// 1.9's IsOccludedOctant), or -1, read from the query (the single-ray walk, any_hit_walk). The
/// root is a node even in a tree of one leaf (make_wide).
/// kFarthest false: the lowest inner slot next instead, the layout's order (wide_bvh.h: a node's
/// leaves' packets, then its inner children's subtrees in slot order, so the lowest slot's lines
/// follow those the node prefetched), for rays that mostly reach their light, where every order
/// visits the same nodes and the farthest only costs its choice (room1m and vast1m shadow rays, 95%
/// and 100% unoccluded, 6-7% slower with it; the batch picks: wide_batch.inl occluded_of_batch).
/// Such rays reach few leaves and wait on few lines, so this order also takes q with the box
/// fields alone (make_box_query; leaf_occludes makes the rest) and prefetches nothing.
template <int kOctant, bool kFarthest = true>
bool any_hit_nodes(const unsigned char* lines, const Query& q) {
    const L8 origin[3] = {L8::splat(q.o[0]), L8::splat(q.o[1]), L8::splat(q.o[2])};
    const L8 neg_inv[3] = {L8::splat(q.neg_inv[0]), L8::splat(q.neg_inv[1]), L8::splat(q.neg_inv[2])};
    const L8 neg_inv_far[3] = {L8::splat(q.neg_inv_far[0]), L8::splat(q.neg_inv_far[1]), L8::splat(q.neg_inv_far[2])};
    const L8 far = L8::splat(q.ray->tmax * gpu::BOX_FAR_SCALE);
    const std::ptrdiff_t* plane = kOctant < 0 ? kPlanes[q.octant] : kPlanes.at[kOctant & 7];
    std::uint32_t stack[Stack::kSize];
    std::uint32_t sp = 0, cur = 0;
    for (;;) {
        const WideNode& node = *reinterpret_cast<const WideNode*>(lines + std::size_t(cur) * sizeof(WideLine));
        const float* f = node.lo_x;
        if constexpr (kFarthest) {
            __builtin_prefetch(node.child);  // as enter_children: the child words, and the lines after
            const char* after = reinterpret_cast<const char*>(&node + 1);
            for (int line = 0; line < 6; ++line) __builtin_prefetch(after + 64 * line);
        }
        L8 t0 = L8::load(q.tmin8), t1 = far;
        for (int a = 0; a < 3; ++a) t0 = raise(t0, (origin[a] - L8::load(f + plane[a])) * neg_inv[a]);
        for (int a = 0; a < 3; ++a) t1 = lower(t1, (origin[a] - L8::load(f + plane[3 + a])) * neg_inv_far[a]);
        const int mask = le_bits(t0, t1);
        const int leaves = mask & leaf_bits(node), inner = mask ^ leaves;
        if (inner) {  // the farthest (or lowest) inner child next, the others pushed unordered below it
            const int next =
                kFarthest && (inner & (inner - 1)) ? farthest_slot(t0, t1, inner) : __builtin_ctz(unsigned(inner));
            const int rest = inner & ~(1 << next);
            if (rest) {
                push_entered(node, rest, stack + sp);
                sp += std::uint32_t(__builtin_popcount(unsigned(rest)));
                if constexpr (kFarthest) prefetch(WideView{lines}, stack[sp - 1]);  // the next to pop after it
            }
            if (!leaves) {  // the commonest case: the next node from the node's words, not the stack
                cur = node.child[next];
                continue;
            }
            stack[sp++] = node.child[next];  // pushed before the leaves' calls: popped right after them
            if constexpr (kFarthest) prefetch(WideView{lines}, node.child[next]);
        }
        for (int m = leaves; m; m &= m - 1)
            if (leaf_occludes<!kFarthest>(
                    lines + std::size_t(node.child[__builtin_ctz(unsigned(m))] & ~kLeafChild) * sizeof(WideLine), q))
                return true;
        if (sp == 0) return false;
        cur = stack[--sp];
    }
}
