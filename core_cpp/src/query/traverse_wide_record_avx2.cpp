// The recorded walk of the 8-wide tree for CPUs with AVX2 (compiled with -mavx2, chosen at run
// time as intersect_wide chooses): traverse_wide_avx2.cpp compiled again with
// BVHLAB_RECORDED_WIDE_WALK (see traverse_wide_record.cpp).
#define BVHLAB_RECORDED_WIDE_WALK
#include "traverse_wide_avx2.cpp"
