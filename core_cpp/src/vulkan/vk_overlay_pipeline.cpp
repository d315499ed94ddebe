// The overlay graphics pipeline (report §3.3): the fixed-function state of a depth-tested line
// drawing; everything per frame (viewport, scissor, line width) is dynamic.
#include "vk_check.h"
#include "vk_pipelines.h"
#include "vk_shaders.h"

namespace bvhlab::vk {
namespace {

VkPipelineShaderStageCreateInfo shader_stage(VkShaderStageFlagBits stage, VkShaderModule module) {
    VkPipelineShaderStageCreateInfo info{VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO};
    info.stage = stage;
    info.module = module;
    info.pName = "main";
    return info;
}

/// The state structs a graphics pipeline points to, filled for the overlay's lines.
struct OverlayState {
    VkPipelineVertexInputStateCreateInfo vertex_input{VK_STRUCTURE_TYPE_PIPELINE_VERTEX_INPUT_STATE_CREATE_INFO};
    VkPipelineInputAssemblyStateCreateInfo assembly{VK_STRUCTURE_TYPE_PIPELINE_INPUT_ASSEMBLY_STATE_CREATE_INFO};
    VkPipelineViewportStateCreateInfo viewport{VK_STRUCTURE_TYPE_PIPELINE_VIEWPORT_STATE_CREATE_INFO};
    VkPipelineRasterizationStateCreateInfo raster{VK_STRUCTURE_TYPE_PIPELINE_RASTERIZATION_STATE_CREATE_INFO};
    VkPipelineMultisampleStateCreateInfo multisample{VK_STRUCTURE_TYPE_PIPELINE_MULTISAMPLE_STATE_CREATE_INFO};
    VkPipelineDepthStencilStateCreateInfo depth{VK_STRUCTURE_TYPE_PIPELINE_DEPTH_STENCIL_STATE_CREATE_INFO};
    VkPipelineColorBlendAttachmentState blend_attachment{};
    VkPipelineColorBlendStateCreateInfo blend{VK_STRUCTURE_TYPE_PIPELINE_COLOR_BLEND_STATE_CREATE_INFO};
    VkDynamicState dynamic_states[3] = {VK_DYNAMIC_STATE_VIEWPORT, VK_DYNAMIC_STATE_SCISSOR,
                                        VK_DYNAMIC_STATE_LINE_WIDTH};
    VkPipelineDynamicStateCreateInfo dynamic{VK_STRUCTURE_TYPE_PIPELINE_DYNAMIC_STATE_CREATE_INFO};
    VkFormat color_format = kColorFormat;
    VkPipelineRenderingCreateInfo rendering{VK_STRUCTURE_TYPE_PIPELINE_RENDERING_CREATE_INFO};
    VkPipelineRasterizationLineStateCreateInfoEXT line{
        VK_STRUCTURE_TYPE_PIPELINE_RASTERIZATION_LINE_STATE_CREATE_INFO_EXT};

    explicit OverlayState(bool bresenham) {
        if (bresenham) {  // one pixel a column or row, as the CPU reference steps (overlay_cpu.cpp)
            line.lineRasterizationMode = VK_LINE_RASTERIZATION_MODE_BRESENHAM_EXT;
            raster.pNext = &line;
        }
        assembly.topology = VK_PRIMITIVE_TOPOLOGY_LINE_LIST;
        viewport.viewportCount = viewport.scissorCount = 1;
        raster.polygonMode = VK_POLYGON_MODE_FILL;
        raster.cullMode = VK_CULL_MODE_NONE;
        raster.lineWidth = 1.0f;  // dynamic: set per frame
        multisample.rasterizationSamples = VK_SAMPLE_COUNT_1_BIT;
        // the nearest line wins a pixel, so alpha holds the distance the trace pass compares to
        depth.depthTestEnable = depth.depthWriteEnable = VK_TRUE;
        depth.depthCompareOp = VK_COMPARE_OP_LESS;
        blend_attachment.colorWriteMask =
            VK_COLOR_COMPONENT_R_BIT | VK_COLOR_COMPONENT_G_BIT | VK_COLOR_COMPONENT_B_BIT | VK_COLOR_COMPONENT_A_BIT;
        blend.attachmentCount = 1;
        blend.pAttachments = &blend_attachment;
        dynamic.dynamicStateCount = 3;
        dynamic.pDynamicStates = dynamic_states;
        rendering.colorAttachmentCount = 1;
        rendering.pColorAttachmentFormats = &color_format;
        rendering.depthAttachmentFormat = kDepthFormat;
    }
    OverlayState(const OverlayState&) = delete;  // holds pointers to its own members
};

}  // namespace

OwnedPipeline create_overlay_pipeline(const Device& device, VkPipelineLayout layout) {
    OwnedShaderModule vert = make_shader_module(device, overlay_vert_spirv());
    OwnedShaderModule frag = make_shader_module(device, overlay_frag_spirv());
    VkPipelineShaderStageCreateInfo stages[2] = {shader_stage(VK_SHADER_STAGE_VERTEX_BIT, vert.get()),
                                                 shader_stage(VK_SHADER_STAGE_FRAGMENT_BIT, frag.get())};
    const OverlayState s(device.physical().bresenham_lines);
    VkGraphicsPipelineCreateInfo info{VK_STRUCTURE_TYPE_GRAPHICS_PIPELINE_CREATE_INFO, &s.rendering};
    info.stageCount = 2;
    info.pStages = stages;
    info.pVertexInputState = &s.vertex_input;
    info.pInputAssemblyState = &s.assembly;
    info.pViewportState = &s.viewport;
    info.pRasterizationState = &s.raster;
    info.pMultisampleState = &s.multisample;
    info.pDepthStencilState = &s.depth;
    info.pColorBlendState = &s.blend;
    info.pDynamicState = &s.dynamic;
    info.layout = layout;
    VkPipeline pipeline = VK_NULL_HANDLE;
    VK_CHECK(device.fn().vkCreateGraphicsPipelines(device.handle(), VK_NULL_HANDLE, 1, &info, nullptr, &pipeline));
    return OwnedPipeline(device, pipeline);
}

}  // namespace bvhlab::vk
