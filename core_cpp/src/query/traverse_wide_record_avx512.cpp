// The recorded walk of the 8-wide tree for CPUs with AVX-512 (traverse_wide_record_avx2.cpp's
// counterpart): traverse_wide_avx512.cpp with BVHLAB_RECORDED_WIDE_WALK.
#define BVHLAB_RECORDED_WIDE_WALK
#include "traverse_wide_avx512.cpp"
