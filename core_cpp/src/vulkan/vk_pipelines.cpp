// Descriptor set layout, pipeline layout and the trace compute pipelines (one per traversal).
#include "vk_pipelines.h"

#include "gpu_types.h"
#include "vk_check.h"
#include "vk_shaders.h"

namespace bvhlab::vk {
namespace {

OwnedSetLayout create_set_layout(const Device& device) {
    VkDescriptorSetLayoutBinding bindings[2]{};
    bindings[0].binding = gpu::BINDING_FRAME;
    bindings[0].descriptorType = VK_DESCRIPTOR_TYPE_STORAGE_BUFFER;
    bindings[0].descriptorCount = 1;
    bindings[0].stageFlags = VK_SHADER_STAGE_COMPUTE_BIT | VK_SHADER_STAGE_VERTEX_BIT | VK_SHADER_STAGE_FRAGMENT_BIT;
    bindings[1].binding = gpu::BINDING_OVERLAY;
    bindings[1].descriptorType = VK_DESCRIPTOR_TYPE_STORAGE_IMAGE;
    bindings[1].descriptorCount = 1;
    bindings[1].stageFlags = VK_SHADER_STAGE_COMPUTE_BIT;
    VkDescriptorSetLayoutCreateInfo info{VK_STRUCTURE_TYPE_DESCRIPTOR_SET_LAYOUT_CREATE_INFO};
    info.bindingCount = 2;
    info.pBindings = bindings;
    VkDescriptorSetLayout layout = VK_NULL_HANDLE;
    VK_CHECK(device.fn().vkCreateDescriptorSetLayout(device.handle(), &info, nullptr, &layout));
    return OwnedSetLayout(device, layout);
}

OwnedPipelineLayout create_pipeline_layout(const Device& device, VkDescriptorSetLayout set_layout) {
    VkPipelineLayoutCreateInfo info{VK_STRUCTURE_TYPE_PIPELINE_LAYOUT_CREATE_INFO};
    info.setLayoutCount = 1;
    info.pSetLayouts = &set_layout;
    VkPipelineLayout layout = VK_NULL_HANDLE;
    VK_CHECK(device.fn().vkCreatePipelineLayout(device.handle(), &info, nullptr, &layout));
    return OwnedPipelineLayout(device, layout);
}

/// trace.comp with specialization constant 0 (TRAVERSAL) set to `traversal`.
OwnedPipeline create_trace_pipeline(const Device& device, VkPipelineLayout layout, VkShaderModule module,
                                    std::uint32_t traversal) {
    VkSpecializationMapEntry entry{0, 0, sizeof(std::uint32_t)};
    VkSpecializationInfo specialization{1, &entry, sizeof(traversal), &traversal};
    VkComputePipelineCreateInfo info{VK_STRUCTURE_TYPE_COMPUTE_PIPELINE_CREATE_INFO};
    info.stage.sType = VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO;
    info.stage.stage = VK_SHADER_STAGE_COMPUTE_BIT;
    info.stage.module = module;
    info.stage.pName = "main";
    info.stage.pSpecializationInfo = &specialization;
    info.layout = layout;
    VkPipeline pipeline = VK_NULL_HANDLE;
    VK_CHECK(device.fn().vkCreateComputePipelines(device.handle(), VK_NULL_HANDLE, 1, &info, nullptr, &pipeline));
    return OwnedPipeline(device, pipeline);
}

}  // namespace

Pipelines::Pipelines(const Device& device)
    : set_layout_(create_set_layout(device)), layout_(create_pipeline_layout(device, set_layout_.get())) {
    OwnedShaderModule trace = make_shader_module(device, trace_comp_spirv());
    for (std::uint32_t traversal : {gpu::TRAVERSAL_STACK, gpu::TRAVERSAL_STACKLESS})
        trace_[traversal] = create_trace_pipeline(device, layout_.get(), trace.get(), traversal);
    overlay_ = create_overlay_pipeline(device, layout_.get());
}

}  // namespace bvhlab::vk
