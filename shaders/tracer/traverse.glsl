// traverse.glsl — BVH traversal of the flattened depth-first tree (report §2.2, §3.1), with a
// stack over its internal nodes as pairs of child boxes (BvhPair), or stackless over its nodes via
// skip indices (TRAVERSAL, a specialization constant on the GPU; the CPU tracer's TRAVERSAL_WIDE
// answers a query by the 8-wide tree where it can, and walks as the stack walk where not), written
// as a resumable walk: each step does one bounded unit of work (a node, a primitive or a pop) and
// the walk's whole state lives in a Walk, so a trace can stop after any step and continue in the
// next dispatch (issue 8: lavapipe stops long loops, GPUs have a watchdog). One walk serves
// closest-hit queries and shadow rays. Shared code: see geometry.glsl.
//
// Two-level scenes (issue 34; docs/design.md "Two-level trees") walk the TLAS the same way; a TLAS
// leaf holds one instance (default_tlas_config), whose BLAS is walked in the same Walk with the ray
// moved into the instance's object space (WALK_INSTANCE), then the TLAS walk goes on (WALK_RETURN):
// the stack walk pushes the BLAS's entries above the TLAS's, the stackless one resumes at the node
// after the instance's leaf. Every tree lives in one forest (the scene's node, pair and primitive
// arrays), its indices moved to its place there, so the steps are those of a flat tree.
//
// Traversal counters (issue 35, Hit::counts): box tests always (the heatmap's cost); box hits,
// primitive tests and hits and instance hits where COUNT_TRAVERSAL (trace.comp: always; the CPU
// reference: only in renders that keep them, so the others run the walk of before).

struct Hit {
    float t;        ///< closest-hit: distance so far; shadow: the end of the segment
    uint ref;       ///< primitive reference, NO_HIT when nothing was hit
    uint instance;  ///< two-level: the instance slot (GpuInstance) of the hit; NO_INSTANCE otherwise
    float u;        ///< triangle barycentrics
    float v;
    float transmission;  ///< shadow rays: product of the transparencies crossed (report §2.1)
    TraversalCounts counts;  ///< what this walk tested (issue 35; a pixel keeps its primary ray's)
};

TraversalCounts no_counts() {
    TraversalCounts c;
    c.box_tests = 0u;
    c.box_hits = 0u;
    c.prim_tests = 0u;
    c.prim_hits = 0u;
    c.instance_hits = 0u;
    return c;
}

Hit empty_hit(float tmax) {
    Hit h;
    h.t = tmax;
    h.ref = NO_HIT;
    h.instance = NO_INSTANCE;
    h.u = 0.0f;
    h.v = 0.0f;
    h.transmission = 1.0f;
    h.counts = no_counts();
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
    return load_triangle(ref).material;
}

/// Whether a ray of `kind` (a RAY_* bit) sees the primitive `ref`: not where its material hides from
/// that kind (Cycles' Object ▸ Visibility ▸ Ray Visibility; the material's hidden bits); such a
/// surface is passed through as if it were not there. Asked only of a hit, and only where some
/// material hides (frame.hidden_materials).
bool sees(uint ref, uint kind) {
    return frame.hidden_materials == 0u || (uint(load_material(material_of(ref)).transparent_ior.w) & kind) == 0u;
}

