// wide_ray.inl — the wide walks' ray (Query, make_query) and their watertight test of a packet of
// four triangles (test_triangles): included by wide_traverse.inl inside the including file's
// namespace, with its vector types (wide_traverse.inl lists them).

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
    int octant;  ///< bit a set where 1/dir[a] is negative: kPlanes' row
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

/// The watertight test's fields of q (o_axes, shear, axis_at) from the ray, make_query's operations.
[[gnu::always_inline]] inline void set_triangle_fields(const Ray& ray, const L4 origin, const L4 dir, const L4 inv,
                                                       Query& q) {
    const float x = std::fabs(ray.dir.x), y = std::fabs(ray.dir.y), z = std::fabs(ray.dir.z);
    const int x_largest = int(x > y) & int(x > z), y_largest = (1 - x_largest) & int(y > z);
    const int kz = 2 - 2 * x_largest - y_largest;
    const int flip = (bits(L4::splat(0.0f) > dir) >> kz) & 1;  // dir[kz] < 0
    const AxisOrder& axes = kAxisOrders[2 * kz + flip];
    // (dir[kx], dir[ky], 1, 1) times 1 / dir[kz]: the shear, and 1 / dir[kz] itself in lane 2
    // (1 · x is x, except a denormal x under denormals-are-zero: 0, which is what the one use of
    // shear[2], a product, reads x as in that mode anyway)
    permute(origin, axes.origin).store(q.o_axes);
    (permute(dir, axes.dir) * permute(inv, axes.inv)).store(q.shear);
    q.axis_at = axes.at;
}

/// The per-ray constants as geometry.glsl make_ray computes them, by the same float operations
/// (so the same values; every test comparing the wide traversal with the brute force, which goes
/// through make_ray, checks that bit for bit): 1/d is IEEE's, ±inf for ±0 as inverse_or_infinity;
/// kz the axis of the largest |component| (ties to the later axis), kx and ky the next two,
/// swapped when dir[kz] < 0; the shear as products with 1/dir[kz]. Computed here from the ray's
/// fields rather than copied out of a TraceRay, which cost cheap rays a third of their time.
/// Without branches: the axes come from comparison flags and the components in axis order from
/// a permute. Selects by the axis compiled to branches, which random directions mispredicted
/// (1.4 a ray, a tenth of a random ray's time in room1m).
/// Written into q in place (the interleaved walks keep their query in the walker, where a returned
/// one was made out of line and copied: vast1m random rays through the batch, 67 instructions a
/// ray). kBoxes: the box test's fields (o, inv, neg_inv, neg_inv_far, octant); kTriangles: the
/// watertight test's (o_axes, shear, axis_at); tmin8, tmin and ray always.
template <bool kBoxes, bool kTriangles>
[[gnu::always_inline]] inline void set_query(const Ray& ray, Query& q) {
    const Vec3 o = ray.origin, d = ray.dir;
    const L4 dir = L4::set(d.x, d.y, d.z, 1.0f), origin = L4::set(o.x, o.y, o.z, 0.0f);
    const L4 inv = L4::splat(1.0f) / dir;
    if constexpr (kBoxes) {
        origin.store(q.o), inv.store(q.inv);
        (inv * L4::splat(-1.0f)).store(q.neg_inv), (inv * L4::splat(-gpu::BOX_FAR_SCALE)).store(q.neg_inv_far);
    }
    if constexpr (kTriangles) set_triangle_fields(ray, origin, dir, inv, q);
    L8::splat(ray.tmin).store(q.tmin8);
    if constexpr (kBoxes) q.octant = sign_bits(inv) & 7;
    q.tmin = ray.tmin, q.ray = &ray;
}
Query make_query(const Ray& ray) {
    Query q;
    set_query<true, true>(ray, q);
    return q;
}
/// make_query without the watertight test's fields, what the boxes need, for a walk that makes
/// those fields at the leaves it reaches (make_triangle_query), since most of its rays reach none
/// (the any-hit walk in the layout's order: design.md, "Any-hit queries").
[[maybe_unused]] Query make_box_query(const Ray& ray) {
    Query q;
    set_query<true, false>(ray, q);
    return q;
}

/// The fields test_triangles and hit_packet_sphere read (o_axes, shear, axis_at, tmin8, ray), as
/// make_query makes them; the box fields are left unset.
[[gnu::always_inline]] inline void make_triangle_query(const Ray& ray, Query& q) { set_query<false, true>(ray, q); }

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

