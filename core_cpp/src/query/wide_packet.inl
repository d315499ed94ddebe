// wide_packet.inl — packets of coherent rays through the 8-wide tree (issue 36, design.md "Packets
// for coherent rays"): the batch's closest-hit walk (closest_of_octant, wide_batch.inl) sends eight
// rays of one octant that share an origin and nearly a direction (a camera's neighbouring pixels)
// through the tree together, one ray in each AVX lane: each node's child boxes are loaded once for
// the eight rays, and the packet is ordered, pushed and popped once. Wald, Slusallek, Benthin and
// Wagner 2001 ("Interactive rendering with coherent ray tracing": SIMD across the rays of a
// packet), with per-ray active masks and entry distances on the stack as in Embree's packet
// traversal (Wald et al. 2014). Only in the AVX2 path (traverse_wide_avx2.cpp defines
// BVHLAB_WIDE_PACKETS); the portable path keeps single rays.
//
// The hits are the single walk's bit for bit: each lane does exactly the single walk's box test
// (the same raises and lowers of the same products, from the ray's own tmin and far limit), so a
// ray enters a child exactly where its own walk, at the same closest hit, would; it may visit
// more (the packet's order is not its own nearest-first order, so its far limit may still be
// larger), never fewer, and each leaf is tested by test_leaf with the ray's own query, under the
// order-independent closer-hit rule (ray.h closer_hit). From a packet's second node, one vector
// test of the whole packet against the eight child boxes (maybe_entered: interval arithmetic over
// the rays' factors) drops the slots no ray enters before the per-ray tests.

inline constexpr int kPacket = 8;

/// Directions at most ~5.7° apart (cos² of the angle to the first ray's at least this) count as
/// one packet's.
inline constexpr float kPacketCos2 = 0.99f;

/// A subtree entered by at most this many of a packet's rays is walked by each alone: a packet
/// stays one while at least six of its eight rays go the same way. With 2, uniform1m's camera rays
/// (a cube of tiny triangles, where neighbouring pixels part within a few levels) were 10% slower
/// through the batch than without packets (0.95 → 0.85 of the best peer); with 5, 0.93-0.97, and
/// Sponza, room1m, repeat1m, vast1m, rods1m as with 2 or better (design.md "Packets for coherent
/// rays").
inline constexpr int kAlone = 5;

static_assert(sizeof(Ray) == 8 * sizeof(float) && offsetof(Ray, dir) == 12 && offsetof(Ray, tmin) == 24 &&
                  offsetof(Ray, tmax) == 28,
              "a Ray is one 32-byte row: origin, direction, tmin, tmax");

/// Eight rays' fields a vector each, ray r in lane r: the rows rays[ids[0, kPacket)] read as
/// vectors and transposed (8 × 8), for the coherence test and the packet's set-up at once.
struct PacketRays {
    __m256 o[3], d[3], tmin, tmax;
};

inline PacketRays packet_rays(const Ray* rays, const std::uint32_t* ids) {
    __m256 r[8];
    for (int k = 0; k < 8; ++k) r[k] = _mm256_loadu_ps(reinterpret_cast<const float*>(rays + ids[k]));
    transpose8(r);  // transpose_avx2.h, included by traverse_wide_avx2.cpp
    return {{r[0], r[1], r[2]}, {r[3], r[4], r[5]}, r[6], r[7]};
}

/// Lane 0 of x in every lane.
inline __m256 first_lane(__m256 x) { return _mm256_permutevar8x32_ps(x, _mm256_setzero_si256()); }

/// Whether the eight rays (one octant) go through the tree as one packet: the same origin as the
/// first ray's (as floats: −0 and 0 alike; a pinhole camera's rays) and directions within
/// kPacketCos2 of the first's, eight lanes at once. Random and shadow rays fail (their origins).
inline bool coherent(const PacketRays& p) {
    __m256 ok = _mm256_cmp_ps(p.o[0], first_lane(p.o[0]), _CMP_EQ_OQ);
    ok = _mm256_and_ps(ok, _mm256_cmp_ps(p.o[1], first_lane(p.o[1]), _CMP_EQ_OQ));
    ok = _mm256_and_ps(ok, _mm256_cmp_ps(p.o[2], first_lane(p.o[2]), _CMP_EQ_OQ));
    const __m256 x0 = first_lane(p.d[0]), y0 = first_lane(p.d[1]), z0 = first_lane(p.d[2]);
    const auto dot = [](__m256 ax, __m256 ay, __m256 az, __m256 bx, __m256 by, __m256 bz) {
        return _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(ax, bx), _mm256_mul_ps(ay, by)), _mm256_mul_ps(az, bz));
    };
    const __m256 c = dot(x0, y0, z0, p.d[0], p.d[1], p.d[2]);
    const __m256 n0 = dot(x0, y0, z0, x0, y0, z0), n = dot(p.d[0], p.d[1], p.d[2], p.d[0], p.d[1], p.d[2]);
    ok = _mm256_and_ps(ok, _mm256_cmp_ps(c, _mm256_setzero_ps(), _CMP_GT_OQ));
    const __m256 least = _mm256_mul_ps(_mm256_mul_ps(_mm256_set1_ps(kPacketCos2), n0), n);
    ok = _mm256_and_ps(ok, _mm256_cmp_ps(_mm256_mul_ps(c, c), least, _CMP_GE_OQ));
    return _mm256_movemask_ps(ok) == 0xff;
}

