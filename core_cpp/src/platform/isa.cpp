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

Isa initial_isa() {
    Isa best = cpu_has_avx2() ? Isa::Avx2 : Isa::Portable;
    if (const char* env = std::getenv("BVHLAB_ISA")) {
        const std::string want = env;
        if (want == "portable") best = Isa::Portable;
        // "avx2" keeps the best when the CPU has it; anything else is ignored
    }
    return best;
}

}  // namespace

// Set when the library loads (dynamic initialisation). Anything that ran before it would read
// zero, Isa::Portable, which every CPU runs.
std::atomic<Isa> detail::active_isa_now{initial_isa()};

bool isa_supported(Isa isa) { return isa == Isa::Portable || (isa == Isa::Avx2 && cpu_has_avx2()); }

void set_isa(Isa isa) {
    if (!isa_supported(isa))
        throw std::invalid_argument("instruction set " + std::string(isa_name(isa)) + " is not available here");
    detail::active_isa_now.store(isa, std::memory_order_relaxed);
}

std::string_view isa_name(Isa isa) { return isa == Isa::Avx2 ? "avx2" : "portable"; }

}  // namespace bvhlab
