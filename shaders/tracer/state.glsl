// state.glsl — a suspended trace (TraceState, shade.glsl) saved to a slot's STATE_WORDS words and
// loaded back bit for bit, so a trace continued in another dispatch computes what it would have
// computed without the pause. Shared code (see geometry.glsl): the CPU reference saves and loads
// through the same functions between its budgets of steps.

uvec4 word3(vec3 v, uint w) { return uvec4(floatBitsToUint(v.x), floatBitsToUint(v.y), floatBitsToUint(v.z), w); }
vec3 vec3_of(uvec4 w) { return vec3(uintBitsToFloat(w.x), uintBitsToFloat(w.y), uintBitsToFloat(w.z)); }

/// `stamp` marks the state as this tile's and pass's (slot_stamp), so a slot left by an earlier
/// tile or pass is never taken for this one.
void save_state(TraceState s, uint stamp) {
    state_store(0u, uvec4(s.pixel.x, s.pixel.y, s.phase, s.sample_index));
    state_store(1u, uvec4(s.target, s.rays, s.walk.state, s.walk.node));
    state_store(2u, uvec4(s.walk.stacked, s.walk.leaf_next, s.walk.leaf_end, stamp));
    state_store(3u, word3(s.ray.origin, floatBitsToUint(s.ray.tmin)));
    state_store(4u, word3(s.ray.dir, floatBitsToUint(s.hit.t)));
    state_store(5u, uvec4(s.hit.ref, floatBitsToUint(s.hit.u), floatBitsToUint(s.hit.v), floatBitsToUint(s.hit.transmission)));
    state_store(6u, uvec4(s.hit.counts.box_tests, floatBitsToUint(s.closest.t), s.closest.ref, s.hit.counts.box_hits));
    state_store(7u, word3(s.task.origin, s.task.depth));
    state_store(8u, word3(s.task.dir, s.counts.box_tests));
    state_store(9u, word3(s.task.weight, floatBitsToUint(s.depth)));
    state_store(10u, word3(s.color, s.work));
    state_store(11u, uvec4(s.walk.instance, s.walk.outer, s.hit.instance, s.closest.instance));
    state_store(12u, uvec4(s.hit.counts.prim_tests, s.hit.counts.prim_hits, s.hit.counts.instance_hits, s.task.kind));
    state_store(13u, uvec4(s.counts.box_hits, s.counts.prim_tests, s.counts.prim_hits, s.counts.instance_hits));
    state_store(14u, uvec4(floatBitsToUint(s.closest.u), floatBitsToUint(s.closest.v), 0u, 0u));
}

uint slot_stamp() { return state_load(2u).w; }

/// A trace that is over (done or failed) keeps only what says so (words 0 and 2 of save_state's layout): most
/// pixels finish in their first dispatch, and a done slot is only ever asked whether it is done.
void save_done(TraceState s, uint stamp) {
    state_store(0u, uvec4(s.pixel.x, s.pixel.y, s.phase, s.sample_index));
    state_store(2u, uvec4(0u, 0u, 0u, stamp));
}

/// Whether the slot holds a trace of this tile and pass (`stamp`) that is over (done or failed).
bool slot_done(uint stamp) { return slot_stamp() == stamp && state_load(0u).z >= PHASE_DONE; }

/// The state save_state stored. (The closest hit's transmission and counters are not kept:
/// shading never reads them; its barycentrics are, for the point rays leave it from: surface_at.
/// Nor is `holdout`: a camera ray meeting a holdout ends its sample in that step, next_ray.)
TraceState load_state() {
    uvec4 w0 = state_load(0u);
    uvec4 w1 = state_load(1u);
    uvec4 w2 = state_load(2u);
    uvec4 w3 = state_load(3u);
    uvec4 w4 = state_load(4u);
    uvec4 w5 = state_load(5u);
    uvec4 w6 = state_load(6u);
    uvec4 w7 = state_load(7u);
    uvec4 w8 = state_load(8u);
    uvec4 w9 = state_load(9u);
    TraceState s = begin_pixel(uvec2(w0.x, w0.y), w0.w, w1.x);
    s.phase = w0.z;
    s.rays = w1.y;
    s.walk.state = w1.z;
    s.walk.node = w1.w;
    s.walk.stacked = w2.x;
    s.walk.leaf_next = w2.y;
    s.walk.leaf_end = w2.z;
    s.ray = make_ray(vec3_of(w3), vec3_of(w4), uintBitsToFloat(w3.w));
    s.hit.t = uintBitsToFloat(w4.w);
    s.hit.ref = w5.x;
    s.hit.u = uintBitsToFloat(w5.y);
    s.hit.v = uintBitsToFloat(w5.z);
    s.hit.transmission = uintBitsToFloat(w5.w);
    s.hit.counts.box_tests = w6.x;
    s.hit.counts.box_hits = w6.w;
    s.closest = empty_hit(uintBitsToFloat(w6.y));
    s.closest.ref = w6.z;
    uvec4 w14 = state_load(14u);
    s.closest.u = uintBitsToFloat(w14.x);
    s.closest.v = uintBitsToFloat(w14.y);
    uvec4 w12 = state_load(12u);
    s.task = ray_task(vec3_of(w7), vec3_of(w8), vec3_of(w9), w7.w, w12.w);
    s.counts.box_tests = w8.w;
    s.depth = uintBitsToFloat(w9.w);
    uvec4 w10 = state_load(10u);
    s.color = vec3_of(w10);
    s.work = w10.w;
    uvec4 w11 = state_load(11u);
    s.walk.instance = w11.x;
    s.walk.outer = w11.y;
    s.hit.instance = w11.z;
    s.closest.instance = w11.w;
    s.hit.counts.prim_tests = w12.x;
    s.hit.counts.prim_hits = w12.y;
    s.hit.counts.instance_hits = w12.z;
    uvec4 w13 = state_load(13u);
    s.counts.box_hits = w13.x;
    s.counts.prim_tests = w13.y;
    s.counts.prim_hits = w13.z;
    s.counts.instance_hits = w13.w;
    return s;
}
