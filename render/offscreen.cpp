#include "hemo/render/renderer.hpp"

#include "hemo/shaders.hpp"
#include "interface/render.h"

#include <glm/geometric.hpp>
#include <glm/vector_relational.hpp>
#include <glm/gtc/matrix_transform.hpp>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <stdexcept>
#include <string>

namespace hemo::render {
namespace {

struct ParticlePush {
  glm::mat4 viewProj;
  glm::vec4 right, up;
  std::uint32_t show[4];
  glm::vec4 cut;
};
static_assert(sizeof(ParticlePush) == 128);

struct SpringPush {
  glm::mat4 viewProj;
  glm::vec4 period;  // w: strain scale
  std::uint32_t flags[4];
};
static_assert(sizeof(SpringPush) == 96);
static_assert(HEMO_RENDER_SPRINGS_BINDING_COUNT == HEMO_RENDER_BINDING_COUNT,
              "particles and springs share one descriptor set layout");

struct SurfacePush {
  glm::mat4 viewProj;
  glm::vec4 eye, light, color;
};
static_assert(sizeof(SurfacePush) == 112);

struct WallPush {
  glm::mat4 viewProj;
  glm::vec4 period;  // w: strain scale
  glm::vec4 origin;  // w: opacity
  glm::vec4 eye;     // w: cutaway on
  glm::vec4 cut;
};
static_assert(sizeof(WallPush) == 128);

constexpr std::uint32_t kMaxParticleSets = 16;

}  // namespace

Camera Camera::framing(glm::vec3 lo, glm::vec3 hi, float aspect, glm::vec3 direction) {
  Camera c;
  c.target = 0.5f * (lo + hi);
  const float radius = std::max(0.5f * glm::length(hi - lo), 1e-6f);
  const glm::vec3 dir = glm::normalize(direction);
  if (std::abs(glm::dot(dir, c.up)) > 0.999f) c.up = glm::vec3(0.0f, 1.0f, 0.0f);
  // Far enough that the bounding sphere fits both fields of view; then closer, as long as
  // the box's eight corners stay inside 95% of the image (bisection).
  const float halfY = 0.5f * c.fovY;
  const float halfX = std::atan(std::tan(halfY) * std::max(aspect, 1e-3f));
  float far = radius / std::sin(std::min(halfX, halfY)) * 1.02f;
  float near = radius * 1.05f;
  const auto fits = [&](float distance) {
    Camera t = c;
    t.eye = c.target + dir * distance;
    t.nearPlane = std::max(distance - 1.5f * radius, 1e-3f * distance);
    t.farPlane = distance + 1.5f * radius;
    const glm::mat4 m = t.projection(aspect) * t.view();
    for (int k = 0; k < 8; ++k) {
      const glm::vec3 corner((k & 1) ? hi.x : lo.x, (k & 2) ? hi.y : lo.y, (k & 4) ? hi.z : lo.z);
      const glm::vec4 clip = m * glm::vec4(corner, 1.0f);
      if (clip.w <= 0.0f || std::abs(clip.x / clip.w) > 0.95f || std::abs(clip.y / clip.w) > 0.95f) return false;
    }
    return true;
  };
  if (fits(near)) {
    far = near;
  } else {
    for (int i = 0; i < 30; ++i) {
      const float mid = 0.5f * (near + far);
      (fits(mid) ? far : near) = mid;
    }
  }
  c.eye = c.target + dir * far;
  // Generous depth range: things may come closer than the box (escaping blood).
  c.nearPlane = 0.02f * far;
  c.farPlane = far + 4.0f * radius;
  return c;
}

Camera defaultCamera(const std::vector<glm::vec4>& positions, float aspect, bool vessel) {
  glm::vec3 lo(3e38f), hi(-3e38f);
  for (const glm::vec4& q : positions) {
    if (std::isfinite(q.x) && std::isfinite(q.y) && std::isfinite(q.z)) {
      lo = glm::min(lo, glm::vec3(q));
      hi = glm::max(hi, glm::vec3(q));
    }
  }
  if (lo.x > hi.x) lo = hi = glm::vec3(0.0f);  // nothing finite: look at the origin
  glm::vec3 from(0.45f, -1.0f, 0.4f);
  if (vessel) {
    // Across the axis from the side, or from above when the vessel spreads wider across y
    // than it stands in z (a bifurcation's branches would hide each other from the side).
    from = hi.y - lo.y > 1.3f * (hi.z - lo.z) ? glm::vec3(0.0f, -0.35f, 1.0f) : glm::vec3(0.0f, -1.0f, 0.45f);
  }
  return Camera::framing(lo, hi, aspect, from);
}

glm::mat4 Camera::view() const { return glm::lookAtRH(eye, target, up); }

glm::mat4 Camera::projection(float aspect) const {
  glm::mat4 p = glm::perspectiveRH_ZO(fovY, aspect, nearPlane, farPlane);
  p[1][1] = -p[1][1];  // Vulkan's y points down
  return p;
}

OffscreenRenderer::OffscreenRenderer(gpu::Context& context, std::uint32_t width, std::uint32_t height)
    : context_(&context),
      width_(width),
      height_(height),
      pixels_(context, VkDeviceSize(width) * height * 4, gpu::MemoryUse::Readback, "rendered pixels"),
      noShade_(context, 16, gpu::MemoryUse::Device, "no wall shade") {
  if (width == 0 || height == 0 || width > 8192 || height > 8192) {
    throw std::invalid_argument("image size " + std::to_string(width) + "x" + std::to_string(height) +
                                " is outside 1..8192");
  }
  createTargets();
  createPipelines();
}

OffscreenRenderer::~OffscreenRenderer() {
  VkDevice d = context_->device();
  vkDeviceWaitIdle(d);
  if (particlePipeline_) vkDestroyPipeline(d, particlePipeline_, nullptr);
  if (surfacePipeline_) vkDestroyPipeline(d, surfacePipeline_, nullptr);
  if (particlePipelineLayout_) vkDestroyPipelineLayout(d, particlePipelineLayout_, nullptr);
  if (springPipeline_) vkDestroyPipeline(d, springPipeline_, nullptr);
  if (springPipelineLayout_) vkDestroyPipelineLayout(d, springPipelineLayout_, nullptr);
  if (wallOpaquePipeline_) vkDestroyPipeline(d, wallOpaquePipeline_, nullptr);
  if (wallBlendPipeline_) vkDestroyPipeline(d, wallBlendPipeline_, nullptr);
  if (wallPipelineLayout_) vkDestroyPipelineLayout(d, wallPipelineLayout_, nullptr);
  if (surfacePipelineLayout_) vkDestroyPipelineLayout(d, surfacePipelineLayout_, nullptr);
  if (pool_) vkDestroyDescriptorPool(d, pool_, nullptr);
  if (particleLayout_) vkDestroyDescriptorSetLayout(d, particleLayout_, nullptr);
  for (VkShaderModule m : modules_) vkDestroyShaderModule(d, m, nullptr);
  if (framebuffer_) vkDestroyFramebuffer(d, framebuffer_, nullptr);
  if (renderPass_) vkDestroyRenderPass(d, renderPass_, nullptr);
  if (colorView_) vkDestroyImageView(d, colorView_, nullptr);
  if (depthView_) vkDestroyImageView(d, depthView_, nullptr);
  if (color_) vkDestroyImage(d, color_, nullptr);
  if (depth_) vkDestroyImage(d, depth_, nullptr);
  if (colorMemory_) vkFreeMemory(d, colorMemory_, nullptr);
  if (depthMemory_) vkFreeMemory(d, depthMemory_, nullptr);
}

void OffscreenRenderer::createTargets() {
  VkDevice d = context_->device();
  for (VkFormat f : {VK_FORMAT_D32_SFLOAT, VK_FORMAT_X8_D24_UNORM_PACK32, VK_FORMAT_D24_UNORM_S8_UINT}) {
    VkFormatProperties props;
    vkGetPhysicalDeviceFormatProperties(context_->physicalDevice(), f, &props);
    if (props.optimalTilingFeatures & VK_FORMAT_FEATURE_DEPTH_STENCIL_ATTACHMENT_BIT) {
      depthFormat_ = f;
      break;
    }
  }
  if (depthFormat_ == VK_FORMAT_UNDEFINED) throw gpu::GpuError("the device has no depth attachment format");

  const auto makeImage = [&](VkFormat format, VkImageUsageFlags usage, VkImageAspectFlags aspect, VkImage& image,
                             VkDeviceMemory& memory, VkImageView& view) {
    VkImageCreateInfo info{VK_STRUCTURE_TYPE_IMAGE_CREATE_INFO};
    info.imageType = VK_IMAGE_TYPE_2D;
    info.format = format;
    info.extent = {width_, height_, 1};
    info.mipLevels = 1;
    info.arrayLayers = 1;
    info.samples = VK_SAMPLE_COUNT_1_BIT;
    info.tiling = VK_IMAGE_TILING_OPTIMAL;
    info.usage = usage;
    info.initialLayout = VK_IMAGE_LAYOUT_UNDEFINED;
    gpu::check(vkCreateImage(d, &info, nullptr, &image), "vkCreateImage");
    VkMemoryRequirements req;
    vkGetImageMemoryRequirements(d, image, &req);
    VkMemoryAllocateInfo alloc{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO};
    alloc.allocationSize = req.size;
    alloc.memoryTypeIndex = context_->memoryType(req.memoryTypeBits, 0, VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT);
    gpu::check(vkAllocateMemory(d, &alloc, nullptr, &memory), "vkAllocateMemory (render target)");
    gpu::check(vkBindImageMemory(d, image, memory, 0), "vkBindImageMemory");
    VkImageViewCreateInfo v{VK_STRUCTURE_TYPE_IMAGE_VIEW_CREATE_INFO};
    v.image = image;
    v.viewType = VK_IMAGE_VIEW_TYPE_2D;
    v.format = format;
    v.subresourceRange = {aspect, 0, 1, 0, 1};
    gpu::check(vkCreateImageView(d, &v, nullptr, &view), "vkCreateImageView");
  };
  makeImage(VK_FORMAT_R8G8B8A8_UNORM, VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT | VK_IMAGE_USAGE_TRANSFER_SRC_BIT,
            VK_IMAGE_ASPECT_COLOR_BIT, color_, colorMemory_, colorView_);
  makeImage(depthFormat_, VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT, VK_IMAGE_ASPECT_DEPTH_BIT, depth_, depthMemory_,
            depthView_);

  VkAttachmentDescription attachments[2]{};
  attachments[0].format = VK_FORMAT_R8G8B8A8_UNORM;
  attachments[0].samples = VK_SAMPLE_COUNT_1_BIT;
  attachments[0].loadOp = VK_ATTACHMENT_LOAD_OP_CLEAR;
  attachments[0].storeOp = VK_ATTACHMENT_STORE_OP_STORE;
  attachments[0].stencilLoadOp = VK_ATTACHMENT_LOAD_OP_DONT_CARE;
  attachments[0].stencilStoreOp = VK_ATTACHMENT_STORE_OP_DONT_CARE;
  attachments[0].initialLayout = VK_IMAGE_LAYOUT_UNDEFINED;
  attachments[0].finalLayout = VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL;
  attachments[1].format = depthFormat_;
  attachments[1].samples = VK_SAMPLE_COUNT_1_BIT;
  attachments[1].loadOp = VK_ATTACHMENT_LOAD_OP_CLEAR;
  attachments[1].storeOp = VK_ATTACHMENT_STORE_OP_DONT_CARE;
  attachments[1].stencilLoadOp = VK_ATTACHMENT_LOAD_OP_DONT_CARE;
  attachments[1].stencilStoreOp = VK_ATTACHMENT_STORE_OP_DONT_CARE;
  attachments[1].initialLayout = VK_IMAGE_LAYOUT_UNDEFINED;
  attachments[1].finalLayout = VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL;
  VkAttachmentReference colorRef{0, VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL};
  VkAttachmentReference depthRef{1, VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL};
  VkSubpassDescription subpass{};
  subpass.pipelineBindPoint = VK_PIPELINE_BIND_POINT_GRAPHICS;
  subpass.colorAttachmentCount = 1;
  subpass.pColorAttachments = &colorRef;
  subpass.pDepthStencilAttachment = &depthRef;
  // In: the previous frame's copy (transfer read) and depth writes finish before this frame
  // clears. Out: colour writes finish before the copy to host memory.
  VkSubpassDependency deps[2]{};
  deps[0].srcSubpass = VK_SUBPASS_EXTERNAL;
  deps[0].dstSubpass = 0;
  deps[0].srcStageMask = VK_PIPELINE_STAGE_TRANSFER_BIT | VK_PIPELINE_STAGE_COLOR_ATTACHMENT_OUTPUT_BIT |
                         VK_PIPELINE_STAGE_LATE_FRAGMENT_TESTS_BIT;
  deps[0].srcAccessMask = VK_ACCESS_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT | VK_ACCESS_COLOR_ATTACHMENT_WRITE_BIT;
  deps[0].dstStageMask = VK_PIPELINE_STAGE_COLOR_ATTACHMENT_OUTPUT_BIT | VK_PIPELINE_STAGE_EARLY_FRAGMENT_TESTS_BIT;
  deps[0].dstAccessMask = VK_ACCESS_COLOR_ATTACHMENT_WRITE_BIT | VK_ACCESS_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT |
                          VK_ACCESS_DEPTH_STENCIL_ATTACHMENT_READ_BIT;
  deps[1].srcSubpass = 0;
  deps[1].dstSubpass = VK_SUBPASS_EXTERNAL;
  deps[1].srcStageMask = VK_PIPELINE_STAGE_COLOR_ATTACHMENT_OUTPUT_BIT;
  deps[1].srcAccessMask = VK_ACCESS_COLOR_ATTACHMENT_WRITE_BIT;
  deps[1].dstStageMask = VK_PIPELINE_STAGE_TRANSFER_BIT;
  deps[1].dstAccessMask = VK_ACCESS_TRANSFER_READ_BIT;
  VkRenderPassCreateInfo rp{VK_STRUCTURE_TYPE_RENDER_PASS_CREATE_INFO};
  rp.attachmentCount = 2;
  rp.pAttachments = attachments;
  rp.subpassCount = 1;
  rp.pSubpasses = &subpass;
  rp.dependencyCount = 2;
  rp.pDependencies = deps;
  gpu::check(vkCreateRenderPass(d, &rp, nullptr, &renderPass_), "vkCreateRenderPass");
  VkImageView views[2] = {colorView_, depthView_};
  VkFramebufferCreateInfo fb{VK_STRUCTURE_TYPE_FRAMEBUFFER_CREATE_INFO};
  fb.renderPass = renderPass_;
  fb.attachmentCount = 2;
  fb.pAttachments = views;
  fb.width = width_;
  fb.height = height_;
  fb.layers = 1;
  gpu::check(vkCreateFramebuffer(d, &fb, nullptr, &framebuffer_), "vkCreateFramebuffer");
}

VkShaderModule OffscreenRenderer::module(const char* name) {
  const auto words = shaders::spirv(name);
  VkShaderModuleCreateInfo info{VK_STRUCTURE_TYPE_SHADER_MODULE_CREATE_INFO};
  info.codeSize = words.size_bytes();
  info.pCode = words.data();
  VkShaderModule m = VK_NULL_HANDLE;
  gpu::check(vkCreateShaderModule(context_->device(), &info, nullptr, &m), "vkCreateShaderModule");
  modules_.push_back(m);
  return m;
}

void OffscreenRenderer::createPipelines() {
  VkDevice d = context_->device();
  VkDescriptorSetLayoutBinding bindings[HEMO_RENDER_BINDING_COUNT]{};
  for (std::uint32_t b = 0; b < HEMO_RENDER_BINDING_COUNT; ++b) {
    bindings[b].binding = b;
    bindings[b].descriptorType = VK_DESCRIPTOR_TYPE_STORAGE_BUFFER;
    bindings[b].descriptorCount = 1;
    bindings[b].stageFlags = VK_SHADER_STAGE_VERTEX_BIT;
  }
  VkDescriptorSetLayoutCreateInfo layout{VK_STRUCTURE_TYPE_DESCRIPTOR_SET_LAYOUT_CREATE_INFO};
  layout.bindingCount = HEMO_RENDER_BINDING_COUNT;
  layout.pBindings = bindings;
  gpu::check(vkCreateDescriptorSetLayout(d, &layout, nullptr, &particleLayout_), "vkCreateDescriptorSetLayout");
  VkDescriptorPoolSize size{VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, HEMO_RENDER_BINDING_COUNT * kMaxParticleSets};
  VkDescriptorPoolCreateInfo pool{VK_STRUCTURE_TYPE_DESCRIPTOR_POOL_CREATE_INFO};
  pool.maxSets = kMaxParticleSets;
  pool.poolSizeCount = 1;
  pool.pPoolSizes = &size;
  gpu::check(vkCreateDescriptorPool(d, &pool, nullptr, &pool_), "vkCreateDescriptorPool");

  VkPushConstantRange particleRange{VK_SHADER_STAGE_VERTEX_BIT, 0, sizeof(ParticlePush)};
  VkPipelineLayoutCreateInfo pl{VK_STRUCTURE_TYPE_PIPELINE_LAYOUT_CREATE_INFO};
  pl.setLayoutCount = 1;
  pl.pSetLayouts = &particleLayout_;
  pl.pushConstantRangeCount = 1;
  pl.pPushConstantRanges = &particleRange;
  gpu::check(vkCreatePipelineLayout(d, &pl, nullptr, &particlePipelineLayout_), "vkCreatePipelineLayout");
  VkPushConstantRange springRange{VK_SHADER_STAGE_VERTEX_BIT, 0, sizeof(SpringPush)};
  VkPipelineLayoutCreateInfo spl = pl;
  spl.pPushConstantRanges = &springRange;
  gpu::check(vkCreatePipelineLayout(d, &spl, nullptr, &springPipelineLayout_), "vkCreatePipelineLayout");
  // The wall's surface: two sets of the same layout (interface/render.h).
  VkPushConstantRange wallRange{VK_SHADER_STAGE_VERTEX_BIT | VK_SHADER_STAGE_FRAGMENT_BIT, 0, sizeof(WallPush)};
  const VkDescriptorSetLayout wallSets[2] = {particleLayout_, particleLayout_};
  VkPipelineLayoutCreateInfo wl = pl;
  wl.setLayoutCount = 2;
  wl.pSetLayouts = wallSets;
  wl.pPushConstantRanges = &wallRange;
  gpu::check(vkCreatePipelineLayout(d, &wl, nullptr, &wallPipelineLayout_), "vkCreatePipelineLayout");
  VkPushConstantRange surfaceRange{VK_SHADER_STAGE_VERTEX_BIT | VK_SHADER_STAGE_FRAGMENT_BIT, 0, sizeof(SurfacePush)};
  VkPipelineLayoutCreateInfo sl{VK_STRUCTURE_TYPE_PIPELINE_LAYOUT_CREATE_INFO};
  sl.pushConstantRangeCount = 1;
  sl.pPushConstantRanges = &surfaceRange;
  gpu::check(vkCreatePipelineLayout(d, &sl, nullptr, &surfacePipelineLayout_), "vkCreatePipelineLayout");

  // State shared by both pipelines.
  VkPipelineInputAssemblyStateCreateInfo assembly{VK_STRUCTURE_TYPE_PIPELINE_INPUT_ASSEMBLY_STATE_CREATE_INFO};
  assembly.topology = VK_PRIMITIVE_TOPOLOGY_TRIANGLE_LIST;
  VkViewport viewport{0.0f, 0.0f, float(width_), float(height_), 0.0f, 1.0f};
  VkRect2D scissor{{0, 0}, {width_, height_}};
  VkPipelineViewportStateCreateInfo vp{VK_STRUCTURE_TYPE_PIPELINE_VIEWPORT_STATE_CREATE_INFO};
  vp.viewportCount = 1;
  vp.pViewports = &viewport;
  vp.scissorCount = 1;
  vp.pScissors = &scissor;
  VkPipelineRasterizationStateCreateInfo raster{VK_STRUCTURE_TYPE_PIPELINE_RASTERIZATION_STATE_CREATE_INFO};
  raster.polygonMode = VK_POLYGON_MODE_FILL;
  raster.cullMode = VK_CULL_MODE_NONE;
  raster.frontFace = VK_FRONT_FACE_COUNTER_CLOCKWISE;
  raster.lineWidth = 1.0f;
  VkPipelineMultisampleStateCreateInfo ms{VK_STRUCTURE_TYPE_PIPELINE_MULTISAMPLE_STATE_CREATE_INFO};
  ms.rasterizationSamples = VK_SAMPLE_COUNT_1_BIT;
  VkPipelineDepthStencilStateCreateInfo depth{VK_STRUCTURE_TYPE_PIPELINE_DEPTH_STENCIL_STATE_CREATE_INFO};
  depth.depthTestEnable = VK_TRUE;
  depth.depthWriteEnable = VK_TRUE;
  depth.depthCompareOp = VK_COMPARE_OP_LESS;
  VkPipelineColorBlendAttachmentState blendAttachment{};
  blendAttachment.colorWriteMask =
      VK_COLOR_COMPONENT_R_BIT | VK_COLOR_COMPONENT_G_BIT | VK_COLOR_COMPONENT_B_BIT | VK_COLOR_COMPONENT_A_BIT;
  VkPipelineColorBlendStateCreateInfo blend{VK_STRUCTURE_TYPE_PIPELINE_COLOR_BLEND_STATE_CREATE_INFO};
  blend.attachmentCount = 1;
  blend.pAttachments = &blendAttachment;

  const auto build = [&](VkShaderModule vert, VkShaderModule frag, const VkPipelineVertexInputStateCreateInfo& input,
                         VkPipelineLayout layoutHandle, VkPipeline& out,
                         VkPrimitiveTopology topology = VK_PRIMITIVE_TOPOLOGY_TRIANGLE_LIST) {
    assembly.topology = topology;
    VkPipelineShaderStageCreateInfo stages[2]{};
    stages[0] = {VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO};
    stages[0].stage = VK_SHADER_STAGE_VERTEX_BIT;
    stages[0].module = vert;
    stages[0].pName = "main";
    stages[1] = {VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO};
    stages[1].stage = VK_SHADER_STAGE_FRAGMENT_BIT;
    stages[1].module = frag;
    stages[1].pName = "main";
    VkGraphicsPipelineCreateInfo info{VK_STRUCTURE_TYPE_GRAPHICS_PIPELINE_CREATE_INFO};
    info.stageCount = 2;
    info.pStages = stages;
    info.pVertexInputState = &input;
    info.pInputAssemblyState = &assembly;
    info.pViewportState = &vp;
    info.pRasterizationState = &raster;
    info.pMultisampleState = &ms;
    info.pDepthStencilState = &depth;
    info.pColorBlendState = &blend;
    info.layout = layoutHandle;
    info.renderPass = renderPass_;
    gpu::check(vkCreateGraphicsPipelines(d, VK_NULL_HANDLE, 1, &info, nullptr, &out), "vkCreateGraphicsPipelines");
  };

  VkPipelineVertexInputStateCreateInfo noInput{VK_STRUCTURE_TYPE_PIPELINE_VERTEX_INPUT_STATE_CREATE_INFO};
  build(module("render/particles.vert"), module("render/particles.frag"), noInput, particlePipelineLayout_,
        particlePipeline_);
  build(module("render/springs.vert"), module("render/springs.frag"), noInput, springPipelineLayout_, springPipeline_,
        VK_PRIMITIVE_TOPOLOGY_LINE_LIST);

  const VkShaderModule wallVert = module("render/wall_surface.vert"), wallFrag = module("render/wall_surface.frag");
  build(wallVert, wallFrag, noInput, wallPipelineLayout_, wallOpaquePipeline_);
  // Translucent: blended over what is behind (straight alpha), tested against the depth of
  // the opaque things but not writing it, so both sides of a vessel show.
  blendAttachment.blendEnable = VK_TRUE;
  blendAttachment.srcColorBlendFactor = VK_BLEND_FACTOR_SRC_ALPHA;
  blendAttachment.dstColorBlendFactor = VK_BLEND_FACTOR_ONE_MINUS_SRC_ALPHA;
  blendAttachment.colorBlendOp = VK_BLEND_OP_ADD;
  blendAttachment.srcAlphaBlendFactor = VK_BLEND_FACTOR_ONE;
  blendAttachment.dstAlphaBlendFactor = VK_BLEND_FACTOR_ONE_MINUS_SRC_ALPHA;
  blendAttachment.alphaBlendOp = VK_BLEND_OP_ADD;
  depth.depthWriteEnable = VK_FALSE;
  build(wallVert, wallFrag, noInput, wallPipelineLayout_, wallBlendPipeline_);
  blendAttachment.blendEnable = VK_FALSE;
  depth.depthWriteEnable = VK_TRUE;

  VkVertexInputBindingDescription binding{0, HEMO_RENDER_SURFACE_STRIDE, VK_VERTEX_INPUT_RATE_VERTEX};
  VkVertexInputAttributeDescription attributes[2] = {{0, 0, VK_FORMAT_R32G32B32A32_SFLOAT, 0},
                                                     {1, 0, VK_FORMAT_R32G32B32A32_SFLOAT, 16}};
  VkPipelineVertexInputStateCreateInfo surfaceInput{VK_STRUCTURE_TYPE_PIPELINE_VERTEX_INPUT_STATE_CREATE_INFO};
  surfaceInput.vertexBindingDescriptionCount = 1;
  surfaceInput.pVertexBindingDescriptions = &binding;
  surfaceInput.vertexAttributeDescriptionCount = 2;
  surfaceInput.pVertexAttributeDescriptions = attributes;
  build(module("render/surface.vert"), module("render/surface.frag"), surfaceInput, surfacePipelineLayout_,
        surfacePipeline_);
}

VkDescriptorSet OffscreenRenderer::storageSet(const gpu::Buffer& b0, const gpu::Buffer& b1, const gpu::Buffer& b2) {
  const auto key = std::make_tuple(b0.handle(), b1.handle(), b2.handle());
  if (auto it = storageSets_.find(key); it != storageSets_.end()) return it->second;
  if (storageSets_.size() >= kMaxParticleSets) {
    throw std::invalid_argument("the renderer draws from at most " + std::to_string(kMaxParticleSets) +
                                " different sets of buffers");
  }
  VkDescriptorSetAllocateInfo alloc{VK_STRUCTURE_TYPE_DESCRIPTOR_SET_ALLOCATE_INFO};
  alloc.descriptorPool = pool_;
  alloc.descriptorSetCount = 1;
  alloc.pSetLayouts = &particleLayout_;
  VkDescriptorSet set = VK_NULL_HANDLE;
  gpu::check(vkAllocateDescriptorSets(context_->device(), &alloc, &set), "vkAllocateDescriptorSets");
  VkDescriptorBufferInfo infos[3] = {{b0.handle(), 0, VK_WHOLE_SIZE}, {b1.handle(), 0, VK_WHOLE_SIZE},
                                     {b2.handle(), 0, VK_WHOLE_SIZE}};
  VkWriteDescriptorSet writes[3]{};
  for (std::uint32_t b = 0; b < 3; ++b) {
    writes[b] = {VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET};
    writes[b].dstSet = set;
    writes[b].dstBinding = b;
    writes[b].descriptorCount = 1;
    writes[b].descriptorType = VK_DESCRIPTOR_TYPE_STORAGE_BUFFER;
    writes[b].pBufferInfo = &infos[b];
  }
  vkUpdateDescriptorSets(context_->device(), 3, writes, 0, nullptr);
  storageSets_.emplace(key, set);
  return set;
}

void OffscreenRenderer::record(gpu::CommandRecorder& rec, const Camera& camera, const FrameOptions& options,
                               const ParticleView& particles, const surface::MarchingCubes* surface,
                               const SpringView* springs, const ToolView* tools, const WallSurfaceView* wall) {
  // The tools' triangles: written to host memory, copied to a vertex buffer before the
  // barrier below (which orders transfers before drawing too).
  std::uint32_t toolVertices = 0;
  if (tools && tools->tools && !tools->tools->empty()) {
    const std::vector<glm::vec4> mesh = toolTriangles(*tools->tools, tools->time);
    const VkDeviceSize bytes = mesh.size() * sizeof(glm::vec4);
    if (bytes > toolStaging_.size()) {
      toolStaging_ = gpu::Buffer(*context_, bytes, gpu::MemoryUse::Upload, "tool triangles (host)");
      toolVertices_ = gpu::Buffer(*context_, bytes, gpu::MemoryUse::Device, "tool triangles");
    }
    toolStaging_.upload(mesh);
    rec.copy(toolStaging_, toolVertices_, bytes);
    toolVertices = static_cast<std::uint32_t>(mesh.size() / 2);
  }
  const bool drawParticles = particles.count > 0 && options.particleRadius > 0.0f &&
                             (options.fluid || options.wall || options.boundary);
  if (drawParticles && (!particles.positions || !particles.velocities)) {
    throw std::invalid_argument("particle view without buffers");
  }
  static_assert(HEMO_RENDER_BINDING_POSITIONS == 0 && HEMO_RENDER_BINDING_VELOCITIES == 1 &&
                HEMO_RENDER_BINDING_WALL_SHADE == 2 && HEMO_RENDER_SPRINGS_BINDING_POSITIONS == 0 &&
                HEMO_RENDER_SPRINGS_BINDING_SLOT_OF_ID == 1 && HEMO_RENDER_SPRINGS_BINDING_SPRINGS == 2);
  const VkDescriptorSet set =
      drawParticles ? storageSet(*particles.positions, *particles.velocities,
                                 particles.wallShade ? *particles.wallShade : noShade_)
                    : VK_NULL_HANDLE;
  const bool drawSprings = options.springs && springs && springs->count > 0;
  if (drawSprings && (!springs->positions || !springs->slotOfId || !springs->springs)) {
    throw std::invalid_argument("spring view without buffers");
  }
  const VkDescriptorSet springSet =
      drawSprings ? storageSet(*springs->positions, *springs->slotOfId, *springs->springs) : VK_NULL_HANDLE;
  const bool drawWall = wall && wall->count > 0 && options.wallOpacity > 0.0f;
  if (drawWall && (!wall->positions || !wall->slotOfId || !wall->springs || !wall->triangles || !wall->normals ||
                   !wall->shade)) {
    throw std::invalid_argument("wall surface view without buffers");
  }
  const VkDescriptorSet wallSets[2] = {
      drawWall ? storageSet(*wall->positions, *wall->slotOfId, *wall->springs) : VK_NULL_HANDLE,
      drawWall ? storageSet(*wall->triangles, *wall->normals, *wall->shade) : VK_NULL_HANDLE};
  rec.computeToGraphics();
  VkCommandBuffer cmd = rec.handle();
  VkClearValue clears[2]{};
  clears[0].color = {{options.background.r, options.background.g, options.background.b, options.background.a}};
  clears[1].depthStencil = {1.0f, 0};
  VkRenderPassBeginInfo begin{VK_STRUCTURE_TYPE_RENDER_PASS_BEGIN_INFO};
  begin.renderPass = renderPass_;
  begin.framebuffer = framebuffer_;
  begin.renderArea = {{0, 0}, {width_, height_}};
  begin.clearValueCount = 2;
  begin.pClearValues = clears;
  vkCmdBeginRenderPass(cmd, &begin, VK_SUBPASS_CONTENTS_INLINE);

  const float aspect = float(width_) / float(height_);
  const glm::mat4 view = camera.view();
  const glm::mat4 viewProj = camera.projection(aspect) * view;
  if (drawParticles) {
    ParticlePush push{};
    push.viewProj = viewProj;
    // Camera axes in world space: the rows of the view matrix's rotation.
    push.right = glm::vec4(view[0][0], view[1][0], view[2][0], options.particleRadius);
    push.up = glm::vec4(view[0][1], view[1][1], view[2][1], std::max(options.speedScale, 1e-9f));
    push.show[0] = options.fluid;
    push.show[1] = options.wall;
    push.show[2] = options.boundary;
    const float strainScale = particles.wallShade ? std::max(options.strainScale, 1e-9f) : 0.0f;
    std::memcpy(&push.show[3], &strainScale, sizeof(float));
    if (options.cutaway) {
      // The plane through the target facing the camera: the near half of the wall goes.
      const glm::vec3 n = glm::normalize(camera.eye - camera.target);
      push.cut = glm::vec4(n, glm::dot(n, camera.target));
    }
    vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, particlePipeline_);
    vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, particlePipelineLayout_, 0, 1, &set, 0, nullptr);
    vkCmdPushConstants(cmd, particlePipelineLayout_, VK_SHADER_STAGE_VERTEX_BIT, 0, sizeof(push), &push);
    vkCmdDraw(cmd, 6, particles.count, 0, 0);
  }
  if (drawSprings) {
    SpringPush push{};
    push.viewProj = viewProj;
    push.period = glm::vec4(springs->period, std::max(options.strainScale, 1e-9f));
    push.flags[0] = options.brokenSprings;
    vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, springPipeline_);
    vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, springPipelineLayout_, 0, 1, &springSet, 0, nullptr);
    vkCmdPushConstants(cmd, springPipelineLayout_, VK_SHADER_STAGE_VERTEX_BIT, 0, sizeof(push), &push);
    vkCmdDraw(cmd, 2 * springs->count, 1, 0, 0);
  }
  if (surface) {
    SurfacePush push{};
    push.viewProj = viewProj;
    push.eye = glm::vec4(camera.eye, 1.0f);
    push.light = glm::vec4(glm::normalize(options.lightDirection), 0.0f);
    push.color = glm::vec4(options.surfaceColor, 1.0f);
    vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, surfacePipeline_);
    vkCmdPushConstants(cmd, surfacePipelineLayout_, VK_SHADER_STAGE_VERTEX_BIT | VK_SHADER_STAGE_FRAGMENT_BIT, 0,
                       sizeof(push), &push);
    const VkBuffer vertices = surface->vertices().handle();
    const VkDeviceSize offset = 0;
    vkCmdBindVertexBuffers(cmd, 0, 1, &vertices, &offset);
    vkCmdDrawIndirect(cmd, surface->args().handle(), surface::MarchingCubes::drawArgsOffset(), 1,
                      sizeof(VkDrawIndirectCommand));
  }
  if (toolVertices > 0) {  // lit like the surface, in the tools' colour
    SurfacePush push{};
    push.viewProj = viewProj;
    push.eye = glm::vec4(camera.eye, 1.0f);
    push.light = glm::vec4(glm::normalize(options.lightDirection), 0.0f);
    push.color = glm::vec4(tools->color, 1.0f);
    vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, surfacePipeline_);
    vkCmdPushConstants(cmd, surfacePipelineLayout_, VK_SHADER_STAGE_VERTEX_BIT | VK_SHADER_STAGE_FRAGMENT_BIT, 0,
                       sizeof(push), &push);
    const VkBuffer vertices = toolVertices_.handle();
    const VkDeviceSize offset = 0;
    vkCmdBindVertexBuffers(cmd, 0, 1, &vertices, &offset);
    vkCmdDraw(cmd, toolVertices, 1, 0, 0);
  }
  if (drawWall) {
    WallPush push{};
    push.viewProj = viewProj;
    push.period = glm::vec4(wall->period, std::max(options.strainScale, 1e-9f));
    push.origin = glm::vec4(wall->origin, std::min(options.wallOpacity, 1.0f));
    push.eye = glm::vec4(camera.eye, options.cutaway ? 1.0f : 0.0f);
    if (options.cutaway) {
      const glm::vec3 n = glm::normalize(camera.eye - camera.target);
      push.cut = glm::vec4(n, glm::dot(n, camera.target));
    }
    vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS,
                      options.wallOpacity >= 1.0f ? wallOpaquePipeline_ : wallBlendPipeline_);
    vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, wallPipelineLayout_, 0, 2, wallSets, 0, nullptr);
    vkCmdPushConstants(cmd, wallPipelineLayout_, VK_SHADER_STAGE_VERTEX_BIT | VK_SHADER_STAGE_FRAGMENT_BIT, 0,
                       sizeof(push), &push);
    // Instance 1: the copies of triangles across a periodic seam (render/shaders/wall_surface.vert).
    vkCmdDraw(cmd, 3 * wall->count, glm::any(glm::greaterThan(wall->period, glm::vec3(0.0f))) ? 2 : 1, 0, 0);
  }
  if (overlay_) overlay_(cmd);
  vkCmdEndRenderPass(cmd);

  VkBufferImageCopy copy{};
  copy.imageSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 0, 1};
  copy.imageExtent = {width_, height_, 1};
  vkCmdCopyImageToBuffer(cmd, color_, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, pixels_.handle(), 1, &copy);
}

std::vector<std::uint8_t> OffscreenRenderer::readPixels() const {
  return pixels_.readback<std::uint8_t>(std::size_t(width_) * height_ * 4);
}

}  // namespace hemo::render
