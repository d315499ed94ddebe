// The 8-wide traversal for CPUs with AVX-512 F, VL, BW and DQ (chosen at run time, isa.h):
// traverse_wide_avx2.cpp compiled again with those flags (core_cpp/CMakeLists.txt), in namespace
// avx512. The vectors stay 256 bits wide; the compiler may use the mask registers and the new
// instructions (vpternlog, vpcompress, compares into masks), not fused multiply-adds
// (-ffp-contract=off): the same IEEE operations in the same order, so the same hits.
#define BVHLAB_KERNEL_NS avx512
#include "traverse_wide_avx2.cpp"
