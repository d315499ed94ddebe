// isa.h — which instruction set the hot loops use, chosen once when the library loads.
//
// The library is built for a portable baseline (x86-64-v2 on x86, what the compiler targets
// elsewhere); the binning/partition passes of the builder, its SAH sweeps and small-subtree sort,
// and the wide traversal also exist compiled for AVX2, picked at run time when the CPU has it.
// Every path does the same IEEE arithmetic in the same order (no fused multiply-adds), so trees
// and hits are bit-identical whichever runs; the tests force each path and compare. The wide
// traversal and the batch's vector passes also exist compiled a third time, for AVX-512 (F, VL,
// BW, DQ: 256-bit vectors with the mask registers; 1-5% faster batches than AVX2 on a Zen 5,
// docs/design.md "An AVX-512 path"); the builder runs its AVX2 kernels there.
#pragma once
#include <atomic>
#include <string_view>

namespace bvhlab {

enum class Isa {
    Portable,  ///< the baseline the library is compiled for (SSE4.2 on x86-64, scalar elsewhere)
    Avx2,      ///< x86-64 with AVX2 (Haswell, Zen and later)
    Avx512,    ///< x86-64 with AVX-512 F, VL, BW and DQ, enabled by the OS (Skylake-X, Zen 4 and later)
};
// Ordered: a path runs the kernels of every path below it that it has no own kernels for
// (active_isa() >= Isa::Avx2: the AVX2 build kernels).

namespace detail {
/// What active_isa() returns (isa.cpp sets it when the library loads; set_isa changes it).
extern std::atomic<Isa> active_isa_now;
}  // namespace detail

/// The path in use. At load: the best the CPU supports, lowered by the environment variable
/// BVHLAB_ISA=portable|avx2|avx512 if set (an unsupported or unknown value is ignored). Inline, one
/// load: the per-ray queries ask it for every ray (an out-of-line call with a guarded static
/// cost the wide walk ~6 instructions a ray).
inline Isa active_isa() { return detail::active_isa_now.load(std::memory_order_relaxed); }
/// True when this build has the path and this CPU can run it.
bool isa_supported(Isa isa);
/// Switches path (for tests and benchmarks). Throws std::invalid_argument if unsupported.
/// Not for use while other threads build or trace.
void set_isa(Isa isa);
std::string_view isa_name(Isa isa);

}  // namespace bvhlab
