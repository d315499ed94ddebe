// wide_batch.inl — the batch walks of the 8-wide tree (intersect_wide_batch, occluded_wide_batch:
// wide_bvh.h): included by wide_traverse.inl, inside the including file's namespace, with its
// walks. The rays come grouped by octant (group_by_octant, traverse_wide.cpp) and each group goes
// through the walk compiled for its octant, so that no ray picks its walk by an indirect call
// (mispredicted at 87% of shadow rays: design.md, "Any-hit queries") and one copy of the walk's
// code is hot at a time.

#ifdef BVHLAB_WIDE_PACKETS
#include "wide_packet.inl"
#endif

/// The closest hits of rays[order[0, n)], all of octant kOctant, to hits[i] (and the count of
/// wide nodes visited to visited[i], where given) in each ray's own slot i.
/// Where the including file defines BVHLAB_WIDE_PACKETS (the AVX2 path) and no visited counts are
/// asked (a packet's are not the single walk's), each run of kPacket rays that `coherent` accepts
/// goes through the tree as one packet (wide_packet.inl); the rest ray by ray.
template <int kOctant>
void closest_of_octant(const WideView& wide, const Ray* rays, const std::uint32_t* order, std::uint32_t n, Hit* hits,
                       std::uint32_t* visited) {
    const auto single = [&](std::uint32_t i) {
        Hit hit{rays[i].tmax, kNoHit, 0.0f, 0.0f, kNoHit};
        const std::uint32_t v = traverse_nodes<false, kOctant>(wide, make_query(rays[i]), hit);
        hits[i] = hit;
        if (visited) visited[i] = v;
    };
    std::uint32_t j = 0;
#ifdef BVHLAB_WIDE_PACKETS
    if (!visited)
        for (; j + kPacket <= n; j += kPacket) {
            if (coherent(rays, order + j)) {
                closest_packet<kOctant>(wide, rays, order + j, hits);
            } else {
                for (int r = 0; r < kPacket; ++r) single(order[j + r]);
            }
        }
#endif
    for (; j < n; ++j) single(order[j]);
}

/// Whether each of rays[order[0, n)], all of octant kOctant, is occluded, to occluded[i].
template <int kOctant>
void occluded_of_octant(const WideView& wide, const Ray* rays, const std::uint32_t* order, std::uint32_t n,
                        bool* occluded) {
    for (std::uint32_t j = 0; j < n; ++j) {
        const std::uint32_t i = order[j];
        occluded[i] = any_hit_nodes<kOctant>(wide.lines, make_query(rays[i]));
    }
}

/// The closest hits of a batch grouped by octant (group_by_octant: order[start[k], start[k + 1])
/// the rays of octant k), each group through its octant's walk.
void closest_of_batch(const WideView& wide, const Ray* rays, const std::uint32_t* order, const std::uint32_t* start,
                      Hit* hits, std::uint32_t* visited) {
    using Walk = void (*)(const WideView&, const Ray*, const std::uint32_t*, std::uint32_t, Hit*, std::uint32_t*);
    static constexpr Walk kWalks[8] = {closest_of_octant<0>, closest_of_octant<1>, closest_of_octant<2>,
                                       closest_of_octant<3>, closest_of_octant<4>, closest_of_octant<5>,
                                       closest_of_octant<6>, closest_of_octant<7>};
    for (int k = 0; k < 8; ++k)
        if (start[k + 1] > start[k]) kWalks[k](wide, rays, order + start[k], start[k + 1] - start[k], hits, visited);
}

/// occluded for a batch grouped by octant, as closest_of_batch.
void occluded_of_batch(const WideView& wide, const Ray* rays, const std::uint32_t* order, const std::uint32_t* start,
                       bool* occluded) {
    using Walk = void (*)(const WideView&, const Ray*, const std::uint32_t*, std::uint32_t, bool*);
    static constexpr Walk kWalks[8] = {occluded_of_octant<0>, occluded_of_octant<1>, occluded_of_octant<2>,
                                       occluded_of_octant<3>, occluded_of_octant<4>, occluded_of_octant<5>,
                                       occluded_of_octant<6>, occluded_of_octant<7>};
    for (int k = 0; k < 8; ++k)
        if (start[k + 1] > start[k]) kWalks[k](wide, rays, order + start[k], start[k + 1] - start[k], occluded);
}
