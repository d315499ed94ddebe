// Closest-hit traversal of the 4-wide tree: four slab tests per SSE instruction sequence, the
// near plane of each axis chosen once per ray from the sign of the direction (no min/max), with
// the same closed faces as hit_box (ray.h).
#include <emmintrin.h>

#include "bvhlab/traverse.h"
#include "bvhlab/wide_bvh.h"

namespace bvhlab {
namespace {

void test_leaf(const Bvh& bvh, std::uint32_t first, std::uint32_t count, const RayQuery& q, Hit& hit) {
    for (std::uint32_t k = first, end = first + count; k < end; ++k)
        if (hit_prim(bvh.prims[k], q, hit)) hit.slot = k;
}

struct Entry {
    std::uint32_t node, count;  // count > 0: a leaf
    float t;
};

}  // namespace

Hit intersect_wide(const WideBvh& wide, const Bvh& bvh, const Ray& ray, std::uint32_t* nodes_visited) {
    Hit hit;
    hit.t = ray.tmax;
    std::uint32_t visited = 0;
    RayQuery q(ray);
    if (wide.root_leaf_count) {
        test_leaf(bvh, 0, wide.root_leaf_count, q, hit);
    } else if (!wide.nodes.empty()) {
        // offsets of the near and far arrays of each axis inside a WideNode (in floats)
        const int nx = q.inv_dir.x >= 0 ? 0 : 4, ny = q.inv_dir.y >= 0 ? 8 : 12, nz = q.inv_dir.z >= 0 ? 16 : 20;
        const int fx = nx ^ 4, fy = ny ^ 4, fz = nz ^ 4;
        const __m128 ox = _mm_set1_ps(q.origin.x), oy = _mm_set1_ps(q.origin.y), oz = _mm_set1_ps(q.origin.z);
        const __m128 ix = _mm_set1_ps(q.inv_dir.x), iy = _mm_set1_ps(q.inv_dir.y), iz = _mm_set1_ps(q.inv_dir.z);
        const __m128 tmin = _mm_set1_ps(q.tmin);
        Entry stack[4 * gpu::MAX_TREE_HEIGHT];
        std::uint32_t sp = 0;
        Entry cur{0, 0, q.tmin};
        for (;;) {
            if (cur.count) {
                test_leaf(bvh, cur.node, cur.count, q, hit);
            } else {
                const WideNode& n = wide.nodes[cur.node];
                const float* f = n.lo_x;
                ++visited;
                __m128 tnx = _mm_mul_ps(_mm_sub_ps(_mm_load_ps(f + nx), ox), ix);
                __m128 tny = _mm_mul_ps(_mm_sub_ps(_mm_load_ps(f + ny), oy), iy);
                __m128 tnz = _mm_mul_ps(_mm_sub_ps(_mm_load_ps(f + nz), oz), iz);
                __m128 tfx = _mm_mul_ps(_mm_sub_ps(_mm_load_ps(f + fx), ox), ix);
                __m128 tfy = _mm_mul_ps(_mm_sub_ps(_mm_load_ps(f + fy), oy), iy);
                __m128 tfz = _mm_mul_ps(_mm_sub_ps(_mm_load_ps(f + fz), oz), iz);
                // maxps/minps return their second operand when either is NaN: with the plane
                // distances first, the NaN of a ray lying in a face (0·inf) is ignored, as in hit_box.
                __m128 tnear = _mm_max_ps(tnz, _mm_max_ps(tny, _mm_max_ps(tnx, tmin)));
                __m128 tfar = _mm_min_ps(tfz, _mm_min_ps(tfy, _mm_min_ps(tfx, _mm_set1_ps(hit.t))));
                int mask = _mm_movemask_ps(_mm_cmple_ps(tnear, tfar));
                if (mask) {
                    alignas(16) float t[4];
                    _mm_store_ps(t, tnear);
                    // nearest hit child next; the others onto the stack, farthest deepest
                    Entry hits[4];
                    int h = 0;
                    for (int k = 0; k < 4; ++k)
                        if (mask & (1 << k)) {
                            Entry e{n.child[k], n.count[k], t[k]};
                            int j = h++;
                            for (; j > 0 && hits[j - 1].t < e.t; --j) hits[j] = hits[j - 1];
                            hits[j] = e;  // sorted by decreasing t
                        }
                    for (int k = 0; k < h - 1; ++k) stack[sp++] = hits[k];
                    cur = hits[h - 1];
                    continue;
                }
            }
            do {  // pop, skipping entries farther than the closest hit so far
                if (sp == 0) goto done;
                --sp;
            } while (stack[sp].t > hit.t);
            cur = stack[sp];
        }
    }
done:
    if (hit.ref == kNoHit) hit.t = kInfinity;
    finish_hit(bvh, ray, hit);
    if (nodes_visited) *nodes_visited = visited;
    return hit;
}

}  // namespace bvhlab
