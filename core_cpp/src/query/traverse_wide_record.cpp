// The recorded walk of the 8-wide tree (wide_kernel.h record_wide_kernel; the inspector's record,
// ray_record.h), portable path: traverse_wide.cpp compiled again with BVHLAB_RECORDED_WIDE_WALK,
// which keeps its vector types and the walk (wide_traverse.inl) and leaves out the rest. A
// translation unit of its own, so that the plain walks' code is what it was (wide_traverse.inl).
#define BVHLAB_RECORDED_WIDE_WALK
#include "traverse_wide.cpp"
