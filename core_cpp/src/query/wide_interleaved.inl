// wide_interleaved.inl — the batch's closest-hit walk of rays that go alone, several rays at once on
// one thread: included by wide_batch.inl, inside the including file's namespace, with the walk's
// parts (wide_traverse.inl). The any-hit walk is not interleaved: it lost on every shadow-ray set
// measured (design.md, "Several rays at once on a thread").
//
// A random ray's walk through a tree larger than the caches is a chain of misses, each node's
// address read from the node before (rods1m: ~14 last-level misses a ray, ~75 ns a wide node
// visited: design.md, "rods1m's random rays"). A core keeps many loads in flight; one walk has
// one to wait for. So the batch keeps several walks (kInterleavedWays) and steps them in turn, one
// node or leaf of one ray a turn, each turn prefetching the entry its walk goes to next: by that
// walk's next turn its lines have come while the others worked (Kocberber, Falsafi and Grot 2015,
// "Asynchronous Memory Access Chaining", PVLDB 9(4)). Each walk is traverse_nodes' own, entry by
// entry, so each ray's hit is the single walk's, bit for bit.

/// The walks an interleaved batch steps in turn. Random rays ÷ the faster of Embree 3 MEDIUM and
/// tinybvh 1.9 through the batch (a 2-core AMD EPYC VM, 2026-12-06, two rounds, two binaries
/// alternately in one run): 4 ways against 10, rods1m 1.04-1.09 / 1.19-1.28, uniform1m 1.63-1.67 /
/// 1.95-2.15; 6, 10 and 14 within the runs' spread (rods1m 1.32-1.37 / 1.24-1.45 / 1.36-1.41,
/// repeat1m 1.81-1.89 / 1.69-1.99 / 1.92-1.95, uniform1m 2.17-2.39 / 2.10-2.70 / 2.00-2.62).
inline constexpr int kInterleavedWays = 8;

/// Runs n walks kInterleavedWays at a time: start(w, j) starts walker w on the j-th, step(w) takes
/// one turn of it (false when its walk is done), finish(w) keeps its result; a walker whose walk
/// ends starts the next, and the turns go round the walkers in use.
template <class W, class Start, class Step, class Finish>
[[gnu::always_inline]] inline void interleave(std::uint32_t n, Start&& start, Step&& step, Finish&& finish) {
    constexpr int kWays = kInterleavedWays;
    W* walkers = thread_room<W, kWays>();  // eight stacks: 31 KiB
    int live[kWays];                       // the walkers in use, live[0, count)
    int count = 0;
    std::uint32_t next = 0;
    for (; count < kWays && next < n; ++count) start(walkers[count], next++), live[count] = count;
    for (int k = 0; count > 0;) {
        W& w = walkers[live[k]];
        if (!step(w)) {
            finish(w);
            if (next < n) {
                start(w, next++);
            } else {  // its place to the last walker, whose turn it is now
                live[k] = live[--count];
                if (k >= count) k = 0;
                continue;
            }
        }
        if (++k >= count) k = 0;
    }
}

/// One ray's closest-hit walk between its turns: traverse_nodes' state.
struct Walker {
    Query q;
    Hit hit;
    Entry cur;
    float far_limit;
    std::uint32_t sp, visited, ray;
    Stack stack;
};

/// Starts `w` on rays[i]: traverse_nodes' start from the root.
inline void start_walker(Walker& w, const Ray* rays, std::uint32_t i) {
    set_query<true, true>(rays[i], w.q);
    w.hit = Hit{rays[i].tmax, kNoHit, 0.0f, 0.0f, kNoHit};
    w.cur = {0, w.q.tmin};
    w.far_limit = w.hit.t * gpu::BOX_FAR_SCALE;
    w.sp = 0, w.visited = 0, w.ray = i;
}

/// One turn of traverse_nodes' loop for `w`, whose octant is kOctant: its entry (a leaf's test, or
/// a node's children), then the entry it goes to next in w.cur, that entry's lines prefetched.
/// false when the walk is done.
template <int kOctant>
[[gnu::always_inline]] inline bool step_walker(const WideView& wide, Walker& w) {
    if (w.cur.index & kLeafChild) {
        test_leaf(wide, w.cur.index & ~kLeafChild, w.q, w.hit);
        w.far_limit = w.hit.t * gpu::BOX_FAR_SCALE;
    } else {
        const Query& q = w.q;
        const L8 origin[3] = {L8::splat(q.o[0]), L8::splat(q.o[1]), L8::splat(q.o[2])};
        const L8 neg_inv[3] = {L8::splat(q.neg_inv[0]), L8::splat(q.neg_inv[1]), L8::splat(q.neg_inv[2])};
        const L8 neg_inv_far[3] = {L8::splat(q.neg_inv_far[0]), L8::splat(q.neg_inv_far[1]),
                                   L8::splat(q.neg_inv_far[2])};
        ++w.visited;
        if (enter_children(wide, node_at(wide, w.cur.index), origin, neg_inv, neg_inv_far, kPlanes.at[kOctant & 7],
                           q.tmin8, w.far_limit, w.stack, w.sp, w.cur)) {
            prefetch(wide, w.cur.index);
            return true;
        }
    }
    do {  // pop, skipping entries farther than the closest hit so far (ray.h may_hold_closer)
        if (w.sp == 0) return false;
        --w.sp;
    } while (!(w.stack.t[w.sp] <= w.far_limit));
    w.cur = {w.stack.index[w.sp], w.stack.t[w.sp]};
    prefetch(wide, w.cur.index);
    return true;
}

/// The closest hits of rays[ids[0, n)], all of octant kOctant, to hits[i] (and the count of wide
/// nodes visited to visited[i], where given), kInterleavedWays walks stepped in turn.
template <int kOctant>
void closest_interleaved(const WideView& wide, const Ray* rays, const std::uint32_t* ids, std::uint32_t n, Hit* hits,
                         std::uint32_t* visited) {
    interleave<Walker>(
        n, [&](Walker& w, std::uint32_t j) { start_walker(w, rays, ids[j]); },
        [&](Walker& w) { return step_walker<kOctant>(wide, w); },
        [&](const Walker& w) {
            hits[w.ray] = w.hit;
            if (visited) visited[w.ray] = w.visited;
        });
}
