#pragma once
// Presentation to a window's surface (the Context's, created by the app: the engine and this
// class never touch a window system). Each frame is drawn by the OffscreenRenderer and then
// copied into a swapchain image with a blit (which also converts RGBA to the surface's
// format) and presented. One frame in flight; the host waits for the previous present's
// copy before recording the next.
#include "hemo/gpu/context.hpp"

#include <cstdint>
#include <vector>

namespace hemo::render {

class Swapchain {
 public:
  // Throws gpu::GpuError when the context has no surface or the surface cannot take
  // transfer-written images.
  Swapchain(gpu::Context& context, VkExtent2D extent);
  ~Swapchain();
  Swapchain(const Swapchain&) = delete;
  Swapchain& operator=(const Swapchain&) = delete;

  // Blits `source` (a colour image in TRANSFER_SRC_OPTIMAL layout, of `sourceExtent`, whose
  // writes were submitted before) into the next swapchain image and presents it. Returns
  // false (nothing presented) when the swapchain no longer matches the surface; call
  // recreate() then.
  bool present(VkImage source, VkExtent2D sourceExtent);
  void recreate(VkExtent2D extent);
  VkExtent2D extent() const { return extent_; }
  VkFormat format() const { return format_; }
  std::uint64_t presentedFrames() const { return presented_; }

 private:
  void create(VkExtent2D extent);
  void destroySwapchain();

  gpu::Context* context_;
  VkSwapchainKHR swapchain_ = VK_NULL_HANDLE;
  VkFormat format_ = VK_FORMAT_UNDEFINED;
  VkExtent2D extent_{};
  std::vector<VkImage> images_;
  VkCommandPool pool_ = VK_NULL_HANDLE;
  VkCommandBuffer cmd_ = VK_NULL_HANDLE;
  VkFence fence_ = VK_NULL_HANDLE;
  VkSemaphore acquired_ = VK_NULL_HANDLE, copied_ = VK_NULL_HANDLE;
  std::uint64_t presented_ = 0;
};

}  // namespace hemo::render
