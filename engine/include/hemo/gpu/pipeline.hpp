#pragma once
// One compute shader with its descriptor layout (storage buffers, and uniform buffers at the
// slots PipelineDesc::uniformSlots names), push constants and workgroup size (specialization
// constant 0). Bindings are addressed by the slot numbers of
// the shader family's interface header, never by position in a list.
#include "hemo/gpu/buffer.hpp"

#include <cstdint>
#include <initializer_list>
#include <string>
#include <string_view>
#include <vector>

namespace hemo::gpu {

// Workgroup counts of a dispatch. Large 1D work is folded into y when x would exceed
// maxComputeWorkGroupCount[0]; shaders use hemo_group_index() from common/index.glsl.
struct Groups {
  std::uint32_t x = 0;
  std::uint32_t y = 1;
  std::uint64_t total() const { return std::uint64_t(x) * y; }
};

// A buffer (or a byte range of one) bound to one slot (storage, uniform, uniform texel or
// storage texel buffer, as the pipeline declares it). A texel slot sees the range as an
// array of `format` texels (a buffer view); the other slots take no format.
struct Binding {
  std::uint32_t slot = 0;
  const Buffer* buffer = nullptr;
  VkDeviceSize offset = 0;
  VkDeviceSize range = VK_WHOLE_SIZE;
  VkFormat format = VK_FORMAT_UNDEFINED;
};

// Texel formats of the engine's per-item records (one 32-bit value per channel).
namespace texel {
inline constexpr VkFormat kVec4 = VK_FORMAT_R32G32B32A32_SFLOAT;
inline constexpr VkFormat kUvec4 = VK_FORMAT_R32G32B32A32_UINT;
inline constexpr VkFormat kIvec4 = VK_FORMAT_R32G32B32A32_SINT;
inline constexpr VkFormat kUvec2 = VK_FORMAT_R32G32_UINT;
inline constexpr VkFormat kVec2 = VK_FORMAT_R32G32_SFLOAT;
inline constexpr VkFormat kUint = VK_FORMAT_R32_UINT;
inline constexpr VkFormat kInt = VK_FORMAT_R32_SINT;
inline constexpr VkFormat kFloat = VK_FORMAT_R32_SFLOAT;
}  // namespace texel

// A whole buffer bound to a texel slot as `format` texels.
inline Binding texelBinding(std::uint32_t slot, const Buffer* buffer, VkFormat format) {
  return {slot, buffer, 0, VK_WHOLE_SIZE, format};
}

class DescriptorSet {
 public:
  DescriptorSet() = default;
  ~DescriptorSet();
  DescriptorSet(DescriptorSet&& other) noexcept;
  DescriptorSet& operator=(DescriptorSet&& other) noexcept;
  DescriptorSet(const DescriptorSet&) = delete;
  DescriptorSet& operator=(const DescriptorSet&) = delete;
  VkDescriptorSet handle() const { return set_; }

  // The byte ranges the set binds (for the recorder's check of pending transfer writes).
  struct Bound {
    VkBuffer buffer;
    VkDeviceSize begin, end;
  };
  const std::vector<Bound>& bound() const { return bound_; }

 private:
  friend class ComputePipeline;
  void release();
  VkDevice device_ = VK_NULL_HANDLE;
  VkDescriptorPool pool_ = VK_NULL_HANDLE;
  VkDescriptorSet set_ = VK_NULL_HANDLE;
  std::vector<VkBufferView> views_;  // of the texel slots
  std::vector<Bound> bound_;
};

struct PipelineDesc {
  std::string_view shader;             // name in compute_shaders/, e.g. "scan/scan_block"
  std::uint32_t bindingCount = 0;      // buffers at slots 0 .. bindingCount-1
  std::uint32_t pushConstantBytes = 0;
  std::uint32_t workgroupSize = 256;   // specialization constant 0
  std::vector<std::uint32_t> specialization;  // constants 1, 2, ... (uint32 each)
  // Bit i set: slot i is a uniform buffer (a small read-only block whose every read has the
  // same address across a dispatch, such as parameters: devices read those once per
  // subgroup, see docs/benchmarks.md "uniform parameters"); otherwise a storage buffer.
  std::uint32_t uniformSlots = 0;
  // Bit i set: slot i is a uniform texel buffer (GLSL samplerBuffer / usamplerBuffer, read
  // with texelFetch): read-only per-particle data gathered at a different index by every
  // invocation. llvmpipe fetches texels as one unrolled vector gather, where a storage-buffer
  // load walks the SIMD lanes one by one (docs/benchmarks.md, "texel gathers").
  std::uint32_t texelSlots = 0;
  // Bit i set: slot i is a storage texel buffer (GLSL imageBuffer / uimageBuffer with an
  // explicit format, written with imageStore). Unlike texel reads, texel stores cost llvmpipe
  // more than storage-buffer stores (hemo-bench primitives, store_scatter), so the engine's passes write storage buffers; the probe uses this slot kind.
  std::uint32_t storageTexelSlots = 0;
};

class ComputePipeline {
 public:
  ComputePipeline() = default;
  ComputePipeline(Context& context, const PipelineDesc& desc);
  ~ComputePipeline();
  ComputePipeline(ComputePipeline&& other) noexcept;
  ComputePipeline& operator=(ComputePipeline&& other) noexcept;
  ComputePipeline(const ComputePipeline&) = delete;
  ComputePipeline& operator=(const ComputePipeline&) = delete;

  VkPipeline handle() const { return pipeline_; }
  VkPipelineLayout layout() const { return layout_; }
  std::uint32_t workgroupSize() const { return workgroupSize_; }
  std::uint32_t pushConstantBytes() const { return pushBytes_; }
  const std::string& name() const { return name_; }

  // Workgroups so that `invocations` invocations of one item each are covered. The single
  // place where host dispatch sizes are derived from the shader's workgroup size.
  Groups groupsFor(std::uint64_t invocations) const;
  // Workgroups for shaders whose invocations each handle `itemsPerInvocation` items.
  Groups groupsFor(std::uint64_t items, std::uint32_t itemsPerInvocation) const;

  // Binds every slot exactly once; throws std::invalid_argument naming the slot otherwise,
  // and when a uniform slot's range exceeds maxUniformBufferRange or its offset is not a
  // multiple of minUniformBufferOffsetAlignment (storage slots likewise with theirs), and
  // when a texel slot has no format, a format the device cannot use as that kind of texel
  // buffer, a misaligned offset or more texels than maxTexelBufferElements.
  DescriptorSet makeSet(std::initializer_list<Binding> bindings) const;

 private:
  void release();
  VkDescriptorType descriptorType(std::uint32_t slot) const;
  struct DescriptorCounts {
    std::uint32_t storage = 0, uniform = 0, texel = 0, storageTexel = 0;
  };
  DescriptorCounts descriptorCounts() const;  // slots of each kind
  Context* context_ = nullptr;
  VkDescriptorSetLayout setLayout_ = VK_NULL_HANDLE;
  VkPipelineLayout layout_ = VK_NULL_HANDLE;
  VkPipeline pipeline_ = VK_NULL_HANDLE;
  std::uint32_t bindingCount_ = 0;
  std::uint32_t uniformSlots_ = 0;
  std::uint32_t texelSlots_ = 0;
  std::uint32_t storageTexelSlots_ = 0;
  std::uint32_t pushBytes_ = 0;
  std::uint32_t workgroupSize_ = 0;
  std::string name_;
};

}  // namespace hemo::gpu
