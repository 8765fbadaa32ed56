#include "hemo/gpu/buffer.hpp"

#include "hemo/gpu/commands.hpp"

#include <algorithm>
#include <utility>

namespace hemo::gpu {

namespace {
std::string mib(VkDeviceSize bytes) {
  return std::to_string(bytes / (1024 * 1024)) + " MiB (" + std::to_string(bytes) + " bytes)";
}
}  // namespace

Buffer::Buffer(Context& context, VkDeviceSize bytes, MemoryUse use, std::string name)
    : context_(&context), size_(bytes), use_(use), name_(std::move(name)) {
  capacity_ = std::max<VkDeviceSize>(bytes, 16);
  const auto& limits = context.limits();
  if (use == MemoryUse::Device && capacity_ > limits.maxStorageBufferRange) {
    throw GpuError("buffer '" + name_ + "' needs " + mib(bytes) +
                   " but the device's largest storage buffer (maxStorageBufferRange) is " +
                   mib(limits.maxStorageBufferRange));
  }
  if (context.maxAllocationSize() != 0 && capacity_ > context.maxAllocationSize()) {
    throw GpuError("buffer '" + name_ + "' needs " + mib(bytes) +
                   " but the device's largest allocation is " + mib(context.maxAllocationSize()));
  }

  VkBufferCreateInfo info{VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO};
  info.size = capacity_;
  info.sharingMode = VK_SHARING_MODE_EXCLUSIVE;
  VkMemoryPropertyFlags required = 0;
  VkMemoryPropertyFlags preferred = 0;
  switch (use) {
    case MemoryUse::Device:
      info.usage = VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | VK_BUFFER_USAGE_UNIFORM_BUFFER_BIT |
                   VK_BUFFER_USAGE_UNIFORM_TEXEL_BUFFER_BIT | VK_BUFFER_USAGE_STORAGE_TEXEL_BUFFER_BIT |
                   VK_BUFFER_USAGE_TRANSFER_SRC_BIT |
                   VK_BUFFER_USAGE_TRANSFER_DST_BIT | VK_BUFFER_USAGE_INDIRECT_BUFFER_BIT |
                   VK_BUFFER_USAGE_VERTEX_BUFFER_BIT | VK_BUFFER_USAGE_INDEX_BUFFER_BIT;
      preferred = VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT;
      break;
    case MemoryUse::Upload:
      info.usage = VK_BUFFER_USAGE_TRANSFER_SRC_BIT;
      required = VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT | VK_MEMORY_PROPERTY_HOST_COHERENT_BIT;
      break;
    case MemoryUse::Readback:
      info.usage = VK_BUFFER_USAGE_TRANSFER_DST_BIT;
      required = VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT | VK_MEMORY_PROPERTY_HOST_COHERENT_BIT;
      preferred = VK_MEMORY_PROPERTY_HOST_CACHED_BIT;
      break;
  }
  VkDevice device = context.device();
  check(vkCreateBuffer(device, &info, nullptr, &buffer_), ("vkCreateBuffer for '" + name_ + "'").c_str());
  VkMemoryRequirements req{};
  vkGetBufferMemoryRequirements(device, buffer_, &req);
  VkMemoryAllocateInfo alloc{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO};
  alloc.allocationSize = req.size;
  try {
    alloc.memoryTypeIndex = context.memoryType(req.memoryTypeBits, required, preferred);
    context.takeMemory(alloc.memoryTypeIndex, req.size, name_);  // throws when its heap is full
    memoryType_ = alloc.memoryTypeIndex;
    memoryBytes_ = req.size;
    const VkResult r = vkAllocateMemory(device, &alloc, nullptr, &memory_);
    if (r == VK_ERROR_OUT_OF_DEVICE_MEMORY || r == VK_ERROR_OUT_OF_HOST_MEMORY) {
      throw GpuError("out of memory allocating buffer '" + name_ + "' of " + mib(bytes));
    }
    check(r, ("vkAllocateMemory for '" + name_ + "'").c_str());
    check(vkBindBufferMemory(device, buffer_, memory_, 0), "vkBindBufferMemory");
    const bool mappable = use != MemoryUse::Device || !context.stagingOnly();
    if (mappable && (context.memoryFlags(alloc.memoryTypeIndex) & VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT)) {
      check(vkMapMemory(device, memory_, 0, VK_WHOLE_SIZE, 0, &mapped_), "vkMapMemory");
      // Coherence is only guaranteed for coherent memory; device buffers that happen to be
      // host-visible but not coherent go through staging instead.
      if (!(context.memoryFlags(alloc.memoryTypeIndex) & VK_MEMORY_PROPERTY_HOST_COHERENT_BIT)) {
        vkUnmapMemory(device, memory_);
        mapped_ = nullptr;
      }
    }
  } catch (...) {
    release();
    throw;
  }
}

Buffer::~Buffer() { release(); }

Buffer::Buffer(Buffer&& other) noexcept { *this = std::move(other); }

Buffer& Buffer::operator=(Buffer&& other) noexcept {
  if (this != &other) {
    release();
    context_ = std::exchange(other.context_, nullptr);
    buffer_ = std::exchange(other.buffer_, VK_NULL_HANDLE);
    memory_ = std::exchange(other.memory_, VK_NULL_HANDLE);
    mapped_ = std::exchange(other.mapped_, nullptr);
    size_ = std::exchange(other.size_, 0);
    capacity_ = std::exchange(other.capacity_, 0);
    memoryType_ = other.memoryType_;
    memoryBytes_ = std::exchange(other.memoryBytes_, 0);
    use_ = other.use_;
    name_ = std::move(other.name_);
  }
  return *this;
}

void Buffer::release() {
  if (!context_) return;
  VkDevice device = context_->device();
  if (buffer_) vkDestroyBuffer(device, buffer_, nullptr);
  if (memory_) vkFreeMemory(device, memory_, nullptr);  // unmaps implicitly
  if (memoryBytes_) context_->releaseMemory(memoryType_, memoryBytes_);
  memoryBytes_ = 0;
  buffer_ = VK_NULL_HANDLE;
  memory_ = VK_NULL_HANDLE;
  mapped_ = nullptr;
}

void Buffer::uploadBytes(const void* src, VkDeviceSize bytes, VkDeviceSize offset) {
  if (bytes == 0) return;
  if (offset + bytes > capacity_) {
    throw std::out_of_range("upload of " + std::to_string(bytes) + " bytes at offset " +
                            std::to_string(offset) + " overruns buffer '" + name_ + "' of " +
                            std::to_string(size_) + " bytes");
  }
  if (mapped_) {
    std::memcpy(static_cast<char*>(mapped_) + offset, src, bytes);
    return;
  }
  Buffer staging(*context_, bytes, MemoryUse::Upload, name_ + " (staging)");
  staging.uploadBytes(src, bytes);
  context_->runOnce([&](VkCommandBuffer cmd) {
    recordBeforeStagingCopy(*context_, cmd);  // earlier work that reads or writes these bytes
    VkBufferCopy region{0, offset, bytes};
    vkCmdCopyBuffer(cmd, staging.handle(), buffer_, 1, &region);
  });  // (the next CommandRecorder::begin orders the copy before its work)
}

void Buffer::readbackBytes(void* dst, VkDeviceSize bytes, VkDeviceSize offset) const {
  if (bytes == 0) return;
  if (offset + bytes > capacity_) {
    throw std::out_of_range("readback of " + std::to_string(bytes) + " bytes at offset " +
                            std::to_string(offset) + " overruns buffer '" + name_ + "' of " +
                            std::to_string(size_) + " bytes");
  }
  if (mapped_) {
    std::memcpy(dst, static_cast<const char*>(mapped_) + offset, bytes);
    return;
  }
  Buffer staging(*context_, bytes, MemoryUse::Readback, name_ + " (readback)");
  context_->runOnce([&](VkCommandBuffer cmd) {
    recordBeforeStagingCopy(*context_, cmd);  // the writes of earlier submissions
    VkBufferCopy region{offset, 0, bytes};
    vkCmdCopyBuffer(cmd, buffer_, staging.handle(), 1, &region);
    recordStagingCopyToHost(cmd);
  });
  staging.readbackBytes(dst, bytes);
}

}  // namespace hemo::gpu
