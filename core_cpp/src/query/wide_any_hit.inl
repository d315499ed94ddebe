// wide_any_hit.inl — the any-hit walk of the 8-wide tree (occluded_wide_kernel): included by
// wide_traverse.inl, inside the including file's namespace, with its vector types and helpers.

/// Whether a leaf's packets, from `at` on, hold a primitive the ray hits at t in (tmin, tmax):
/// test_leaf's loop up to the first packet with a hit, the hit kept here rather than the walk's,
/// so that the walk keeps one value fewer across the call (its registers are full: what does not
/// fit is written and read back at every node). A hit counts by the closest-hit rule against one
/// at tmax, so occluded is exactly intersect's t < tmax.
bool leaf_occludes(const unsigned char* at, const Query& q) {
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

/// The any-hit walk for one octant: the farthest child first. A node's entered children, leaves
/// and nodes alike, are ordered by the middle of the ray's span in each box, the farthest next and
/// the others pushed so that they pop farthest first (push_children, the closest-hit walk's sort,
/// on the negated span: −exit as entry and −entry as exit give the same keys negated, exactly);
/// a leaf is tested when it comes up, and its first packet with a hit ends the walk. Why farthest
/// first (design.md, "Where repeat1m's shadow rays lose"): shadow rays end at a light, so the
/// lines near their far end are shared by all rays toward that light and stay in the caches, while
/// those near each ray's origin (a random surface point; its own leaf, entered first, never
/// occludes) are read by that ray alone. Measured against the walk it replaced (leaves tested at
/// once in slot order, the lowest inner slot next): repeat1m shadow rays 26.1 → 3.8 simulated D1
/// and 6.3 → 0.4 last-level misses a ray (design.md). Nearest first doubles them there.
/// No entry distance is kept: the boxes' far limit is the ray's tmax throughout, which every
/// pushed entry passes (push_children writes the distances to `stack.t`, unread).
/// One copy per octant, each with its plane offsets as constants (tinybvh 1.9's
/// IsOccludedOctant). The root is a node even in a tree of one leaf (make_wide).
template <int kOctant>
bool any_hit_nodes(const unsigned char* lines, const Query& q) {
    const L8 origin[3] = {L8::splat(q.o[0]), L8::splat(q.o[1]), L8::splat(q.o[2])};
    const L8 neg_inv[3] = {L8::splat(q.neg_inv[0]), L8::splat(q.neg_inv[1]), L8::splat(q.neg_inv[2])};
    const L8 neg_inv_far[3] = {L8::splat(q.neg_inv_far[0]), L8::splat(q.neg_inv_far[1]), L8::splat(q.neg_inv_far[2])};
    const L8 far = L8::splat(q.ray->tmax * gpu::BOX_FAR_SCALE), zero = L8::splat(0.0f);
    Stack stack;
    std::uint32_t sp = 0, cur = 0;
    for (;;) {
        if (cur & kLeafChild) {
            if (leaf_occludes(lines + std::size_t(cur & ~kLeafChild) * sizeof(WideLine), q)) return true;
        } else {
            const WideNode& node = *reinterpret_cast<const WideNode*>(lines + std::size_t(cur) * sizeof(WideLine));
            const float* f = node.lo_x;
            __builtin_prefetch(node.child);  // as enter_children: the child words, and the lines after
            const char* after = reinterpret_cast<const char*>(&node + 1);
            for (int line = 0; line < 6; ++line) __builtin_prefetch(after + 64 * line);
            L8 t0 = L8::load(q.tmin8), t1 = far;
            for (int a = 0; a < 3; ++a) t0 = raise(t0, (origin[a] - L8::load(f + kPlanes.at[kOctant][a])) * neg_inv[a]);
            for (int a = 0; a < 3; ++a)
                t1 = lower(t1, (origin[a] - L8::load(f + kPlanes.at[kOctant][3 + a])) * neg_inv_far[a]);
            const int mask = le_bits(t0, t1);
            if (mask & (mask - 1)) {
                const int k = push_children(node, zero - t1, zero - t0, mask, stack.index + sp, stack.t + sp);
                sp += std::uint32_t(__builtin_popcount(unsigned(mask))) - 1;
                cur = node.child[k];
                prefetch(WideView{lines}, stack.index[sp - 1]);  // the next to pop
                continue;
            }
            if (mask) {
                cur = node.child[__builtin_ctz(unsigned(mask))];
                continue;
            }
        }
        if (sp == 0) return false;
        cur = stack.index[--sp];
    }
}
