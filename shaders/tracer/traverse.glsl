// traverse.glsl — BVH traversal over the flattened depth-first nodes (report §2.2, §3.1), with a
// fixed-size stack or stackless via skip indices (TRAVERSAL, a specialization constant on the
// GPU). One loop serves closest-hit queries and shadow rays. Shared code: see geometry.glsl.

struct Hit {
    float t;        ///< closest-hit: distance so far; shadow: the end of the segment
    uint ref;       ///< primitive reference, NO_HIT when nothing was hit
    float u;        ///< triangle barycentrics
    float v;
    float transmission;  ///< shadow rays: product of the transparencies crossed (report §2.1)
    uint visited;   ///< box tests, for the heatmap
};

Hit empty_hit(float tmax) {
    Hit h;
    h.t = tmax;
    h.ref = NO_HIT;
    h.u = 0.0f;
    h.v = 0.0f;
    h.transmission = 1.0f;
    h.visited = 0u;
    return h;
}

/// The closest-hit rule (the same as closer_hit in core_cpp/include/bvhlab/ray.h): nearer, or as
/// near and of a smaller primitive reference (triangles before spheres, then the lower index), so
/// every traversal order picks the same primitive when distances tie.
bool closer(float t, uint ref, Hit hit) {
    return t < hit.t || (t == hit.t && hit.ref != NO_HIT && ref < hit.ref);
}

uint material_of(uint ref) {
    if ((ref & REF_SPHERE_BIT) != 0u) return load_sphere(ref & REF_INDEX_MASK).material.x;
    return floatBitsToUint(load_triangle(ref).v0.w);
}

/// The primitives of a leaf. Closest-hit keeps the nearest; a shadow ray multiplies its
/// transmission by the transparent factor of every surface it crosses (a sphere can be crossed
/// twice). Returns true when traversal may stop (a shadow ray that is fully blocked).
bool visit_leaf(BvhNode n, TraceRay r, bool shadow, INOUT(Hit) hit) {
    for (uint k = n.index; k < n.index + n.info; ++k) {
        uint ref = load_ref(k);
        uint crossings = 0u;
        if ((ref & REF_SPHERE_BIT) != 0u) {
            GpuSphere s = load_sphere(ref & REF_INDEX_MASK);
            float t;
            if (shadow) crossings = sphere_crossings(s, r, hit.t);
            else if (hit_sphere(s, r, hit.t, t) && closer(t, ref, hit)) { hit.t = t; hit.ref = ref; }
        } else {
            vec3 tuv;
            if (hit_triangle(load_triangle(ref), r, hit.t, tuv)) {
                if (shadow) crossings = tuv.x < hit.t ? 1u : 0u;
                else if (closer(tuv.x, ref, hit)) { hit.t = tuv.x; hit.u = tuv.y; hit.v = tuv.z; hit.ref = ref; }
            }
        }
        if (crossings > 0u) {
            float transparent = load_material(material_of(ref)).transparent_ior.x;
            hit.transmission *= crossings == 2u ? transparent * transparent : transparent;
            if (hit.transmission <= 0.0f) return true;
        }
    }
    return false;
}

/// Depth first with a stack of MAX_TREE_HEIGHT entries: both children's boxes are tested, the
/// nearer is entered and the farther pushed with its entry distance (dropped if a closer hit
/// is found meanwhile).
void traverse_stack(TraceRay r, bool shadow, INOUT(Hit) hit) {
    uint stack_node[MAX_TREE_HEIGHT];
    float stack_t[MAX_TREE_HEIGHT];
    uint sp = 0u;
    BvhNode root = load_node(0u);
    hit.visited += 1u;
    if (box_entry(root.lo, root.hi, r, hit.t) < 0.0f) return;
    uint i = 0u;
    BvhNode n = root;
    // "while-while" (Aila and Laine 2009): descend through inner nodes in one loop, then handle
    // the leaf, so SIMD lanes at different kinds of node run fewer masked-off instructions.
    for (;;) {
        bool dead_end = false;
        while ((n.info & NODE_INTERNAL_BIT) != 0u && !dead_end) {
            uint a = i + 1u;
            uint b = n.index;
            BvhNode na = load_node(a);
            BvhNode nb = load_node(b);
            float ta = box_entry(na.lo, na.hi, r, hit.t);
            float tb = box_entry(nb.lo, nb.hi, r, hit.t);
            hit.visited += 2u;
            if (ta >= 0.0f && tb >= 0.0f) {
                bool b_first = tb < ta;
                stack_node[sp] = b_first ? a : b;
                stack_t[sp] = b_first ? ta : tb;
                sp += 1u;
                i = b_first ? b : a;
                n = load_node(i);
            } else if (ta >= 0.0f || tb >= 0.0f) {
                i = ta >= 0.0f ? a : b;
                n = load_node(i);
            } else {
                dead_end = true;
            }
        }
        if (!dead_end && visit_leaf(n, r, shadow, hit)) return;
        // pop, skipping entries farther than the closest hit so far
        bool popped = false;
        while (sp > 0u && !popped) {
            sp -= 1u;
            popped = stack_t[sp] <= hit.t;
            i = stack_node[sp];
        }
        if (!popped) return;
        n = load_node(i);
    }
}

/// Stackless (report §3.1): nodes in depth-first order; a missed box continues at its skip
/// index, the first node after its subtree; a leaf's skip index is the next node.
void traverse_stackless(TraceRay r, bool shadow, INOUT(Hit) hit) {
    uint count = node_count();
    uint i = 0u;
    while (i < count) {
        BvhNode n = load_node(i);
        bool leaf = (n.info & NODE_INTERNAL_BIT) == 0u;
        hit.visited += 1u;
        if (box_entry(n.lo, n.hi, r, hit.t) < 0.0f) {
            i = leaf ? i + 1u : (n.info & NODE_SKIP_MASK);
            continue;
        }
        if (leaf && visit_leaf(n, r, shadow, hit)) return;
        i += 1u;
    }
}

void traverse(TraceRay r, bool shadow, INOUT(Hit) hit) {
    if (node_count() == 0u) return;
    if (TRAVERSAL == TRAVERSAL_STACKLESS) traverse_stackless(r, shadow, hit);
    else traverse_stack(r, shadow, hit);
}

/// Closest hit in (r.tmin, tmax).
Hit closest_hit(TraceRay r, float tmax) {
    Hit hit = empty_hit(tmax);
    traverse(r, false, hit);
    return hit;
}

/// Light let through along r up to `dist`: the product of the transparencies of every surface
/// crossed (report §2.1; refraction is not taken into account, as in the report).
float shadow_transmission(TraceRay r, float dist) {
    Hit hit = empty_hit(dist);
    traverse(r, true, hit);
    return hit.transmission;
}