/// The packet walk's stack: a child word and the entry distance of each ray in its lane (NaN where
/// the ray did not enter it, which no far limit passes).
struct PacketStack {
    static constexpr std::uint32_t kSize = WideStack::kSize;
    alignas(32) float t[kSize][kPacket];
    std::uint32_t index[kSize];
};

/// The least and the largest of x's lanes, in every lane.
inline L8 least(L8 x) {
    __m256 m = _mm256_min_ps(x.v, _mm256_permute2f128_ps(x.v, x.v, 1));
    m = _mm256_min_ps(m, _mm256_shuffle_ps(m, m, _MM_SHUFFLE(1, 0, 3, 2)));
    return {_mm256_min_ps(m, _mm256_shuffle_ps(m, m, _MM_SHUFFLE(2, 3, 0, 1)))};
}
inline L8 largest(L8 x) {
    __m256 m = _mm256_max_ps(x.v, _mm256_permute2f128_ps(x.v, x.v, 1));
    m = _mm256_max_ps(m, _mm256_shuffle_ps(m, m, _MM_SHUFFLE(1, 0, 3, 2)));
    return {_mm256_max_ps(m, _mm256_shuffle_ps(m, m, _MM_SHUFFLE(2, 3, 0, 1)))};
}

/// The smallest lane of t among `in` (+inf where none): a packet's child's sort key, of the
/// middles (t0 + t1) of the rays' spans in its box, as the single walk's order (enter_children
/// says why: Sponza's camera stands inside boxes; ordered by the least entry instead, Sponza's
/// primary rays were 7% slower, room1m's 3% faster, repeat1m's and vast1m's even).
inline float least_lane(__m256 t, __m256 in) {
    return _mm256_cvtss_f32(
        least(L8{_mm256_blendv_ps(_mm256_set1_ps(std::numeric_limits<float>::infinity()), t, in)}).v);
}

/// The bounds of a packet's box-test factors over its rays (Boulos, Wald et al. 2006, "Geometric
/// and arithmetic culling methods for entire ray packets": interval arithmetic over the packet),
/// so that one vector test of a node's eight children drops those no ray of the packet enters
/// before the per-ray tests of the others (maybe_entered), each bound in every lane. `valid` is
/// false where some ray's factor is infinite, zero (a direction with a zero component) or under
/// the least normal float: a product with a plane difference could then be NaN, which the per-ray
/// test ignores and a bound cannot, so such a packet tests every child ray by ray.
struct Interval {
    L8 near_lo[3], near_hi[3], far_lo[3], far_hi[3];  // per axis: the least and largest factor
    L8 tmin_lo;                                       // the least tmin
    L8 limit_hi;                                      // the largest far limit (renewed after leaves)
    bool valid;
};

/// The packet's Interval from its rays' factors (closest_packet's neg_inv and neg_inv_far, a ray a
/// lane), tmin and far limits.
inline Interval packet_interval(const L8* neg_inv, const L8* neg_inv_far, L8 tmin, L8 far_limit) {
    Interval span{};
    const __m256 inf = _mm256_set1_ps(std::numeric_limits<float>::infinity());
    const __m256 magnitude = _mm256_castsi256_ps(_mm256_set1_epi32(0x7fffffff));
    const __m256 normal = _mm256_set1_ps(std::numeric_limits<float>::min());
    __m256 ok = _mm256_castsi256_ps(_mm256_set1_epi32(-1));
    for (int a = 0; a < 3; ++a) {
        // |−(1/d)·s| < inf and |−(1/d)| normal (a denormal reads as 0 under denormals-are-zero)
        ok = _mm256_and_ps(ok, _mm256_cmp_ps(_mm256_and_ps(neg_inv_far[a].v, magnitude), inf, _CMP_LT_OQ));
        ok = _mm256_and_ps(ok, _mm256_cmp_ps(_mm256_and_ps(neg_inv[a].v, magnitude), normal, _CMP_GE_OQ));
        span.near_lo[a] = least(neg_inv[a]), span.near_hi[a] = largest(neg_inv[a]);
        span.far_lo[a] = least(neg_inv_far[a]), span.far_hi[a] = largest(neg_inv_far[a]);
    }
    span.tmin_lo = least(tmin), span.limit_hi = largest(far_limit);
    span.valid = _mm256_movemask_ps(ok) == 0xff;
    return span;
}

