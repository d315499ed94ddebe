// wide_kernels.h — the wide walks of one instruction set as a type (wide_kernel.h's kernels), so
// that a query that walks many trees picks the set once and calls each kernel directly: the
// two-level walk (traverse_two_level.cpp) walks a BLAS for every instance a ray enters and
// resumes the TLAS walk after each, and the dispatch of each call (intersect_wide, next_tlas_leaf:
// the active instruction set loaded, the view made, one more call) cost `many`'s random rays ~80
// instructions a ray of ~2,600 (design.md, "The two-level walk's cost").
#pragma once
#include <cstdint>

#include "bvhlab/isa.h"
#include "bvhlab/tlas.h"
#include "wide_kernel.h"

namespace bvhlab {

/// The kernels of namespace `ns` under the names every kernel set has: the single-ray walks, the
/// batch walks (wide_batch.inl) and the TLAS walk.
#define BVHLAB_WIDE_KERNEL_SET(Name, ns)                                                                       \
    struct Name {                                                                                              \
        static Hit closest(const WideView& w, const Ray& r, std::uint32_t* visited) {                          \
            return ns::intersect_wide_kernel(w, r, visited);                                                   \
        }                                                                                                      \
        static bool any(const WideView& w, const Ray& r) { return ns::occluded_wide_kernel(w, r); }            \
        static void closest_batch(const WideView& w, const Ray* rays, const std::uint32_t* order,              \
                                  const std::uint32_t* start, Hit* hits, std::uint32_t* visited, WideWalk k) { \
            ns::intersect_wide_batch_kernel(w, rays, order, start, hits, visited, k);                          \
        }                                                                                                      \
        static void any_batch(const WideView& w, const Ray* rays, const std::uint32_t* order,                  \
                              const std::uint32_t* start, bool* occluded) {                                    \
            ns::occluded_wide_batch_kernel(w, rays, order, start, occluded);                                   \
        }                                                                                                      \
        static void start_tlas(const Ray& r, TlasWalk& walk) { ns::start_tlas_walk(r, walk); }                 \
        static std::uint32_t next_tlas(const WideView& w, TlasWalk& walk, float hit_t, WideRecorder* record) { \
            return ns::next_tlas_leaf(w, walk, hit_t, record);                                                 \
        }                                                                                                      \
    }

/// The portable kernels (plain C++ or SSE).
BVHLAB_WIDE_KERNEL_SET(PortableKernels, portable);
#if defined(BVHLAB_AVX2_KERNELS)
/// The AVX2 kernels (traverse_wide_avx2.cpp).
BVHLAB_WIDE_KERNEL_SET(Avx2Kernels, avx2);
#endif
#if defined(BVHLAB_AVX512_KERNELS)
/// The AVX-512 kernels (traverse_wide_avx512.cpp: traverse_wide_avx2.cpp built with AVX-512VL).
BVHLAB_WIDE_KERNEL_SET(Avx512Kernels, avx512);
#endif
#undef BVHLAB_WIDE_KERNEL_SET

/// f(kernels) with the kernel set of the active instruction set (isa.h), chosen here once.
template <class F>
decltype(auto) with_wide_kernels(F&& f) {
#if defined(BVHLAB_AVX512_KERNELS)
    if (active_isa() == Isa::Avx512) return f(Avx512Kernels{});
#endif
#if defined(BVHLAB_AVX2_KERNELS)
    if (active_isa() == Isa::Avx2) return f(Avx2Kernels{});
#endif
    return f(PortableKernels{});
}

/// intersect_wide (wide_bvh.h) by kernel set K: the BLAS walk of a two-level query.
template <class K>
Hit intersect_wide_with(const BlasView& blas, const Ray& ray, std::uint32_t* visited) {
    Hit hit = K::closest(view_of(*blas.wide), ray, visited);
    finish_wide_hit(*blas.bvh, ray, hit);
    return hit;
}

}  // namespace bvhlab
