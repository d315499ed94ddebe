#include "bvhlab/isa.h"

#include <atomic>
#include <cstdlib>
#include <stdexcept>
#include <string>

namespace bvhlab {
namespace {

bool cpu_has_avx2() {
#if defined(BVHLAB_AVX2_KERNELS) && (defined(__GNUC__) || defined(__clang__))
    __builtin_cpu_init();
    return __builtin_cpu_supports("avx2") != 0;
#else
    return false;
#endif
}

/// AVX-512 F, VL, BW and DQ, and the OS saving the opmask and zmm state (XCR0 bits 5-7 with the
/// SSE and AVX bits 1-2: Intel SDM vol. 1, 15.2). libgcc's __builtin_cpu_supports checks XCR0
/// too; the xgetbv here says so where that is read. valgrind hides AVX-512 from CPUID, so the
/// AVX2 path runs under callgrind.
bool cpu_has_avx512() {
#if defined(BVHLAB_AVX512_KERNELS) && (defined(__GNUC__) || defined(__clang__))
    __builtin_cpu_init();
    if (!__builtin_cpu_supports("avx512f") || !__builtin_cpu_supports("avx512vl") ||
        !__builtin_cpu_supports("avx512bw") || !__builtin_cpu_supports("avx512dq") || !cpu_has_avx2())
        return false;
    unsigned lo = 0, hi = 0;
    __asm__ volatile("xgetbv" : "=a"(lo), "=d"(hi) : "c"(0));  // OSXSAVE is implied by avx2 above
    return (lo & 0xe6u) == 0xe6u;
#else
    return false;
#endif
}

Isa initial_isa() {
    Isa best = cpu_has_avx512() ? Isa::Avx512 : cpu_has_avx2() ? Isa::Avx2 : Isa::Portable;
    if (const char* env = std::getenv("BVHLAB_ISA")) {
        const std::string want = env;
        if (want == "portable") best = Isa::Portable;
        else if (want == "avx2" && best > Isa::Avx2) best = Isa::Avx2;
        // "avx512" keeps the best when the CPU has it; anything else is ignored
    }
    return best;
}

}  // namespace

// Set when the library loads (dynamic initialisation). Anything that ran before it would read
// zero, Isa::Portable, which every CPU runs.
std::atomic<Isa> detail::active_isa_now{initial_isa()};

bool isa_supported(Isa isa) {
    return isa == Isa::Portable || (isa == Isa::Avx2 && cpu_has_avx2()) || (isa == Isa::Avx512 && cpu_has_avx512());
}

void set_isa(Isa isa) {
    if (!isa_supported(isa))
        throw std::invalid_argument("instruction set " + std::string(isa_name(isa)) + " is not available here");
    detail::active_isa_now.store(isa, std::memory_order_relaxed);
}

std::string_view isa_name(Isa isa) { return isa == Isa::Avx512 ? "avx512" : isa == Isa::Avx2 ? "avx2" : "portable"; }

}  // namespace bvhlab