/// One primitive of a leaf, as the tree keeps it in leaf order (Bvh::prims: a triangle's vertices,
/// or a sphere's centre in v0 and radius in v1.x, its reference in `ref`), so a leaf's primitives
/// are read in one run with no reference to follow to the scene's arrays (the leaf layout of Aila
/// and Laine 2009). Closest-hit keeps the nearest; a shadow ray multiplies its transmission by the
/// transparent factor of every surface it crosses (a sphere can be crossed twice). Returns true
/// when the walk may stop (a shadow ray that is fully blocked).
/// `kind`: the ray's RAY_* bit (RAY_SHADOW: a shadow ray); a primitive whose material hides from it
/// is not hit (sees). `instance`: the instance slot whose BLAS holds the primitive (NO_INSTANCE in a
/// flat scene).
bool visit_primitive(GpuTriangle p, TraceRay r, uint kind, uint instance, INOUT(Hit) hit) {
    bool shadow = kind == RAY_SHADOW;
    uint crossings = 0u;
    if ((p.ref & REF_SPHERE_BIT) != 0u) {
        float t;
        if (shadow) crossings = sphere_crossings(p.v0, p.v1.x, r, hit.t);
        else if (hit_sphere(p.v0, p.v1.x, r, hit.t, t) && closer(t, p.ref, hit) && sees(p.ref, kind)) { hit.t = t; hit.ref = p.ref; hit.instance = instance; if (COUNT_TRAVERSAL) hit.counts.prim_hits += 1u; }
    } else {
        vec3 tuv;
        if (hit_triangle(p.v0, p.v1, p.v2, r, hit.t, tuv)) {
            if (shadow) crossings = tuv.x < hit.t ? 1u : 0u;
            else if (closer(tuv.x, p.ref, hit) && sees(p.ref, kind)) { hit.t = tuv.x; hit.u = tuv.y; hit.v = tuv.z; hit.ref = p.ref; hit.instance = instance; if (COUNT_TRAVERSAL) hit.counts.prim_hits += 1u; }
        }
    }
    if (crossings == 0u || !sees(p.ref, RAY_SHADOW)) return false;
    float transparent = load_material(material_of(p.ref)).transparent_ior.x;
    hit.transmission *= crossings == 2u ? transparent * transparent : transparent;
    return hit.transmission <= 0.0f;
}

// Where a walk stands (TraceState::walk).
LOCAL_CONST uint WALK_ROOT = 0u;      ///< stack traversal: the root's box is still to be tested
LOCAL_CONST uint WALK_NODE = 1u;      ///< stackless: test node `node`'s box; stack: pair `node`'s two boxes
LOCAL_CONST uint WALK_LEAF = 2u;      ///< testing primitives leaf_next .. leaf_end - 1 of a leaf
LOCAL_CONST uint WALK_POP = 3u;       ///< stack traversal: take the next entry off the stack
LOCAL_CONST uint WALK_FINISHED = 4u;  ///< the query is answered
LOCAL_CONST uint WALK_INSTANCE = 5u;  ///< two-level: enter the instance in slot leaf_next (a TLAS leaf's)
LOCAL_CONST uint WALK_RETURN = 6u;    ///< two-level: the instance's BLAS is done: back to the TLAS

/// The state of a query in progress; the traversal stack itself lives in the slot's storage
/// (node_stack_load/store), `stacked` entries of it.
struct Walk {
    uint state;      ///< WALK_*
    uint node;       ///< stackless: a node (BvhNode); stack: a pair (BvhPair)
    uint stacked;    ///< entries on the traversal stack
    uint leaf_next;
    uint leaf_end;
    uint instance;   ///< two-level: the instance slot whose BLAS is walked; NO_INSTANCE: the top level
    uint outer;      ///< in an instance: stack walk, the TLAS's entries below the BLAS's (0 at the top
                     ///< level: the stack's floor); stackless, the TLAS node after the instance's leaf
};

Walk start_walk() {
    Walk w;
    w.state = node_count() == 0u ? WALK_FINISHED : (TRAVERSAL == TRAVERSAL_STACKLESS ? WALK_NODE : WALK_ROOT);
    w.node = 0u;
    w.stacked = 0u;
    w.leaf_next = 0u;
    w.leaf_end = 0u;
    w.instance = NO_INSTANCE;
    w.outer = 0u;
    return w;
}

/// A leaf of a two-level scene's TLAS names an instance to enter; any other leaf has primitives.
void enter_leaf(INOUT(Walk) w, uint first, uint count) {
    w.leaf_next = first;
    w.leaf_end = first + count;
    w.state = two_level() && w.instance == NO_INSTANCE ? WALK_INSTANCE : WALK_LEAF;
}

