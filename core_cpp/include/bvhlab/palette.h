// palette.h — the colour ramps of shaders/tracer/shade_colors.glsl (the heatmap and the overlay's
// depth colours) for C++: the resolve step of both renderers, the Python module, the add-on.
#pragma once
#include "gpu_types.h"

namespace bvhlab::gpu {

struct Palette {
#include "tracer/shade_colors.glsl"
};

}  // namespace bvhlab::gpu
