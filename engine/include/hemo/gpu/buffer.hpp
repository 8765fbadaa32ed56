#pragma once
// Move-only GPU buffer with a declared purpose. upload()/readback() are for set-up, tests and
// output; the simulation loop never calls them.
#include "hemo/gpu/context.hpp"

#include <cstring>
#include <span>
#include <string>
#include <vector>

namespace hemo::gpu {

enum class MemoryUse {
  Device,    // storage buffer in device-local memory; filled by shaders or upload()
  Upload,    // host-visible staging memory written by the CPU
  Readback,  // host-visible memory the GPU copies results into
};

class Buffer {
 public:
  Buffer() = default;
  // `bytes` may be 0 (an empty array); the Vulkan object then has a minimal size.
  // Throws GpuError naming `name` when the size exceeds what the device allows.
  Buffer(Context& context, VkDeviceSize bytes, MemoryUse use, std::string name);
  ~Buffer();
  Buffer(Buffer&& other) noexcept;
  Buffer& operator=(Buffer&& other) noexcept;
  Buffer(const Buffer&) = delete;
  Buffer& operator=(const Buffer&) = delete;

  VkBuffer handle() const { return buffer_; }
  VkDeviceSize size() const { return size_; }            // bytes requested
  VkDeviceSize allocatedSize() const { return capacity_; }  // bytes of the VkBuffer
  const std::string& name() const { return name_; }
  MemoryUse use() const { return use_; }
  bool valid() const { return buffer_ != VK_NULL_HANDLE; }
  // The host reads and writes it directly (else upload/readback copy through staging).
  bool hostMapped() const { return mapped_ != nullptr; }

  // Copies `bytes` from `src` into the buffer at `offset` (staging copy if not host-visible).
  void uploadBytes(const void* src, VkDeviceSize bytes, VkDeviceSize offset = 0);
  void readbackBytes(void* dst, VkDeviceSize bytes, VkDeviceSize offset = 0) const;

  template <class T>
  void upload(std::span<const T> data, VkDeviceSize offset = 0) {
    uploadBytes(data.data(), data.size_bytes(), offset);
  }
  template <class T>
  void upload(const std::vector<T>& data, VkDeviceSize offset = 0) {
    uploadBytes(data.data(), data.size() * sizeof(T), offset);
  }
  template <class T>
  std::vector<T> readback(std::size_t count, VkDeviceSize offset = 0) const {
    std::vector<T> out(count);
    readbackBytes(out.data(), count * sizeof(T), offset);
    return out;
  }

 private:
  void release();

  Context* context_ = nullptr;
  VkBuffer buffer_ = VK_NULL_HANDLE;
  VkDeviceMemory memory_ = VK_NULL_HANDLE;
  void* mapped_ = nullptr;
  VkDeviceSize size_ = 0;
  VkDeviceSize capacity_ = 0;
  std::uint32_t memoryType_ = 0;
  VkDeviceSize memoryBytes_ = 0;  // taken from the context's account (Context::takeMemory)
  MemoryUse use_ = MemoryUse::Device;
  std::string name_;
};

}  // namespace hemo::gpu
