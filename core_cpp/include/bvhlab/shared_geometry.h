// shared_geometry.h — the ray tests of shaders/tracer/geometry.glsl (the ray with its precomputed
// constants, the box test, the watertight triangle test, the sphere roots) compiled as C++, in
// bvhlab::gpu: the one definition that the CPU traversal (ray.h), the CPU reference tracer
// (cpu_tracer.h) and the compute shader all run.
#pragma once
#include "gpu_types.h"

namespace bvhlab::gpu {

inline vec3 xyz(vec4 v) { return {v.x, v.y, v.z}; }

#include "tracer/geometry.glsl"

}  // namespace bvhlab::gpu