/// Where the walk's current tree lies: its root node and pair, and the end of its nodes (the
/// stackless walk stops there). The ray in its space is walk()'s `r`.
struct Level {
    uint root;
    uint root_pair;
    uint end;
};

Level top_level() {
    Level l;
    l.root = 0u;
    l.root_pair = 0u;
    l.end = node_count();
    return l;
}

/// A direction moved by an instance's world-to-object transform (its 3×3 part L).
vec3 object_vector(GpuInstance inst, vec3 d) {
    return vec3(dot(xyz(inst.row0), d), dot(xyz(inst.row1), d), dot(xyz(inst.row2), d));
}

/// A point moved by an instance's world-to-object transform, relative to the object's origin in
/// the world (GpuInstance: L·(p - P)), as rays enter it and shading finds points in it.
vec3 object_point(GpuInstance inst, vec3 p) {
    return object_vector(inst, p - vec3(inst.row0.w, inst.row1.w, inst.row2.w));
}

/// An instance's BLAS; `ray` goes from world space into the instance's object space: origin and
/// direction by the world-to-object transform (the origin relative to the object's, ObjectMap in
/// transform.h), the direction left unnormalised so that t is the
/// same number in both spaces (as the CPU queries do: core_cpp/src/query/traverse_two_level.cpp).
Level instance_level(uint slot, INOUT(TraceRay) ray) {
    GpuInstance inst = load_instance(slot);
    ray = make_ray(object_point(inst, ray.origin), object_vector(inst, ray.dir), ray.tmin);
    Level l;
    l.root = inst.tree.x;
    l.end = inst.tree.y;
    l.root_pair = inst.tree.z;
    return l;
}

/// Two-level: enters the instance of the TLAS leaf reached (WALK_INSTANCE) at its BLAS's root, or,
/// when that BLAS is done (WALK_RETURN), goes on with the TLAS where it left it, the world ray made
/// again from its origin and direction (make_ray gives the same ray for the same numbers).
void change_level(INOUT(Walk) w, INOUT(TraceRay) ray, vec3 world_origin, vec3 world_dir, INOUT(Level) level) {
    bool stackless = TRAVERSAL == TRAVERSAL_STACKLESS;
    if (w.state == WALK_INSTANCE) {
        w.instance = w.leaf_next;
        w.outer = stackless ? w.node + 1u : w.stacked;
        level = instance_level(w.instance, ray);
        w.node = level.root;
        w.state = stackless ? WALK_NODE : WALK_ROOT;
    } else {
        w.node = w.outer;
        w.state = stackless ? WALK_NODE : WALK_POP;
        w.instance = NO_INSTANCE;
        w.outer = 0u;
        ray = make_ray(world_origin, world_dir, ray.tmin);
        level = top_level();
    }
}

/// The walk of the current tree is over: the query's, or (two-level) only the instance's.
uint walk_done(Walk w) { return w.instance == NO_INSTANCE ? WALK_FINISHED : WALK_RETURN; }

/// The stack walk goes on with a child of a pair: an internal one's pair is visited next, a leaf's
/// primitives are tested.
void enter_child(INOUT(Walk) w, uint child, uint count) {
    if ((child & PAIR_LEAF_BIT) != 0u) {
        enter_leaf(w, child & ~PAIR_LEAF_BIT, count);
    } else {
        w.node = child;
        w.state = WALK_NODE;
    }
}

/// enter_child of pair `p`'s first child, or its second where `second`.
void enter_side(INOUT(Walk) w, BvhPair p, bool second) {
    enter_child(w, second ? p.child_b : p.child_a, second ? p.count_b : p.count_a);
}