/// geometry.glsl product_error and exact_edge, the same operations (plain functions of this file:
/// an inline function of a header compiled here for AVX2 could be the copy the linker keeps for
/// the portable path, wide_traverse.inl's note).
inline float product_error(float a, float b, float p) {
    const float ca = 4097.0f * a, ah = ca - (ca - a), al = a - ah;
    const float cb = 4097.0f * b, bh = cb - (cb - b), bl = b - bh;
    return ((ah * bh - p) + (ah * bl + al * bh)) + al * bl;
}
inline float exact_edge(float a, float b, float c, float d) {
    const float p = a * b, q = c * d;
    return product_error(a, b, p) - product_error(c, d, q);
}

/// Edge functions of four lanes.
struct Edges {
    L4 u, v, w;
};

/// u, v, w with those of the lanes in `lanes` that are 0 made again exactly (exact_edge). Out of
/// line and by value: u, v, w passed by reference had their addresses taken in the inlined walk,
/// which then kept them in memory on the hot path too (Sponza primary and random rays: 1-2% in an A/B).
[[gnu::noinline]] inline Edges redo_zero_edges(int lanes, L4 ax, L4 ay, L4 bx, L4 by, L4 cx, L4 cy, L4 u, L4 v, L4 w) {
    alignas(16) float a_x[4], a_y[4], b_x[4], b_y[4], c_x[4], c_y[4], us[4], vs[4], ws[4];
    ax.store(a_x), ay.store(a_y), bx.store(b_x), by.store(b_y), cx.store(c_x), cy.store(c_y);
    u.store(us), v.store(vs), w.store(ws);
    for (; lanes; lanes &= lanes - 1) {
        const int l = __builtin_ctz(unsigned(lanes));
        if (us[l] == 0.0f) us[l] = exact_edge(c_x[l], b_y[l], c_y[l], b_x[l]);
        if (vs[l] == 0.0f) vs[l] = exact_edge(a_x[l], c_y[l], a_y[l], c_x[l]);
        if (ws[l] == 0.0f) ws[l] = exact_edge(b_x[l], a_y[l], b_y[l], a_x[l]);
    }
    return {L4::load(us), L4::load(vs), L4::load(ws)};
}

/// The watertight test (geometry.glsl hit_triangle) on four triangles at once, its operations in
/// its order lane by lane; the lanes that pass become hits in lane order under the closest-hit rule.
/// kAnyHit: the first lane that passes is the hit (its t and ref only; the query wants no more).
/// Inlined into its leaf loops, as the compiler did while the closest-hit walk was one copy: with
/// eight more (the batch walks, wide_batch.inl) it called it out of line (Sponza random rays +22
/// instructions a ray).
template <bool kAnyHit>
[[gnu::always_inline]] inline void test_triangles(const PrimPacket& k, const Query& q, Hit& hit) {
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
    L4 u = cx * by - cy * bx, v = ax * cy - ay * cx, w = bx * ay - by * ax;
    const L4 zero = L4::splat(0.0f);
    // "not (some negative and some positive)"; a NaN lane (an empty one: make_wide) fails here
    L4 low = lower(lower(u, v), w), high = raise(raise(u, v), w);
    M4 one_sign = (low >= zero) | (high <= zero);
    if (!bits(one_sign)) return;  // most packets a ray reaches: nothing more to work out
    // A lane with an edge function of 0 (one, two or all three), which then passes the sign test
    // (its least or greatest is that 0): those made again exactly, as geometry.glsl
    // sheared_triangle does (exact_edge). A lane that fails keeps failing (its other two differ
    // in sign); a NaN lane has no 0 to find.
    if (const int zeros = 15 & ~bits((low != zero) & (high != zero))) [[unlikely]] {
        const Edges exact = redo_zero_edges(zeros, ax, ay, bx, by, cx, cy, u, v, w);
        u = exact.u, v = exact.v, w = exact.w;
        low = lower(lower(u, v), w), high = raise(raise(u, v), w);
        one_sign = (low >= zero) | (high <= zero);
    }
    const L4 det = (u + v) + w;
    const M4 inside = one_sign & (det != zero);
    if (!bits(inside)) return;  // no division to wait for
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
