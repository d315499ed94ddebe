// vk_upload.h — arrays copied into device-local buffers that the shaders read through their
// device addresses: written directly where that memory is host-visible (lavapipe), else (or when
// forced) through a staging buffer, as real GPUs need.
#pragma once
#include <cstddef>

#include "vk_commands.h"
#include "vk_memory.h"

namespace bvhlab::vk {

/// A device-local buffer holding `bytes` bytes of `data`, with SHADER_DEVICE_ADDRESS usage. Never
/// zero-sized (16 bytes at least), so an empty array still has a valid address.
Buffer upload_array(const Device& device, CommandRunner& runner, const void* data, std::size_t bytes,
                    bool force_staging);

}  // namespace bvhlab::vk
