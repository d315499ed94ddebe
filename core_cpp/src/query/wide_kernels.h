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

/// The portable kernels (plain C++ or SSE) under the names every kernel set has.
struct PortableKernels {
    static Hit closest(const WideView& w, const Ray& r, std::uint32_t* visited) {
        return portable::intersect_wide_kernel(w, r, visited);
    }
    static bool any(const WideView& w, const Ray& r) { return portable::occluded_wide_kernel(w, r); }
    static void start_tlas(const Ray& r, TlasWalk& walk) { portable::start_tlas_walk(r, walk); }
    static std::uint32_t next_tlas(const WideView& w, TlasWalk& walk, float hit_t, WideRecorder* record) {
        return portable::next_tlas_leaf(w, walk, hit_t, record);
    }
};
#if defined(BVHLAB_AVX2_KERNELS)
/// The AVX2 kernels (traverse_wide_avx2.cpp), as PortableKernels.
struct Avx2Kernels {
    static Hit closest(const WideView& w, const Ray& r, std::uint32_t* visited) {
        return avx2::intersect_wide_kernel(w, r, visited);
    }
    static bool any(const WideView& w, const Ray& r) { return avx2::occluded_wide_kernel(w, r); }
    static void start_tlas(const Ray& r, TlasWalk& walk) { avx2::start_tlas_walk(r, walk); }
    static std::uint32_t next_tlas(const WideView& w, TlasWalk& walk, float hit_t, WideRecorder* record) {
        return avx2::next_tlas_leaf(w, walk, hit_t, record);
    }
};
#endif

/// f(kernels) with the kernel set of the active instruction set (isa.h), chosen here once.
template <class F>
decltype(auto) with_wide_kernels(F&& f) {
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
