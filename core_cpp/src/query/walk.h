// walk.h — the two binary-tree walks (report §2.2, §3.1), written once over a leaf callback: the
// flat traversals test a leaf's primitives, the two-level one a leaf's instances (tlas.h); an
// optional box callback lets the inspector record every box test (ray_record.h). The same walks
// answer closest-hit and any-hit queries (occluded): an any-hit leaf callback returns bool, true
// ending the walk at the first hit (ends_walk).
#pragma once
#include <cstdint>
#include <type_traits>
#include <utility>

#include "bvhlab/bvh.h"
#include "bvhlab/ray.h"

namespace bvhlab::walk {

/// The box-test callback of a walk that reports nothing (every query but the inspector's records,
/// ray_record.h): on_box(node, entered) is called for each box test, in order.
struct NoBoxes {
    void operator()(std::uint32_t, bool) const {}
};

/// Tests leaf `n`; true when the walk is to end there. A closest-hit leaf callback returns nothing
/// and never ends the walk (this compiles to the call alone); an any-hit one returns true once it
/// has found a hit, which answers the query (Embree's rtcOccluded1, tinybvh's IsOccluded).
template <class TestLeaf>
bool ends_walk(TestLeaf& test_leaf, const BvhNode& n) {
    if constexpr (std::is_void_v<decltype(test_leaf(n))>) {
        test_leaf(n);
        return false;
    } else {
        return test_leaf(n);
    }
}

/// Ordered depth-first walk: test both children's boxes, descend into the nearer, push the farther
/// with its entry distance so it is dropped if a closer hit is found meanwhile. `hit_t` is the
/// closest hit so far, lowered by `test_leaf(node)`. Returns the box tests. `q` is a RayQuery, or
/// a query with its own hit_box(node, q, tmax, t_enter) computing what ray.h's does (the TLAS's,
/// traverse_two_level.cpp).
template <class Query, class TestLeaf, class OnBox = NoBoxes>
std::uint32_t stack(const BvhNode* nodes, const Query& q, const float& hit_t, TestLeaf&& test_leaf,
                    OnBox&& on_box = OnBox{}) {
    struct Entry {
        std::uint32_t node;
        float t;
    };
    Entry stack[gpu::MAX_TREE_HEIGHT];
    std::uint32_t sp = 0, visited = 1, i = 0;
    float t_root;
    const bool hit_root = hit_box(nodes[0], q, hit_t, t_root);
    on_box(0u, hit_root);
    if (!hit_root) return visited;
    for (;;) {
        const BvhNode& n = nodes[i];
        if (is_leaf(n)) {
            if (ends_walk(test_leaf, n)) return visited;
        } else {
            std::uint32_t a = i + 1, b = n.index;
            float ta, tb;
            bool hit_a = hit_box(nodes[a], q, hit_t, ta), hit_b = hit_box(nodes[b], q, hit_t, tb);
            visited += 2;
            on_box(a, hit_a), on_box(b, hit_b);
            if (hit_a && hit_b) {
                if (tb < ta) std::swap(a, b), std::swap(ta, tb);
                stack[sp++] = {b, tb};
                i = a;
                continue;
            }
            if (hit_a || hit_b) {
                i = hit_a ? a : b;
                continue;
            }
        }
        do {  // pop, skipping entries farther than the closest hit so far
            if (sp == 0) return visited;
            --sp;
        } while (!may_hold_closer(stack[sp].t, hit_t));
        i = stack[sp].node;
    }
}

/// Stackless walk (report §3.1): nodes in depth-first order; a missed box jumps to its skip index,
/// the first node after its subtree. `q` as for stack().
template <class Query, class TestLeaf, class OnBox = NoBoxes>
std::uint32_t stackless(const BvhNode* nodes, std::uint32_t count, const Query& q, const float& hit_t,
                        TestLeaf&& test_leaf, OnBox&& on_box = OnBox{}) {
    std::uint32_t visited = 0;
    for (std::uint32_t i = 0; i < count;) {
        const BvhNode& n = nodes[i];
        float t;
        ++visited;
        const bool entered = hit_box(n, q, hit_t, t);
        on_box(i, entered);
        if (!entered) {
            i = skip_index(n, i);
            continue;
        }
        if (is_leaf(n) && ends_walk(test_leaf, n)) return visited;
        ++i;
    }
    return visited;
}

}  // namespace bvhlab::walk