/// The slots of the node whose planes start at `f` that some ray of the packet may enter: a slot
/// no ray enters (the per-ray test's entry after its exit for every ray) is left out, and every
/// slot some ray enters is in. Why it is exact in floats: a per-ray plane distance is one product
/// fl(x · n_r) of the difference x = origin − plane, the same for every ray (one origin), and the
/// ray's factor n_r; rounding is monotone, so fl(x · n_r) lies between fl(x · n_lo) and
/// fl(x · n_hi) whichever the sign of x. With no NaN (span.valid), each ray's entry (the largest
/// of tmin and the three near distances) is at least the largest of the lower bounds, and its exit
/// (the least of its far limit and the three far distances) at most the least of the upper bounds;
/// where the first exceeds the second, no ray's entry is at or before its exit.
inline int maybe_entered(const Interval& span, const float* f, const std::ptrdiff_t* plane, const L8* origin) {
    if (!span.valid) return 0xff;
    L8 t0 = span.tmin_lo, t1 = span.limit_hi;
    for (int a = 0; a < 3; ++a) {
        const L8 x = origin[a] - L8::load(f + plane[a]);
        t0 = raise(t0, lower(x * span.near_lo[a], x * span.near_hi[a]));
        const L8 y = origin[a] - L8::load(f + plane[3 + a]);
        t1 = lower(t1, raise(y * span.far_lo[a], y * span.far_hi[a]));
    }
    return le_bits(t0, t1);
}

