#include "hemo/render/swapchain.hpp"

#include <algorithm>
#include <limits>
#include <string>

namespace hemo::render {

Swapchain::Swapchain(gpu::Context& context, VkExtent2D extent) : context_(&context) {
  if (!context.surface()) throw gpu::GpuError("presenting needs a context created with a window surface");
  VkDevice d = context.device();
  VkCommandPoolCreateInfo poolInfo{VK_STRUCTURE_TYPE_COMMAND_POOL_CREATE_INFO};
  poolInfo.flags = VK_COMMAND_POOL_CREATE_RESET_COMMAND_BUFFER_BIT;
  poolInfo.queueFamilyIndex = context.queueFamily();
  gpu::check(vkCreateCommandPool(d, &poolInfo, nullptr, &pool_), "vkCreateCommandPool (present)");
  VkCommandBufferAllocateInfo alloc{VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO};
  alloc.commandPool = pool_;
  alloc.level = VK_COMMAND_BUFFER_LEVEL_PRIMARY;
  alloc.commandBufferCount = 1;
  gpu::check(vkAllocateCommandBuffers(d, &alloc, &cmd_), "vkAllocateCommandBuffers (present)");
  VkFenceCreateInfo fenceInfo{VK_STRUCTURE_TYPE_FENCE_CREATE_INFO};
  fenceInfo.flags = VK_FENCE_CREATE_SIGNALED_BIT;
  gpu::check(vkCreateFence(d, &fenceInfo, nullptr, &fence_), "vkCreateFence (present)");
  VkSemaphoreCreateInfo semInfo{VK_STRUCTURE_TYPE_SEMAPHORE_CREATE_INFO};
  gpu::check(vkCreateSemaphore(d, &semInfo, nullptr, &acquired_), "vkCreateSemaphore");
  gpu::check(vkCreateSemaphore(d, &semInfo, nullptr, &copied_), "vkCreateSemaphore");
  create(extent);
}

Swapchain::~Swapchain() {
  VkDevice d = context_->device();
  vkDeviceWaitIdle(d);
  destroySwapchain();
  vkDestroySemaphore(d, acquired_, nullptr);
  vkDestroySemaphore(d, copied_, nullptr);
  vkDestroyFence(d, fence_, nullptr);
  vkDestroyCommandPool(d, pool_, nullptr);
}

void Swapchain::destroySwapchain() {
  if (swapchain_) vkDestroySwapchainKHR(context_->device(), swapchain_, nullptr);
  swapchain_ = VK_NULL_HANDLE;
  images_.clear();
}

void Swapchain::create(VkExtent2D wanted) {
  VkPhysicalDevice phys = context_->physicalDevice();
  VkSurfaceKHR surface = context_->surface();
  VkSurfaceCapabilitiesKHR caps;
  gpu::check(vkGetPhysicalDeviceSurfaceCapabilitiesKHR(phys, surface, &caps), "vkGetPhysicalDeviceSurfaceCapabilitiesKHR");
  if (!(caps.supportedUsageFlags & VK_IMAGE_USAGE_TRANSFER_DST_BIT)) {
    throw gpu::GpuError("the window surface does not accept transfer-written images");
  }
  std::uint32_t count = 0;
  vkGetPhysicalDeviceSurfaceFormatsKHR(phys, surface, &count, nullptr);
  std::vector<VkSurfaceFormatKHR> formats(count);
  vkGetPhysicalDeviceSurfaceFormatsKHR(phys, surface, &count, formats.data());
  // A format the blit can write: UNORM first (the offscreen image holds display values, so
  // they pass unchanged); an sRGB-only surface still works (the blit encodes, colours look
  // lighter).
  VkSurfaceFormatKHR chosen{VK_FORMAT_UNDEFINED, VK_COLOR_SPACE_SRGB_NONLINEAR_KHR};
  for (VkFormat want : {VK_FORMAT_B8G8R8A8_UNORM, VK_FORMAT_R8G8B8A8_UNORM, VK_FORMAT_B8G8R8A8_SRGB,
                        VK_FORMAT_R8G8B8A8_SRGB}) {
    for (const auto& f : formats) {
      VkFormatProperties props;
      vkGetPhysicalDeviceFormatProperties(phys, f.format, &props);
      if (f.format == want && (props.optimalTilingFeatures & VK_FORMAT_FEATURE_BLIT_DST_BIT) &&
          chosen.format == VK_FORMAT_UNDEFINED) {
        chosen = f;
      }
    }
  }
  if (chosen.format == VK_FORMAT_UNDEFINED) {
    throw gpu::GpuError("the window surface offers no 8-bit RGBA/BGRA format that a blit can write");
  }
  format_ = chosen.format;

  vkGetPhysicalDeviceSurfacePresentModesKHR(phys, surface, &count, nullptr);
  std::vector<VkPresentModeKHR> modes(count);
  vkGetPhysicalDeviceSurfacePresentModesKHR(phys, surface, &count, modes.data());
  VkPresentModeKHR mode = VK_PRESENT_MODE_FIFO_KHR;  // always available
  if (std::find(modes.begin(), modes.end(), VK_PRESENT_MODE_MAILBOX_KHR) != modes.end()) {
    mode = VK_PRESENT_MODE_MAILBOX_KHR;
  }

  if (caps.currentExtent.width != std::numeric_limits<std::uint32_t>::max()) {
    extent_ = caps.currentExtent;
  } else {
    extent_.width = std::clamp(wanted.width, caps.minImageExtent.width, caps.maxImageExtent.width);
    extent_.height = std::clamp(wanted.height, caps.minImageExtent.height, caps.maxImageExtent.height);
  }
  std::uint32_t imageCount = caps.minImageCount + 1;
  if (caps.maxImageCount > 0) imageCount = std::min(imageCount, caps.maxImageCount);

  VkSwapchainCreateInfoKHR info{VK_STRUCTURE_TYPE_SWAPCHAIN_CREATE_INFO_KHR};
  info.surface = surface;
  info.minImageCount = imageCount;
  info.imageFormat = chosen.format;
  info.imageColorSpace = chosen.colorSpace;
  info.imageExtent = extent_;
  info.imageArrayLayers = 1;
  info.imageUsage = VK_IMAGE_USAGE_TRANSFER_DST_BIT;
  info.imageSharingMode = VK_SHARING_MODE_EXCLUSIVE;
  info.preTransform = caps.currentTransform;
  info.compositeAlpha = (caps.supportedCompositeAlpha & VK_COMPOSITE_ALPHA_OPAQUE_BIT_KHR)
                            ? VK_COMPOSITE_ALPHA_OPAQUE_BIT_KHR
                            : VkCompositeAlphaFlagBitsKHR(caps.supportedCompositeAlpha & -caps.supportedCompositeAlpha);
  info.presentMode = mode;
  info.clipped = VK_TRUE;
  info.oldSwapchain = swapchain_;
  VkSwapchainKHR created = VK_NULL_HANDLE;
  gpu::check(vkCreateSwapchainKHR(context_->device(), &info, nullptr, &created), "vkCreateSwapchainKHR");
  destroySwapchain();
  swapchain_ = created;
  vkGetSwapchainImagesKHR(context_->device(), swapchain_, &count, nullptr);
  images_.resize(count);
  vkGetSwapchainImagesKHR(context_->device(), swapchain_, &count, images_.data());
}

void Swapchain::recreate(VkExtent2D extent) {
  vkDeviceWaitIdle(context_->device());
  create(extent);
}

bool Swapchain::present(VkImage source, VkExtent2D sourceExtent) {
  VkDevice d = context_->device();
  gpu::check(vkWaitForFences(d, 1, &fence_, VK_TRUE, UINT64_MAX), "vkWaitForFences (present)");
  std::uint32_t index = 0;
  const VkResult acquired = vkAcquireNextImageKHR(d, swapchain_, UINT64_MAX, acquired_, VK_NULL_HANDLE, &index);
  if (acquired == VK_ERROR_OUT_OF_DATE_KHR) return false;
  if (acquired != VK_SUBOPTIMAL_KHR) gpu::check(acquired, "vkAcquireNextImageKHR");
  gpu::check(vkResetFences(d, 1, &fence_), "vkResetFences (present)");

  gpu::check(vkResetCommandBuffer(cmd_, 0), "vkResetCommandBuffer (present)");
  VkCommandBufferBeginInfo begin{VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO};
  begin.flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT;
  gpu::check(vkBeginCommandBuffer(cmd_, &begin), "vkBeginCommandBuffer (present)");
  VkImageMemoryBarrier barriers[2]{};
  // The frame's colour writes (an earlier submission) before the blit reads them.
  barriers[0] = {VK_STRUCTURE_TYPE_IMAGE_MEMORY_BARRIER};
  barriers[0].srcAccessMask = VK_ACCESS_COLOR_ATTACHMENT_WRITE_BIT;
  barriers[0].dstAccessMask = VK_ACCESS_TRANSFER_READ_BIT;
  barriers[0].oldLayout = VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL;
  barriers[0].newLayout = VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL;
  barriers[0].srcQueueFamilyIndex = barriers[0].dstQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED;
  barriers[0].image = source;
  barriers[0].subresourceRange = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 1, 0, 1};
  // The swapchain image: whatever it held -> transfer destination.
  barriers[1] = barriers[0];
  barriers[1].srcAccessMask = 0;
  barriers[1].dstAccessMask = VK_ACCESS_TRANSFER_WRITE_BIT;
  barriers[1].oldLayout = VK_IMAGE_LAYOUT_UNDEFINED;
  barriers[1].newLayout = VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL;
  barriers[1].image = images_[index];
  vkCmdPipelineBarrier(cmd_, VK_PIPELINE_STAGE_COLOR_ATTACHMENT_OUTPUT_BIT | VK_PIPELINE_STAGE_TRANSFER_BIT,
                       VK_PIPELINE_STAGE_TRANSFER_BIT, 0, 0, nullptr, 0, nullptr, 2, barriers);
  VkImageBlit blit{};
  blit.srcSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 0, 1};
  blit.srcOffsets[1] = {std::int32_t(sourceExtent.width), std::int32_t(sourceExtent.height), 1};
  blit.dstSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 0, 1};
  blit.dstOffsets[1] = {std::int32_t(extent_.width), std::int32_t(extent_.height), 1};
  vkCmdBlitImage(cmd_, source, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, images_[index],
                 VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, 1, &blit, VK_FILTER_NEAREST);
  VkImageMemoryBarrier toPresent = barriers[1];
  toPresent.srcAccessMask = VK_ACCESS_TRANSFER_WRITE_BIT;
  toPresent.dstAccessMask = 0;
  toPresent.oldLayout = VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL;
  toPresent.newLayout = VK_IMAGE_LAYOUT_PRESENT_SRC_KHR;
  vkCmdPipelineBarrier(cmd_, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_PIPELINE_STAGE_BOTTOM_OF_PIPE_BIT, 0, 0, nullptr, 0,
                       nullptr, 1, &toPresent);
  gpu::check(vkEndCommandBuffer(cmd_), "vkEndCommandBuffer (present)");

  const VkPipelineStageFlags waitStage = VK_PIPELINE_STAGE_TRANSFER_BIT;
  VkSubmitInfo submit{VK_STRUCTURE_TYPE_SUBMIT_INFO};
  submit.waitSemaphoreCount = 1;
  submit.pWaitSemaphores = &acquired_;
  submit.pWaitDstStageMask = &waitStage;
  submit.commandBufferCount = 1;
  submit.pCommandBuffers = &cmd_;
  submit.signalSemaphoreCount = 1;
  submit.pSignalSemaphores = &copied_;
  gpu::check(vkQueueSubmit(context_->queue(), 1, &submit, fence_), "vkQueueSubmit (present)");

  VkPresentInfoKHR presentInfo{VK_STRUCTURE_TYPE_PRESENT_INFO_KHR};
  presentInfo.waitSemaphoreCount = 1;
  presentInfo.pWaitSemaphores = &copied_;
  presentInfo.swapchainCount = 1;
  presentInfo.pSwapchains = &swapchain_;
  presentInfo.pImageIndices = &index;
  const VkResult presented = vkQueuePresentKHR(context_->queue(), &presentInfo);
  if (presented == VK_ERROR_OUT_OF_DATE_KHR) return false;
  if (presented == VK_SUBOPTIMAL_KHR) {
    ++presented_;
    return false;
  }
  gpu::check(presented, "vkQueuePresentKHR");
  ++presented_;
  return true;
}

}  // namespace hemo::render
