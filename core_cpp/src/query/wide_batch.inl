// wide_batch.inl — the batch walks of the 8-wide tree (intersect_wide_batch, occluded_wide_batch:
// wide_bvh.h): included by wide_traverse.inl, inside the including file's namespace, with its
// walks. The rays come grouped by octant (group_by_octant, traverse_wide.cpp) and each group goes
// through the walk compiled for its octant, so that no ray picks its walk by an indirect call
// (mispredicted at 87% of shadow rays: design.md, "Any-hit queries") and one copy of the walk's
// code is hot at a time.

#ifdef BVHLAB_WIDE_PACKETS
#include "wide_packet.inl"
#endif
#include "wide_interleaved.inl"

/// The closest hits of rays[order[0, n)], all of octant kOctant, to hits[i] (and the count of
/// wide nodes visited to visited[i], where given) in each ray's own slot i.
/// Where the including file defines BVHLAB_WIDE_PACKETS (the AVX2 path) and no visited counts are
/// asked (a packet's are not the single walk's), each run of kPacket rays that `coherent` accepts
/// goes through the tree as one packet (wide_packet.inl); the rest go alone after the packets, one
/// after another or interleaved (`walk`, wide_interleaved.inl). n is at most kWideBatch (a piece:
/// group_by_octant, ray_batch.h prepare_piece).
template <int kOctant>
void closest_of_octant(const WideView& wide, const Ray* rays, const std::uint32_t* order, std::uint32_t n, Hit* hits,
                       std::uint32_t* visited, WideWalk walk) {
    std::uint32_t alone[kWideBatch], m = 0;  // the rays that go alone
    std::uint32_t j = 0;
#ifdef BVHLAB_WIDE_PACKETS
    if (!visited) {
        PacketStack& stack = *thread_room<PacketStack, 1>();
        for (; j + kPacket <= n; j += kPacket) {
            // random and shadow rays part at the second ray's origin: no gather for them
            const Vec3 &a = rays[order[j]].origin, &b = rays[order[j + 1]].origin;
            if (a.x == b.x && a.y == b.y && a.z == b.z) {
                const PacketRays p = packet_rays(rays, order + j);
                if (coherent(p)) {
                    closest_packet<kOctant>(wide, rays, order + j, p, hits, stack);
                    continue;
                }
            }
            for (int r = 0; r < kPacket; ++r) alone[m++] = order[j + r];
        }
    }
#endif
    for (; j < n; ++j) alone[m++] = order[j];
    if (walk == WideWalk::Interleaved) return closest_interleaved<kOctant>(wide, rays, alone, m, hits, visited);
    for (std::uint32_t r = 0; r < m; ++r) {
        const std::uint32_t i = alone[r];
        Hit hit{rays[i].tmax, kNoHit, 0.0f, 0.0f, kNoHit};
        const std::uint32_t v = traverse_nodes<false, kOctant>(wide, make_query(rays[i]), hit);
        hits[i] = hit;
        if (visited) visited[i] = v;
    }
}

/// Whether each of rays[order[0, n)], all of octant kOctant, is occluded, to occluded[i], by the
/// any-hit walk's farthest-first order or (kFarthest false) the layout's (any_hit_nodes).
template <int kOctant, bool kFarthest>
void occluded_of_octant(const WideView& wide, const Ray* rays, const std::uint32_t* order, std::uint32_t n,
                        bool* occluded) {
    for (std::uint32_t j = 0; j < n; ++j) {
        const std::uint32_t i = order[j];
        occluded[i] =
            any_hit_nodes<kOctant, kFarthest>(wide.lines, kFarthest ? make_query(rays[i]) : make_box_query(rays[i]));
    }
}

/// The closest hits of a batch grouped by octant (group_by_octant: order[start[k], start[k + 1])
/// the rays of octant k), each group through its octant's walk.
void closest_of_batch(const WideView& wide, const Ray* rays, const std::uint32_t* order, const std::uint32_t* start,
                      Hit* hits, std::uint32_t* visited, WideWalk walk) {
    using Walk =
        void (*)(const WideView&, const Ray*, const std::uint32_t*, std::uint32_t, Hit*, std::uint32_t*, WideWalk);
    static constexpr Walk kWalks[8] = {closest_of_octant<0>, closest_of_octant<1>, closest_of_octant<2>,
                                       closest_of_octant<3>, closest_of_octant<4>, closest_of_octant<5>,
                                       closest_of_octant<6>, closest_of_octant<7>};
    for (int k = 0; k < 8; ++k)
        if (start[k + 1] > start[k])
            kWalks[k](wide, rays, order + start[k], start[k + 1] - start[k], hits, visited, walk);
}

/// occluded for the entries order[from, to) of a batch grouped by octant, each through its
/// octant's walk in the order kFarthest says.
template <bool kFarthest>
void occluded_of_entries(const WideView& wide, const Ray* rays, const std::uint32_t* order, const std::uint32_t* start,
                         std::uint32_t from, std::uint32_t to, bool* occluded) {
    using Walk = void (*)(const WideView&, const Ray*, const std::uint32_t*, std::uint32_t, bool*);
    static constexpr Walk kWalks[8] = {occluded_of_octant<0, kFarthest>, occluded_of_octant<1, kFarthest>,
                                       occluded_of_octant<2, kFarthest>, occluded_of_octant<3, kFarthest>,
                                       occluded_of_octant<4, kFarthest>, occluded_of_octant<5, kFarthest>,
                                       occluded_of_octant<6, kFarthest>, occluded_of_octant<7, kFarthest>};
    for (int k = 0; k < 8; ++k) {
        const std::uint32_t lo = std::max(start[k], from), hi = std::min(start[k + 1], to);
        if (hi > lo) kWalks[k](wide, rays, order + lo, hi - lo, occluded);
    }
}

/// The batch's any-hit order, per piece: its first kOrderProbe rays (in grouped order) go farthest
/// first, and the rest go so too where at least kOrderProbeOccluded of those were occluded, else in
/// the layout's order (any_hit_nodes kFarthest). Any order gives the same answers; the farthest
/// saves cache misses on occluded rays and costs its choice on the others (design.md, "The any-hit
/// walk's order against the caches"). The six bench scenes' shadow rays are occluded at 0-7%
/// (room1m, vast1m) or 85-99% (the others) of every 256-ray piece, so a quarter lies far from both;
/// a piece's own first rays rather than the piece before, so that no state crosses pieces (the
/// threads each take their own).
inline constexpr std::uint32_t kOrderProbe = 16, kOrderProbeOccluded = 4;

/// occluded for a batch grouped by octant, as closest_of_batch, in the order its first rays say.
void occluded_of_batch(const WideView& wide, const Ray* rays, const std::uint32_t* order, const std::uint32_t* start,
                       bool* occluded) {
    const std::uint32_t n = start[8], probe = std::min(n, kOrderProbe);
    occluded_of_entries<true>(wide, rays, order, start, 0, probe, occluded);
    std::uint32_t found = 0;
    for (std::uint32_t j = 0; j < probe; ++j) found += occluded[order[j]];
    if (found >= kOrderProbeOccluded) occluded_of_entries<true>(wide, rays, order, start, probe, n, occluded);
    else occluded_of_entries<false>(wide, rays, order, start, probe, n, occluded);
}
