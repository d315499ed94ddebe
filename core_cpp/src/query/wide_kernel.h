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

namespace portable {
Hit intersect_wide_kernel(const WideView& wide, const Ray& ray, std::uint32_t* nodes_visited);
bool occluded_wide_kernel(const WideView& wide, const Ray& ray);
}  // namespace portable
namespace avx2 {
Hit intersect_wide_kernel(const WideView& wide, const Ray& ray, std::uint32_t* nodes_visited);
bool occluded_wide_kernel(const WideView& wide, const Ray& ray);
}  // namespace avx2

}  // namespace bvhlab
