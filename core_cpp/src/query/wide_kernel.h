// wide_kernel.h — what the traversal kernels of the wide tree (wide_traverse.inl, one copy per
// instruction set) see: plain pointers, and the helpers they call out of line.
#pragma once
#include <cstdint>

#include "bvhlab/wide_bvh.h"

namespace bvhlab {

/// A WideBvh as a plain pointer to its lines (null when the tree is empty).
struct WideView {
    const unsigned char* lines;
};

/// hit_sphere (ray.h) on lane `lane` of a sphere packet; updates hit (t, ref) as it does.
bool hit_packet_sphere(const PrimPacket& k, int lane, const Ray& ray, Hit& hit);

/// What the recorded walk of the wide tree reports (the inspector's record, ray_record.h; the
/// walk calls it only in its recorded instantiation, wide_traverse.inl traverse_nodes).
class WideRecorder {
public:
    /// The node at `line` was visited: `nearest` is the child word of the child the walk goes to
    /// next (kNoHit where the ray entered none), `pushed[0, count)` those pushed for later.
    virtual void node(std::uint32_t line, std::uint32_t nearest, const std::uint32_t* pushed, std::uint32_t count) = 0;
    /// The leaf whose first packet is at `line` was tested; the closest hit before and after.
    virtual void leaf(std::uint32_t line, const Hit& before, const Hit& after) = 0;

protected:
    ~WideRecorder() = default;
};

namespace portable {
Hit intersect_wide_kernel(const WideView& wide, const Ray& ray, std::uint32_t* nodes_visited);
Hit record_wide_kernel(const WideView& wide, const Ray& ray, WideRecorder& record, std::uint32_t* nodes_visited);
bool occluded_wide_kernel(const WideView& wide, const Ray& ray);
}  // namespace portable
namespace avx2 {
Hit intersect_wide_kernel(const WideView& wide, const Ray& ray, std::uint32_t* nodes_visited);
Hit record_wide_kernel(const WideView& wide, const Ray& ray, WideRecorder& record, std::uint32_t* nodes_visited);
bool occluded_wide_kernel(const WideView& wide, const Ray& ray);
}  // namespace avx2

}  // namespace bvhlab