/// Stack traversal at pair `w.node`: both children's boxes come in one fetch; the nearer child is
/// entered and the farther pushed with its entry distance (dropped at the pop if a closer hit is
/// found meanwhile). A pushed leaf is named by its parent and side (PAIR_LEAF_BIT | 2 · pair +
/// side): a stack entry has no room for a leaf's range, and the pop reads it from the parent.
void step_stack_node(INOUT(Walk) w, TraceRay r, INOUT(Hit) hit) {
    BvhPair p = load_pair(w.node);
    float ta = box_entry(p.lo_a, p.hi_a, r, hit.t);
    float tb = box_entry(p.lo_b, p.hi_b, r, hit.t);
    hit.counts.box_tests += 2u;
    if (COUNT_TRAVERSAL) hit.counts.box_hits += uint(ta >= 0.0f) + uint(tb >= 0.0f);
    if (ta < 0.0f && tb < 0.0f) {
        w.state = WALK_POP;
        return;
    }
    bool b_next = ta < 0.0f || (tb >= 0.0f && tb < ta);
    if (ta >= 0.0f && tb >= 0.0f) {
        uint far_child = b_next ? p.child_a : p.child_b;
        uint far_leaf = PAIR_LEAF_BIT | (2u * w.node + (b_next ? 0u : 1u));
        uint far_entry = (far_child & PAIR_LEAF_BIT) != 0u ? far_leaf : far_child;
        node_stack_store(w.stacked, uvec2(far_entry, floatBitsToUint(b_next ? ta : tb)));
        w.stacked += 1u;
    }
    enter_side(w, p, b_next);
}

/// Stackless (report §3.1) at node `node` of the depth-first order: a missed box continues at
/// its skip index, the first node after its subtree; a leaf's skip index is the next node.
void step_stackless_node(INOUT(Walk) w, TraceRay r, uint end, INOUT(Hit) hit) {
    if (w.node >= end) {
        w.state = walk_done(w);
        return;
    }
    BvhNode n = load_node(w.node);
    bool leaf = (n.info & NODE_INTERNAL_BIT) == 0u;
    bool entered = box_entry(n.lo, n.hi, r, hit.t) >= 0.0f;
    hit.counts.box_tests += 1u;
    if (COUNT_TRAVERSAL) hit.counts.box_hits += uint(entered);
    if (!entered) w.node = leaf ? w.node + 1u : (n.info & NODE_SKIP_MASK);
    else if (leaf) enter_leaf(w, n.index, n.info);
    else w.node += 1u;
}

/// The next primitive of the leaf; after the last, the stack traversal pops and the stackless
/// one goes on with the next node in depth-first order.
void step_leaf(INOUT(Walk) w, TraceRay r, uint kind, INOUT(Hit) hit) {
    GpuTriangle p = load_leaf_prim(w.leaf_next);
    w.leaf_next += 1u;
    if (COUNT_TRAVERSAL) hit.counts.prim_tests += 1u;
    if (visit_primitive(p, r, kind, w.instance, hit)) w.state = WALK_FINISHED;
    else if (w.leaf_next >= w.leaf_end) {
        w.state = TRAVERSAL == TRAVERSAL_STACKLESS ? WALK_NODE : WALK_POP;
        w.node += 1u;  // stackless: past the leaf; the stack walk reads `node` only once a pop sets it
    }
}

/// Takes one entry off the stack; an entry farther than the closest hit so far is dropped. A
/// leaf's entry names its parent pair and side, whose words hold the leaf's range. The current
/// tree's entries end at `outer` (two-level: the TLAS's lie below an instance's).
void step_pop(INOUT(Walk) w, Hit hit) {
    if (w.stacked == w.outer) {
        w.state = walk_done(w);
        return;
    }
    w.stacked -= 1u;
    uvec2 entry = node_stack_load(w.stacked);
    if (uintBitsToFloat(entry.y) > hit.t * BOX_FAR_SCALE) return;  // as conservative as box_entry (Ize 2013)
    if ((entry.x & PAIR_LEAF_BIT) == 0u) {
        enter_child(w, entry.x, 0u);
        return;
    }
    enter_side(w, load_pair((entry.x & ~PAIR_LEAF_BIT) >> 1u), (entry.x & 1u) != 0u);
}

