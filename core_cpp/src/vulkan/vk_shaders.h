// vk_shaders.h — the SPIR-V of shaders/trace.comp, overlay.vert and overlay.frag, compiled by glslc
// at build time (core_cpp/CMakeLists.txt) and embedded in the binary.
#pragma once
#include <cstddef>
#include <cstdint>

#include "vk_device.h"

namespace bvhlab::vk {

struct Spirv {
    const std::uint32_t* words;
    std::size_t size_bytes;
};

Spirv trace_comp_spirv();
Spirv overlay_vert_spirv();
Spirv overlay_frag_spirv();

/// A shader module for `code`, to be dropped once the pipelines using it exist.
OwnedShaderModule make_shader_module(const Device& device, Spirv code);

}  // namespace bvhlab::vk
