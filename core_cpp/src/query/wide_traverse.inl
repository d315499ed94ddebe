// wide_traverse.inl — the closest-hit traversal of the 8-wide tree (wide_bvh.h), written once
// against two small vector types that the including file defines in its own namespace:
//   L8: eight floats — load(const float*), splat(float), operator-, operator*, raise(acc, t)
//       (= t > acc ? t : acc), lower(acc, t) (= t < acc ? t : acc), le_bits(a, b) (bit i set
//       when a[i] <= b[i]), store(float*);
//   L4: four floats — load, splat, + - * /, comparisons giving an M4 mask, M4 & M4, bits(M4),
//       store.
// traverse_wide.cpp includes it for the portable path (SSE or plain C++), traverse_wide_avx2.cpp
// for AVX2. Both compute, lane by lane, exactly what hit_box and hit_triangle (ray.h) compute,
// so every path returns the same hit. Only plain data and functions of the including file are
// used here (an inline function of another header compiled for AVX2 could be picked by the
// linker for code running without AVX2).

namespace {

/// The ray as the tests need it: origin, direction, exact inverse direction, tmin.
struct Query {
    float o[3], d[3], inv[3], tmin;
};

struct Entry {
    std::uint32_t index, count;  ///< count > 0: a leaf of `count` packets from `index`
    float t;                     ///< where the ray enters the box
};

/// closer_hit (ray.h), repeated here for the reason given at the top of this file.
bool closer(float t, std::uint32_t ref, const Hit& hit) {
    return t < hit.t || (t == hit.t && hit.ref != kNoHit && ref < hit.ref);
}

/// Möller–Trumbore on four triangles at once (hit_triangle's operations, lane by lane); the
/// lanes that pass become hits in lane order under the closest-hit rule.
void test_triangles(const PrimPacket& k, std::uint32_t packet, const Query& q, const WideView& wide, Hit& hit) {
    const L4 dx = L4::splat(q.d[0]), dy = L4::splat(q.d[1]), dz = L4::splat(q.d[2]);
    const L4 e1x = L4::load(k.e1x), e1y = L4::load(k.e1y), e1z = L4::load(k.e1z);
    const L4 e2x = L4::load(k.e2x), e2y = L4::load(k.e2y), e2z = L4::load(k.e2z);
    const L4 px = dy * e2z - dz * e2y, py = dz * e2x - dx * e2z, pz = dx * e2y - dy * e2x;
    const L4 det = (e1x * px + e1y * py) + e1z * pz;
    const L4 zero = L4::splat(0.0f), one = L4::splat(1.0f);
    const L4 inv_det = one / det;
    const L4 tx = L4::splat(q.o[0]) - L4::load(k.v0x), ty = L4::splat(q.o[1]) - L4::load(k.v0y),
             tz = L4::splat(q.o[2]) - L4::load(k.v0z);
    const L4 u = ((tx * px + ty * py) + tz * pz) * inv_det;
    const L4 qx = ty * e1z - tz * e1y, qy = tz * e1x - tx * e1z, qz = tx * e1y - ty * e1x;
    const L4 v = ((dx * qx + dy * qy) + dz * qz) * inv_det;
    const L4 t = ((e2x * qx + e2y * qy) + e2z * qz) * inv_det;
    int lanes = bits((det != zero) & (u >= zero) & (u <= one) & (v >= zero) & (u + v <= one) & (t > L4::splat(q.tmin)));
    if (!lanes) return;
    alignas(16) float ts[4], us[4], vs[4];
    t.store(ts), u.store(us), v.store(vs);
    for (; lanes; lanes &= lanes - 1) {
        const int l = __builtin_ctz(unsigned(lanes));
        if (!closer(ts[l], k.ref[l], hit)) continue;
        hit.t = ts[l], hit.ref = k.ref[l], hit.u = us[l], hit.v = vs[l];
        hit.slot = wide.slots[4 * std::size_t(packet) + l];
    }
}

void test_leaf(const WideView& wide, std::uint32_t first, std::uint32_t count, const Query& q, Hit& hit) {
    for (std::uint32_t p = first; p < first + count; ++p) {
        const PrimPacket& k = wide.packets[p];
        if (!(k.ref[0] & gpu::REF_SPHERE_BIT)) {
            test_triangles(k, p, q, wide, hit);
            continue;
        }
        for (int l = 0; l < 4 && k.ref[l] != kNoHit; ++l)
            if (hit_packet_sphere(k, l, q.o, q.d, q.tmin, hit)) hit.slot = wide.slots[4 * std::size_t(p) + l];
    }
}

/// The children of `node` the ray enters before hit.t, nearest last: returns how many.
int enter_children(const WideNode& node, const L8 origin[3], const L8 inv[3], const int near[3], float tmin, const Hit& hit,
                   Entry out[8]) {
    const float* f = node.lo_x;
    // the same order of raises and lowers as hit_box: NaN from 0·inf on a face is ignored
    L8 t0 = L8::splat(tmin), t1 = L8::splat(hit.t);
    for (int a = 0; a < 3; ++a) t0 = raise(t0, (L8::load(f + near[a]) - origin[a]) * inv[a]);
    for (int a = 0; a < 3; ++a) t1 = lower(t1, (L8::load(f + (near[a] ^ 8)) - origin[a]) * inv[a]);
    int mask = le_bits(t0, t1);
    if (!mask) return 0;
    alignas(32) float entry[8];
    t0.store(entry);
    int k = __builtin_ctz(unsigned(mask));
    out[0] = {node.child[k], node.count[k], entry[k]};
    if (!(mask &= mask - 1)) return 1;  // the common case: one child entered
    k = __builtin_ctz(unsigned(mask));
    const Entry second{node.child[k], node.count[k], entry[k]};
    if (second.t > out[0].t) out[1] = out[0], out[0] = second;  // farther first
    else out[1] = second;
    int h = 2;
    for (mask &= mask - 1; mask; mask &= mask - 1) {
        k = __builtin_ctz(unsigned(mask));
        const Entry e{node.child[k], node.count[k], entry[k]};
        int j = h++;
        for (; j > 0 && out[j - 1].t < e.t; --j) out[j] = out[j - 1];  // by decreasing entry distance
        out[j] = e;
    }
    return h;
}

std::uint32_t traverse_nodes(const WideView& wide, const Query& q, Hit& hit) {
    const L8 origin[3] = {L8::splat(q.o[0]), L8::splat(q.o[1]), L8::splat(q.o[2])};
    const L8 inv[3] = {L8::splat(q.inv[0]), L8::splat(q.inv[1]), L8::splat(q.inv[2])};
    int near[3];  // float offset of the near plane array of each axis in a WideNode (lo_x = 0, hi_x = 8, ...)
    for (int a = 0; a < 3; ++a) near[a] = 16 * a + (std::signbit(q.inv[a]) ? 8 : 0);
    Entry stack[7 * gpu::MAX_TREE_HEIGHT + 8];
    std::uint32_t sp = 0, visited = 0;
    Entry cur{0, 0, q.tmin};
    for (;;) {
        if (cur.count) {
            test_leaf(wide, cur.index, cur.count, q, hit);
        } else {
            ++visited;
            Entry hits[8];
            const int h = enter_children(wide.nodes[cur.index], origin, inv, near, q.tmin, hit, hits);
            if (h) {
                for (int k = 0; k < h - 1; ++k) stack[sp++] = hits[k];
                cur = hits[h - 1];
                continue;
            }
        }
        do {  // pop, skipping entries farther than the closest hit so far
            if (sp == 0) return visited;
            --sp;
        } while (stack[sp].t > hit.t);
        cur = stack[sp];
    }
}

}  // namespace

Hit intersect_wide_kernel(const WideView& wide, const Ray& ray, std::uint32_t* nodes_visited) {
    Hit hit{ray.tmax, kNoHit, 0.0f, 0.0f, kNoHit};
    Query q{{ray.origin.x, ray.origin.y, ray.origin.z}, {ray.dir.x, ray.dir.y, ray.dir.z},
            {1.0f / ray.dir.x, 1.0f / ray.dir.y, 1.0f / ray.dir.z}, ray.tmin};
    std::uint32_t visited = 0;
    if (wide.root_packets) test_leaf(wide, 0, wide.root_packets, q, hit);
    else if (wide.nodes) visited = traverse_nodes(wide, q, hit);
    if (nodes_visited) *nodes_visited = visited;
    return hit;
}
