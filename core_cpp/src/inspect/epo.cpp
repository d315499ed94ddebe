// epo.cpp — end-point overlap per node (Aila, Karras and Laine 2013, eq. 3; node_data.h).
//
// Each triangle walks down from the root through the boxes it overlaps: a box that holds none of
// it holds none below (children lie inside their parent), so the walk stops there. Where the box
// is not an ancestor of the triangle's leaf, the clipped area is that node's overlap. Sums are in
// fixed point (units of A(Q)·2^-52), so they do not depend on how the triangles were shared out.
#include <algorithm>
#include <cmath>
#include <cstdint>

#include "bvhlab/node_data.h"
#include "bvhlab/stats.h"
#include "bvhlab/thread_pool.h"
#include "clip_polygon.h"

namespace bvhlab {

namespace {

constexpr double kFixedScale = 4503599627370496.0;  // 2^52: a node's sum is at most A(Q), i.e. 1

}  // namespace

double clipped_triangle_area(const double a[3], const double b[3], const double c[3], const double lo[3],
                             const double hi[3]) {
    ClipPolygon x, y;
    x.n = 3;
    std::copy(a, a + 3, x.p[0]), std::copy(b, b + 3, x.p[1]), std::copy(c, c + 3, x.p[2]);
    for (int axis = 0; axis < 3 && x.n > 0; ++axis) {
        clip(x, y, axis, hi[axis], 1.0);
        clip(y, x, axis, lo[axis], -1.0);
    }
    return x.n >= 3 ? polygon_area(x) : 0.0;
}

double surface_area(const Bvh& bvh) {
    double total = 0;
    for (const PackedPrim& p : bvh.prims) {
        if (p.ref & gpu::REF_SPHERE_BIT) continue;
        const double v[3][3] = {{p.v0.x, p.v0.y, p.v0.z}, {p.v1.x, p.v1.y, p.v1.z}, {p.v2.x, p.v2.y, p.v2.z}};
        double lo[3], hi[3];
        for (int a = 0; a < 3; ++a)
            lo[a] = std::min({v[0][a], v[1][a], v[2][a]}), hi[a] = std::max({v[0][a], v[1][a], v[2][a]});
        total += clipped_triangle_area(v[0], v[1], v[2], lo, hi);  // the same arithmetic as the clips
    }
    return total;
}

std::vector<double> epo_terms(const Bvh& bvh, unsigned threads, Cancellation* cancel) {
    const std::uint32_t count = bvh.node_count();
    std::vector<double> terms(count, 0.0);
    if (count == 0) return terms;
    // The leaf of each slot, and the triangles' total area A(Q).
    std::vector<std::uint32_t> leaf_of_slot(bvh.prims.size());
    for (std::uint32_t i = 0; i < count; ++i)
        if (is_leaf(bvh.nodes[i])) std::fill_n(leaf_of_slot.begin() + bvh.nodes[i].index, leaf_count(bvh.nodes[i]), i);
    auto vertices = [&](std::size_t k, double v[3][3]) {
        const PackedPrim& p = bvh.prims[k];
        const gpu::vec3* src[3] = {&p.v0, &p.v1, &p.v2};
        for (int j = 0; j < 3; ++j) v[j][0] = src[j]->x, v[j][1] = src[j]->y, v[j][2] = src[j]->z;
    };
    auto is_triangle = [&](std::size_t k) { return !(bvh.prims[k].ref & gpu::REF_SPHERE_BIT); };
    const double total_area = surface_area(bvh);
    if (!(total_area > 0)) return terms;

    const unsigned slots = ThreadPool::resolve(threads);
    std::vector<std::vector<std::uint64_t>> sums(slots, std::vector<std::uint64_t>(count, 0));
    // small chunks: a stop is polled before each (a triangle of a soup may clip against thousands
    // of boxes), and a worker looks at the stop before each triangle; sums in fixed point, so the
    // same terms whatever the chunks and threads
    constexpr std::size_t kChunk = 16;
    const std::size_t chunks = (bvh.prims.size() + kChunk - 1) / kChunk;
    const bool finished = ThreadPool::shared().run_until_stopped(
        chunks, slots,
        [&](std::size_t c, unsigned slot) {
            std::vector<std::uint32_t> stack;
            std::uint64_t* sum = sums[slot].data();
            for (std::size_t k = c * kChunk, end = std::min(bvh.prims.size(), k + kChunk); k < end; ++k) {
                if (cancel && cancel->stop_requested()) return;
                if (!is_triangle(k)) continue;
                double v[3][3], t_lo[3], t_hi[3];
                vertices(k, v);
                for (int a = 0; a < 3; ++a)
                    t_lo[a] = std::min({v[0][a], v[1][a], v[2][a]}), t_hi[a] = std::max({v[0][a], v[1][a], v[2][a]});
                const std::uint32_t leaf = leaf_of_slot[k];
                stack.assign(1, 0);
                while (!stack.empty()) {
                    const std::uint32_t i = stack.back();
                    stack.pop_back();
                    const BvhNode& n = bvh.nodes[i];
                    const double lo[3] = {n.lo.x, n.lo.y, n.lo.z}, hi[3] = {n.hi.x, n.hi.y, n.hi.z};
                    const bool ancestor = i <= leaf && leaf < skip_index(n, i);
                    if (!ancestor) {
                        if (t_lo[0] > hi[0] || t_lo[1] > hi[1] || t_lo[2] > hi[2] || t_hi[0] < lo[0] ||
                            t_hi[1] < lo[1] || t_hi[2] < lo[2])
                            continue;  // boxes apart: nothing to clip
                        const double a = clipped_triangle_area(v[0], v[1], v[2], lo, hi);
                        if (a <= 0) continue;  // nothing of it here, nor in the children
                        sum[i] += std::uint64_t(std::llround(a / total_area * kFixedScale));
                    }
                    if (!is_leaf(n)) stack.push_back(n.index), stack.push_back(i + 1);
                }
            }
        },
        cancel);
    if (!finished || (cancel && cancel->stop_requested())) throw Cancelled();
    for (std::uint32_t i = 0; i < count; ++i) {
        std::uint64_t s = 0;
        for (const auto& part : sums) s += part[i];
        const double cost = is_leaf(bvh.nodes[i]) ? double(leaf_count(bvh.nodes[i])) : 1.0;  // as sah_term
        terms[i] = cost * (double(s) / kFixedScale);
    }
    return terms;
}

}  // namespace bvhlab
