// The batch's vector passes for CPUs with AVX-512 F, VL, BW and DQ (chosen at run time, isa.h):
// ray_piece_avx2.cpp compiled again with those flags (core_cpp/CMakeLists.txt), in namespace
// avx512, so that a batch on that path runs no AVX2 code (no transition between the two builds).
#define BVHLAB_KERNEL_NS avx512
#include "ray_piece_avx2.cpp"