/// The walk, until the query is answered or `steps` reaches `budget`, as "while-while" loops
/// (Aila and Laine 2009: descend through inner nodes in one loop, test a leaf's primitives in
/// another, pop in a third, so SIMD lanes at different kinds of work run fewer masked-off
/// instructions). Every loop iteration counts one step; after each inner loop the lanes take the
/// largest count among them (sync_steps), plus one for the loop's exit. So `steps` never falls
/// below the iterations the SIMD vector ran, which is what lavapipe's loop limit counts (see
/// MAX_STEPS_PER_DISPATCH), and a walk cut short by the budget continues from `w` later. `work`
/// counts this lane's own steps (a node, a primitive, a pop; two-level: entering or leaving an
/// instance). `r` is the world ray; `kind` its RAY_* bit (RAY_SHADOW: a shadow ray, which multiplies
/// the transmissions it crosses; the others find the closest hit they see).
void walk(INOUT(Walk) walk_state, TraceRay r, uint kind, INOUT(Hit) query, INOUT(uint) work, INOUT(uint) steps,
          uint budget) {
#ifdef __cplusplus
    // The CPU tracer's wide walk (cpu_tracer.h): the whole query at once, the same hit; asked once
    // a query, where it starts (a query it leaves to the stack walk goes on there in later budgets).
    if (TRAVERSAL == TRAVERSAL_WIDE && steps < budget && walk_state.state == WALK_ROOT &&
        walk_state.instance == NO_INSTANCE && wide_walk(walk_state, r, kind, query, work, steps))
        return;
#endif
    Walk w = walk_state;  // locals: the CPU build keeps them in registers (the state may alias the slot)
    Hit hit = query;
    vec3 world_origin = r.origin;  // `r` is the current tree's ray: the world's, or an instance's
    vec3 world_dir = r.dir;
    Level level = top_level();
    if (w.instance != NO_INSTANCE) level = instance_level(w.instance, r);
    while (w.state != WALK_FINISHED && steps < budget) {
        steps += 1u;
        if (w.state >= WALK_INSTANCE) {  // two-level only
            if (COUNT_TRAVERSAL) hit.counts.instance_hits += uint(w.state == WALK_INSTANCE);
            change_level(w, r, world_origin, world_dir, level);
            steps += 1u;
            work += 1u;
        }
        if (w.state == WALK_ROOT) {  // the stack walk tests the root's box, then enters its pair or the root leaf
            BvhNode root = load_node(level.root);
            bool entered = box_entry(root.lo, root.hi, r, hit.t) >= 0.0f;
            hit.counts.box_tests += 1u;
            if (COUNT_TRAVERSAL) hit.counts.box_hits += uint(entered);
            if (!entered) w.state = walk_done(w);
            else if ((root.info & NODE_INTERNAL_BIT) == 0u) enter_leaf(w, root.index, root.info);
            else enter_child(w, level.root_pair, 0u);
            steps += 1u;
            work += 1u;
        }
        while (w.state == WALK_NODE && steps < budget) {
            steps += 1u;
            work += 1u;
            if (TRAVERSAL == TRAVERSAL_STACKLESS) step_stackless_node(w, r, level.end, hit);
            else step_stack_node(w, r, hit);
        }
        steps = sync_steps(steps) + 1u;
        while (w.state == WALK_LEAF && steps < budget) {
            steps += 1u;
            work += 1u;
            step_leaf(w, r, kind, hit);
        }
        steps = sync_steps(steps) + 1u;
        while (w.state == WALK_POP && steps < budget) {
            steps += 1u;
            work += 1u;
            step_pop(w, hit);
        }
        steps = sync_steps(steps) + 1u;
    }
    walk_state = w;
    query = hit;
}
