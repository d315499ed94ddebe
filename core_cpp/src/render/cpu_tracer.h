// cpu_tracer.h — the CPU reference tracer: the shared GLSL tracer code (shaders/tracer/*.glsl)
// compiled as member functions of this class, over the same arrays the GPU reads. The accessors
// below play the part of trace.comp's buffer references and storage image.
#pragma once
#include "bvhlab/render.h"
#include "gpu_types.h"

namespace bvhlab::gpu {

inline vec3 xyz(vec4 v) { return {v.x, v.y, v.z}; }

class CpuTracer {
public:
    CpuTracer(const RenderScene& scene, const FrameParams& params, const vec4* overlay, uint traversal)
        : frame(params), TRAVERSAL(traversal), scene_(scene), overlay_(overlay) {}

    FrameParams frame;
    uint TRAVERSAL;

    BvhNode load_node(uint i) const { return scene_.bvh->nodes[i]; }
    uint load_ref(uint i) const { return scene_.bvh->refs[i]; }
    GpuTriangle load_triangle(uint i) const { return scene_.triangles[i]; }
    GpuSphere load_sphere(uint i) const { return scene_.spheres[i]; }
    GpuMaterial load_material(uint i) const { return scene_.materials[i]; }
    uint node_count() const { return frame.flags.z; }
    vec4 overlay_at(uvec2 p) const { return overlay_ ? overlay_[std::size_t(p.y) * frame.size.x + p.x] : vec4(0.0f); }

#include "tracer/geometry.glsl"
#include "tracer/traverse.glsl"
#include "tracer/shade_colors.glsl"
#include "tracer/shade.glsl"
#include "tracer/overlay.glsl"

private:
    const RenderScene& scene_;
    const vec4* overlay_;
};

}  // namespace bvhlab::gpu