/// The closest hits of rays[ids[0, kPacket)], all of octant kOctant, to hits[ids[r]] (unfinished,
/// as closest_of_octant's), by one walk of the packet: nearest child first by the least middle of
/// the rays' spans in its box (least_lane). `p`: the rays' fields, as packet_rays reads them;
/// `stack`: the walk's (19 KiB, the calling thread's: thread_room).
template <int kOctant>
void closest_packet(const WideView& wide, const Ray* rays, const std::uint32_t* ids, const PacketRays& p, Hit* hits,
                    PacketStack& stack) {
    const float s = gpu::BOX_FAR_SCALE;
    // The box test's factors for the eight rays at once, by make_query's operations lane by lane
    // (the same IEEE division and products, so the same bits); the origin is one for all
    // (coherent). The triangle test's query is made for a ray at its first leaf only: most of
    // room1m's camera rays reach none (design.md).
    alignas(32) float tmax[kPacket], far[kPacket];
    _mm256_store_ps(tmax, p.tmax);
    _mm256_store_ps(far, _mm256_mul_ps(p.tmax, _mm256_set1_ps(s)));  // the single walk's far_limit, lane by lane
    Hit h[kPacket];
    for (int r = 0; r < kPacket; ++r) h[r] = Hit{tmax[r], kNoHit, 0.0f, 0.0f, kNoHit};
    // the first ray's origin for all (coherent: the others' equal it), as the interval cull needs
    const L8 origin[3] = {L8{first_lane(p.o[0])}, L8{first_lane(p.o[1])}, L8{first_lane(p.o[2])}};
    L8 neg_inv[3], neg_inv_far[3];
    for (int a = 0; a < 3; ++a) {
        const L8 inv = L8::splat(1.0f) / L8{p.d[a]};
        neg_inv[a] = inv * L8::splat(-1.0f), neg_inv_far[a] = inv * L8::splat(-s);
    }
    Query q[kPacket];
    int made = 0;  // bit r: q[r] made
    const auto query = [&](int r) -> const Query& {
        if (!(made >> r & 1)) q[r] = make_query(rays[ids[r]]), made |= 1 << r;
        return q[r];
    };
    const L8 t_min{p.tmin};
    L8 far_limit = L8::load(far);
    // made at the packet's second node: most of room1m's and repeat1m's camera packets end at the
    // root (every ray misses), where the per-ray tests of its children cost less than the bounds
    Interval span{};
    int packet_nodes = 0;
    const std::ptrdiff_t* plane = kPlanes.at[kOctant & 7];
    const __m256 none = _mm256_set1_ps(std::numeric_limits<float>::quiet_NaN());
    std::uint32_t sp = 0, cur = 0;
    L8 cur_t = t_min;  // the root: every ray enters it at tmin, as the single walk does
    for (;;) {
        // the rays whose entry is within their closest hit so far (ray.h may_hold_closer)
        const __m256 active = _mm256_cmp_ps(cur_t.v, far_limit.v, _CMP_LE_OS);
        const int lanes = _mm256_movemask_ps(active);
        if (!(cur & kLeafChild) && __builtin_popcount(unsigned(lanes)) <= kAlone) {
            // a subtree few of the rays enter: each of them through it alone (a packet's node
            // costs a box test of eight rays a child, whatever the rays still in it; Benthin,
            // Wald et al. 2012, "Combining single and packet-ray tracing", Embree's hybrid walk)
            for (int m = lanes; m; m &= m - 1) {
                const int r = __builtin_ctz(unsigned(m));
                traverse_nodes<false, kOctant>(wide, query(r), h[r], nullptr, cur);
                far[r] = h[r].t * s;
            }
            far_limit = L8::load(far);
            span.limit_hi = largest(far_limit);
        } else if (cur & kLeafChild) {
            for (int m = lanes; m; m &= m - 1) {
                const int r = __builtin_ctz(unsigned(m));
                test_leaf(wide, cur & ~kLeafChild, query(r), h[r]);
                far[r] = h[r].t * s;
            }
            far_limit = L8::load(far);
            span.limit_hi = largest(far_limit);
        } else {
            const WideNode& node = node_at(wide, cur);
            __builtin_prefetch(node.child);
            const float* f = node.lo_x;
            std::uint32_t child[8];
            float key[8];
            alignas(32) float entry[8][kPacket];
            int n = 0;
            // the slots in use (an unused slot's box is inverted): a packet tests each child
            // for its eight rays at once, so an empty slot would cost a whole test
            int slots = le_bits(L8::load(node.lo_x), L8::load(node.hi_x));
            if (packet_nodes++ == 1) span = packet_interval(neg_inv, neg_inv_far, t_min, far_limit);
            if (packet_nodes > 1) slots &= maybe_entered(span, f, plane, origin);
            for (; slots; slots &= slots - 1) {
                const int c = __builtin_ctz(unsigned(slots));
                // hit_box's raises and lowers in enter_children's order, lane by lane
                L8 t0 = t_min, t1 = far_limit;
                for (int a = 0; a < 3; ++a) t0 = raise(t0, (origin[a] - L8::splat(f[plane[a] + c])) * neg_inv[a]);
                for (int a = 0; a < 3; ++a)
                    t1 = lower(t1, (origin[a] - L8::splat(f[plane[3 + a] + c])) * neg_inv_far[a]);
                const __m256 in = _mm256_and_ps(_mm256_cmp_ps(t0.v, t1.v, _CMP_LE_OS), active);
                if (!_mm256_movemask_ps(in)) continue;
                _mm256_store_ps(entry[n], _mm256_blendv_ps(none, t0.v, in));
                key[n] = least_lane(_mm256_add_ps(t0.v, t1.v), in);
                child[n++] = node.child[c];
            }
            if (n > 0) {
                // the farthest pushed first: an insertion sort of at most eight keys, then the
                // nearest taken as the next entry
                int rank[8];
                for (int i = 0; i < n; ++i) {
                    int j = i;
                    for (; j > 0 && key[rank[j - 1]] < key[i]; --j) rank[j] = rank[j - 1];
                    rank[j] = i;
                }
                for (int i = 0; i + 1 < n; ++i) {
                    const int e = rank[i];
                    stack.index[sp] = child[e];
                    _mm256_store_ps(stack.t[sp], _mm256_load_ps(entry[e]));
                    prefetch(wide, child[e]);
                    ++sp;
                }
                cur = child[rank[n - 1]];
                cur_t = L8{_mm256_load_ps(entry[rank[n - 1]])};
                continue;
            }
        }
        do {  // pop, skipping entries that no ray may find a closer hit in
            if (sp == 0) {
                for (int r = 0; r < kPacket; ++r) hits[ids[r]] = h[r];
                return;
            }
            --sp;
            cur_t = L8{_mm256_load_ps(stack.t[sp])};
        } while (!le_bits(cur_t, far_limit));
        cur = stack.index[sp];
    }
}
