#include "hemo/gpu/pipeline.hpp"

#include "hemo/shaders.hpp"
#include "interface/spec.h"

#include <algorithm>
#include <bit>
#include <stdexcept>
#include <utility>

namespace hemo::gpu {

DescriptorSet::~DescriptorSet() { release(); }

DescriptorSet::DescriptorSet(DescriptorSet&& other) noexcept { *this = std::move(other); }

DescriptorSet& DescriptorSet::operator=(DescriptorSet&& other) noexcept {
  if (this != &other) {
    release();
    device_ = std::exchange(other.device_, VK_NULL_HANDLE);
    pool_ = std::exchange(other.pool_, VK_NULL_HANDLE);
    set_ = std::exchange(other.set_, VK_NULL_HANDLE);
    views_ = std::exchange(other.views_, {});
    bound_ = std::exchange(other.bound_, {});
  }
  return *this;
}

void DescriptorSet::release() {
  if (pool_) vkDestroyDescriptorPool(device_, pool_, nullptr);  // frees the set too
  for (VkBufferView view : views_) vkDestroyBufferView(device_, view, nullptr);
  views_.clear();
  bound_.clear();
  pool_ = VK_NULL_HANDLE;
  set_ = VK_NULL_HANDLE;
}

ComputePipeline::ComputePipeline(Context& context, const PipelineDesc& desc)
    : context_(&context),
      bindingCount_(desc.bindingCount),
      uniformSlots_(desc.uniformSlots),
      texelSlots_(desc.texelSlots),
      storageTexelSlots_(desc.storageTexelSlots),
      pushBytes_(desc.pushConstantBytes),
      workgroupSize_(desc.workgroupSize),
      name_(desc.shader) {
  const auto& limits = context.limits();
  if (workgroupSize_ == 0 || workgroupSize_ > limits.maxComputeWorkGroupSize[0] ||
      workgroupSize_ > limits.maxComputeWorkGroupInvocations) {
    throw GpuError("workgroup size " + std::to_string(workgroupSize_) + " for '" + name_ +
                   "' is outside the device's limits (max " +
                   std::to_string(limits.maxComputeWorkGroupSize[0]) + ")");
  }
  if (bindingCount_ < 32 && ((uniformSlots_ | texelSlots_ | storageTexelSlots_) >> bindingCount_) != 0) {
    throw GpuError("uniform or texel slots of '" + name_ + "' name a slot beyond its " +
                   std::to_string(bindingCount_) + " bindings");
  }
  if ((uniformSlots_ & texelSlots_) != 0 || (storageTexelSlots_ & (uniformSlots_ | texelSlots_)) != 0) {
    throw GpuError("'" + name_ + "' declares a slot of two kinds (uniform, texel, storage texel)");
  }
  // Descriptors of each kind against the device's per-stage limits (Vulkan guarantees only 4
  // storage buffers; desktop GPUs allow far more, and the SPH passes bind up to 17 slots).
  const DescriptorCounts n = descriptorCounts();
  const struct {
    std::uint32_t count, limit;
    const char* what;
  } kinds[] = {{n.storage, limits.maxPerStageDescriptorStorageBuffers, "storage buffers (maxPerStageDescriptorStorageBuffers"},
               {n.uniform, limits.maxPerStageDescriptorUniformBuffers, "uniform buffers (maxPerStageDescriptorUniformBuffers"},
               {n.texel, limits.maxPerStageDescriptorSampledImages, "uniform texel buffers (maxPerStageDescriptorSampledImages"},
               {n.storageTexel, limits.maxPerStageDescriptorStorageImages, "storage texel buffers (maxPerStageDescriptorStorageImages"},
               {bindingCount_, limits.maxPerStageResources, "descriptors (maxPerStageResources"}};
  for (const auto& k : kinds) {
    if (k.count > k.limit) {
      throw GpuError("'" + name_ + "' binds " + std::to_string(k.count) + " " + k.what + " is " +
                     std::to_string(k.limit) + " on this device)");
    }
  }
  if (pushBytes_ > limits.maxPushConstantsSize) {
    throw GpuError("push constants of '" + name_ + "' exceed the device's " +
                   std::to_string(limits.maxPushConstantsSize) + " bytes");
  }
  VkDevice device = context.device();
  const auto words = shaders::spirv(desc.shader);
  VkShaderModule module = VK_NULL_HANDLE;
  try {
    std::vector<VkDescriptorSetLayoutBinding> slots(bindingCount_);
    for (std::uint32_t i = 0; i < bindingCount_; ++i) {
      slots[i].binding = i;
      slots[i].descriptorType = descriptorType(i);
      slots[i].descriptorCount = 1;
      slots[i].stageFlags = VK_SHADER_STAGE_COMPUTE_BIT;
    }
    VkDescriptorSetLayoutCreateInfo setInfo{VK_STRUCTURE_TYPE_DESCRIPTOR_SET_LAYOUT_CREATE_INFO};
    setInfo.bindingCount = bindingCount_;
    setInfo.pBindings = slots.data();
    check(vkCreateDescriptorSetLayout(device, &setInfo, nullptr, &setLayout_), "vkCreateDescriptorSetLayout");

    VkPushConstantRange push{VK_SHADER_STAGE_COMPUTE_BIT, 0, pushBytes_};
    VkPipelineLayoutCreateInfo layoutInfo{VK_STRUCTURE_TYPE_PIPELINE_LAYOUT_CREATE_INFO};
    layoutInfo.setLayoutCount = 1;
    layoutInfo.pSetLayouts = &setLayout_;
    layoutInfo.pushConstantRangeCount = pushBytes_ ? 1 : 0;
    layoutInfo.pPushConstantRanges = &push;
    check(vkCreatePipelineLayout(device, &layoutInfo, nullptr, &layout_), "vkCreatePipelineLayout");

    VkShaderModuleCreateInfo moduleInfo{VK_STRUCTURE_TYPE_SHADER_MODULE_CREATE_INFO};
    moduleInfo.codeSize = words.size_bytes();
    moduleInfo.pCode = words.data();
    check(vkCreateShaderModule(device, &moduleInfo, nullptr, &module), "vkCreateShaderModule");

    std::vector<std::uint32_t> constants;
    constants.push_back(workgroupSize_);
    constants.insert(constants.end(), desc.specialization.begin(), desc.specialization.end());
    if (constants.size() > HEMO_SPEC_MAX_GROUPS_X) {
      throw GpuError("'" + name_ + "' has more specialization constants than interface/spec.h leaves room for");
    }
    std::vector<VkSpecializationMapEntry> entries(constants.size());
    for (std::uint32_t i = 0; i < constants.size(); ++i) {
      entries[i] = {i, i * 4u, 4u};
    }
    // The shared constants (interface/spec.h); an id a shader does not use is ignored.
    entries.push_back({HEMO_SPEC_MAX_GROUPS_X, std::uint32_t(constants.size() * 4), 4u});
    constants.push_back(std::min({limits.maxComputeWorkGroupCount[0], limits.maxComputeWorkGroupCount[1], 65535u}));
    VkSpecializationInfo spec{};
    spec.mapEntryCount = static_cast<std::uint32_t>(entries.size());
    spec.pMapEntries = entries.data();
    spec.dataSize = constants.size() * 4;
    spec.pData = constants.data();

    VkComputePipelineCreateInfo info{VK_STRUCTURE_TYPE_COMPUTE_PIPELINE_CREATE_INFO};
    info.stage = {VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO};
    info.stage.stage = VK_SHADER_STAGE_COMPUTE_BIT;
    info.stage.module = module;
    info.stage.pName = "main";
    info.stage.pSpecializationInfo = &spec;
    info.layout = layout_;
    check(vkCreateComputePipelines(device, VK_NULL_HANDLE, 1, &info, nullptr, &pipeline_),
          ("vkCreateComputePipelines for '" + name_ + "'").c_str());
  } catch (...) {
    if (module) vkDestroyShaderModule(device, module, nullptr);
    release();
    throw;
  }
  vkDestroyShaderModule(device, module, nullptr);
}

ComputePipeline::~ComputePipeline() { release(); }

ComputePipeline::ComputePipeline(ComputePipeline&& other) noexcept { *this = std::move(other); }

ComputePipeline& ComputePipeline::operator=(ComputePipeline&& other) noexcept {
  if (this != &other) {
    release();
    context_ = std::exchange(other.context_, nullptr);
    setLayout_ = std::exchange(other.setLayout_, VK_NULL_HANDLE);
    layout_ = std::exchange(other.layout_, VK_NULL_HANDLE);
    pipeline_ = std::exchange(other.pipeline_, VK_NULL_HANDLE);
    bindingCount_ = other.bindingCount_;
    uniformSlots_ = other.uniformSlots_;
    texelSlots_ = other.texelSlots_;
    storageTexelSlots_ = other.storageTexelSlots_;
    pushBytes_ = other.pushBytes_;
    workgroupSize_ = other.workgroupSize_;
    name_ = std::move(other.name_);
  }
  return *this;
}

void ComputePipeline::release() {
  if (!context_) return;
  VkDevice device = context_->device();
  if (pipeline_) vkDestroyPipeline(device, pipeline_, nullptr);
  if (layout_) vkDestroyPipelineLayout(device, layout_, nullptr);
  if (setLayout_) vkDestroyDescriptorSetLayout(device, setLayout_, nullptr);
  pipeline_ = VK_NULL_HANDLE;
  layout_ = VK_NULL_HANDLE;
  setLayout_ = VK_NULL_HANDLE;
}

Groups ComputePipeline::groupsFor(std::uint64_t invocations) const {
  const std::uint64_t groups = (invocations + workgroupSize_ - 1) / workgroupSize_;
  const std::uint64_t maxX = context_->limits().maxComputeWorkGroupCount[0];
  const std::uint64_t maxY = context_->limits().maxComputeWorkGroupCount[1];
  if (groups <= maxX) return {static_cast<std::uint32_t>(groups), 1};
  const std::uint64_t y = (groups + maxX - 1) / maxX;
  if (y > maxY) {
    throw GpuError("dispatch of " + std::to_string(invocations) + " invocations for '" + name_ +
                   "' exceeds the device's workgroup-count limits");
  }
  const std::uint64_t x = (groups + y - 1) / y;
  return {static_cast<std::uint32_t>(x), static_cast<std::uint32_t>(y)};
}

Groups ComputePipeline::groupsFor(std::uint64_t items, std::uint32_t itemsPerInvocation) const {
  return groupsFor((items + itemsPerInvocation - 1) / itemsPerInvocation);
}

ComputePipeline::DescriptorCounts ComputePipeline::descriptorCounts() const {
  DescriptorCounts n;
  n.uniform = static_cast<std::uint32_t>(std::popcount(uniformSlots_));
  n.texel = static_cast<std::uint32_t>(std::popcount(texelSlots_));
  n.storageTexel = static_cast<std::uint32_t>(std::popcount(storageTexelSlots_));
  n.storage = bindingCount_ - std::min(bindingCount_, n.uniform + n.texel + n.storageTexel);
  return n;
}

VkDescriptorType ComputePipeline::descriptorType(std::uint32_t slot) const {
  if ((texelSlots_ >> slot) & 1u) return VK_DESCRIPTOR_TYPE_UNIFORM_TEXEL_BUFFER;
  if ((storageTexelSlots_ >> slot) & 1u) return VK_DESCRIPTOR_TYPE_STORAGE_TEXEL_BUFFER;
  return (uniformSlots_ >> slot) & 1u ? VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER : VK_DESCRIPTOR_TYPE_STORAGE_BUFFER;
}

namespace {

// Bytes per texel of the formats texel slots take (4-byte channels).
VkDeviceSize texelBytes(VkFormat format) {
  switch (format) {
    case VK_FORMAT_R32_UINT:
    case VK_FORMAT_R32_SINT:
    case VK_FORMAT_R32_SFLOAT:
      return 4;
    case VK_FORMAT_R32G32_UINT:
    case VK_FORMAT_R32G32_SINT:
    case VK_FORMAT_R32G32_SFLOAT:
      return 8;
    case VK_FORMAT_R32G32B32A32_UINT:
    case VK_FORMAT_R32G32B32A32_SINT:
    case VK_FORMAT_R32G32B32A32_SFLOAT:
      return 16;
    default:
      return 0;
  }
}

// Bytes a texel slot's view covers. A whole-buffer binding of an empty buffer (a stage built
// for zero items, which never reads it) views the first texel of its allocation, as a view
// cannot be empty.
VkDeviceSize texelRange(const Binding& b, VkDeviceSize texelBytes) {
  if (b.range != VK_WHOLE_SIZE) return b.range;
  const VkDeviceSize size = b.buffer->size() - std::min(b.offset, b.buffer->size());
  if (size == 0 && b.offset + texelBytes <= b.buffer->allocatedSize()) return texelBytes;
  return size;
}

}  // namespace

DescriptorSet ComputePipeline::makeSet(std::initializer_list<Binding> bindings) const {
  const auto& limits = context_->limits();
  std::vector<const Binding*> bySlot(bindingCount_, nullptr);
  for (const Binding& b : bindings) {
    if (b.slot >= bindingCount_) {
      throw std::invalid_argument("'" + name_ + "' has no binding slot " + std::to_string(b.slot));
    }
    if (bySlot[b.slot]) {
      throw std::invalid_argument("'" + name_ + "' binding slot " + std::to_string(b.slot) + " bound twice");
    }
    if (!b.buffer || !b.buffer->valid()) {
      throw std::invalid_argument("'" + name_ + "' binding slot " + std::to_string(b.slot) + " has no buffer");
    }
    if (b.buffer->use() != MemoryUse::Device) {
      throw std::invalid_argument("'" + name_ + "' binding slot " + std::to_string(b.slot) +
                                  ": buffer '" + b.buffer->name() + "' is not a device buffer");
    }
    const std::string where = "'" + name_ + "' binding slot " + std::to_string(b.slot);
    const VkDescriptorType type = descriptorType(b.slot);
    if (type == VK_DESCRIPTOR_TYPE_UNIFORM_TEXEL_BUFFER || type == VK_DESCRIPTOR_TYPE_STORAGE_TEXEL_BUFFER) {
      const bool storage = type == VK_DESCRIPTOR_TYPE_STORAGE_TEXEL_BUFFER;
      const VkDeviceSize bytes = texelBytes(b.format);
      if (bytes == 0) {
        throw std::invalid_argument(where + " is a texel slot and needs a 32-bit-channel format (R32, R32G32 or R32G32B32A32)");
      }
      VkFormatProperties props{};
      vkGetPhysicalDeviceFormatProperties(context_->physicalDevice(), b.format, &props);
      const VkFormatFeatureFlags feature =
          storage ? VK_FORMAT_FEATURE_STORAGE_TEXEL_BUFFER_BIT : VK_FORMAT_FEATURE_UNIFORM_TEXEL_BUFFER_BIT;
      if (!(props.bufferFeatures & feature)) {
        throw std::invalid_argument(where + ": the device cannot use format " + std::to_string(b.format) +
                                    (storage ? " as a storage texel buffer" : " as a uniform texel buffer"));
      }
      if (b.offset % std::max<VkDeviceSize>(limits.minTexelBufferOffsetAlignment, 1) != 0) {
        throw std::invalid_argument(where + ": offset " + std::to_string(b.offset) +
                                    " is not a multiple of the device's minTexelBufferOffsetAlignment " +
                                    std::to_string(limits.minTexelBufferOffsetAlignment));
      }
      const VkDeviceSize range = texelRange(b, bytes);
      if (b.offset + range > b.buffer->allocatedSize()) {
        throw std::invalid_argument(where + ": bytes " + std::to_string(b.offset) + " to " + std::to_string(b.offset + range) +
                                    " lie beyond buffer '" + b.buffer->name() + "' (" +
                                    std::to_string(b.buffer->allocatedSize()) + " bytes)");
      }
      if (range < bytes) {
        throw std::invalid_argument(where + ": buffer '" + b.buffer->name() + "' binds " + std::to_string(range) +
                                    " bytes, less than one " + std::to_string(bytes) + "-byte texel");
      }
      if (range / bytes > limits.maxTexelBufferElements) {
        throw std::invalid_argument(where + ": buffer '" + b.buffer->name() + "' binds " + std::to_string(range / bytes) +
                                    " texels, more than the device's maxTexelBufferElements " +
                                    std::to_string(limits.maxTexelBufferElements));
      }
      bySlot[b.slot] = &b;
      continue;
    }
    if (b.format != VK_FORMAT_UNDEFINED) {
      throw std::invalid_argument(where + " is not a texel slot and takes no format");
    }
    const bool uniform = descriptorType(b.slot) == VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER;
    const VkDeviceSize alignment =
        uniform ? limits.minUniformBufferOffsetAlignment : limits.minStorageBufferOffsetAlignment;
    if (alignment > 1 && b.offset % alignment != 0) {
      throw std::invalid_argument("'" + name_ + "' binding slot " + std::to_string(b.slot) + ": offset " +
                                  std::to_string(b.offset) + " is not a multiple of the device's " +
                                  (uniform ? "minUniformBufferOffsetAlignment " : "minStorageBufferOffsetAlignment ") +
                                  std::to_string(alignment));
    }
    const VkDeviceSize range = b.range == VK_WHOLE_SIZE ? b.buffer->size() - std::min(b.offset, b.buffer->size()) : b.range;
    const VkDeviceSize maxRange = uniform ? limits.maxUniformBufferRange : limits.maxStorageBufferRange;
    if (range > maxRange) {
      throw std::invalid_argument("'" + name_ + "' binding slot " + std::to_string(b.slot) + ": buffer '" +
                                  b.buffer->name() + "' binds " + std::to_string(range) + " bytes, more than the device's " +
                                  (uniform ? "maxUniformBufferRange " : "maxStorageBufferRange ") +
                                  std::to_string(maxRange));
    }
    bySlot[b.slot] = &b;
  }
  for (std::uint32_t i = 0; i < bindingCount_; ++i) {
    if (!bySlot[i]) {
      throw std::invalid_argument("'" + name_ + "' binding slot " + std::to_string(i) + " is not bound");
    }
  }

  DescriptorSet set;
  set.device_ = context_->device();
  const DescriptorCounts n = descriptorCounts();
  const VkDescriptorPoolSize sizes[4] = {
      {VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, std::max(n.storage, 1u)},
      {VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER, std::max(n.uniform, 1u)},
      {VK_DESCRIPTOR_TYPE_UNIFORM_TEXEL_BUFFER, std::max(n.texel, 1u)},
      {VK_DESCRIPTOR_TYPE_STORAGE_TEXEL_BUFFER, std::max(n.storageTexel, 1u)}};
  VkDescriptorPoolCreateInfo poolInfo{VK_STRUCTURE_TYPE_DESCRIPTOR_POOL_CREATE_INFO};
  poolInfo.maxSets = 1;
  poolInfo.poolSizeCount = 4;
  poolInfo.pPoolSizes = sizes;
  check(vkCreateDescriptorPool(set.device_, &poolInfo, nullptr, &set.pool_), "vkCreateDescriptorPool");
  VkDescriptorSetAllocateInfo alloc{VK_STRUCTURE_TYPE_DESCRIPTOR_SET_ALLOCATE_INFO};
  alloc.descriptorPool = set.pool_;
  alloc.descriptorSetCount = 1;
  alloc.pSetLayouts = &setLayout_;
  check(vkAllocateDescriptorSets(set.device_, &alloc, &set.set_), "vkAllocateDescriptorSets");

  std::vector<VkDescriptorBufferInfo> infos(bindingCount_);
  std::vector<VkBufferView> views(bindingCount_, VK_NULL_HANDLE);
  std::vector<VkWriteDescriptorSet> writes(bindingCount_);
  for (std::uint32_t i = 0; i < bindingCount_; ++i) {
    const Binding& b = *bySlot[i];
    const VkDeviceSize end = b.range == VK_WHOLE_SIZE ? b.buffer->allocatedSize() : b.offset + b.range;
    set.bound_.push_back({b.buffer->handle(), b.offset, end});
    writes[i] = {VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET};
    writes[i].dstSet = set.set_;
    writes[i].dstBinding = i;
    writes[i].descriptorCount = 1;
    writes[i].descriptorType = descriptorType(i);
    if (writes[i].descriptorType == VK_DESCRIPTOR_TYPE_UNIFORM_TEXEL_BUFFER ||
        writes[i].descriptorType == VK_DESCRIPTOR_TYPE_STORAGE_TEXEL_BUFFER) {
      // Whole texels only: a range that is not a multiple of the texel size is cut down.
      const VkDeviceSize bytes = texelBytes(b.format);
      const VkDeviceSize range = texelRange(b, bytes);
      VkBufferViewCreateInfo viewInfo{VK_STRUCTURE_TYPE_BUFFER_VIEW_CREATE_INFO};
      viewInfo.buffer = b.buffer->handle();
      viewInfo.format = b.format;
      viewInfo.offset = b.offset;
      viewInfo.range = range / bytes * bytes;
      check(vkCreateBufferView(set.device_, &viewInfo, nullptr, &views[i]), "vkCreateBufferView");
      set.views_.push_back(views[i]);
      writes[i].pTexelBufferView = &views[i];
    } else {
      infos[i] = {b.buffer->handle(), b.offset, b.range};
      writes[i].pBufferInfo = &infos[i];
    }
  }
  vkUpdateDescriptorSets(set.device_, bindingCount_, writes.data(), 0, nullptr);
  return set;
}

}  // namespace hemo::gpu
