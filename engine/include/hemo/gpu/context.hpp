#pragma once
// Headless Vulkan instance, device and compute queue. Knows nothing of physics.
#include <vulkan/vulkan.h>

#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <stdexcept>
#include <string>
#include <vector>

namespace hemo::gpu {

class PipelineCache;

// A Vulkan failure or an unusable device (hemo-run exit code 3).
class GpuError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Throws GpuError naming `what` when `result` is not VK_SUCCESS.
void check(VkResult result, const char* what);
const char* resultName(VkResult result);

struct DeviceInfo {
  std::uint32_t index = 0;  // position in vkEnumeratePhysicalDevices order
  std::string name;
  VkPhysicalDeviceType type = VK_PHYSICAL_DEVICE_TYPE_OTHER;
  std::uint32_t apiVersion = 0;
  std::string typeName() const;
};

struct ContextOptions {
  // Enable VK_LAYER_KHRONOS_validation and count its messages. Fails if the layer is missing.
  // The environment variable HEMO_VALIDATION=1 turns it on as well.
  bool validation = false;
  // Device selector: an index into the device list or a case-insensitive substring of the
  // device name. Empty: the HEMO_DEVICE environment variable, else the default choice
  // (discrete > integrated > virtual > CPU).
  std::string device;
  // Window-system integration (hemo-view), supplied by the app so the engine never links a
  // window system: extra instance extensions (e.g. GLFW's required ones) and a function that
  // creates the presentation surface once the instance exists. With a surface, the queue
  // family must also draw and present to it, and VK_KHR_swapchain is enabled.
  std::vector<std::string> instanceExtensions;
  std::function<VkSurfaceKHR(VkInstance)> createSurface;
};

// Devices visible to the Vulkan loader (creates a short-lived instance).
std::vector<DeviceInfo> listDevices();

// The worker-thread count hemo asks lavapipe for (its LP_NUM_THREADS variable) on a machine of
// `cores` cores when the variable is `current` (nullptr: unset): empty when the user has set
// it, else three threads per core. lavapipe splits each dispatch into one contiguous chunk of
// workgroups per thread, one thread per core by default, and waits for the slowest chunk;
// smaller chunks let the OS balance cores whose speed differs from moment to moment (a VM's)
// and passes whose cost varies along the slots (the SPH grid puts the fluid's slots first).
// Every Context and listDevices() apply it before the driver starts (setenv, overwriting
// nothing); other drivers ignore the variable.
std::string cpuDriverThreads(const char* current, unsigned cores);

class Context {
 public:
  explicit Context(const ContextOptions& options = {});
  ~Context();
  Context(const Context&) = delete;
  Context& operator=(const Context&) = delete;

  VkInstance instance() const { return instance_; }
  VkPhysicalDevice physicalDevice() const { return physical_; }
  VkDevice device() const { return device_; }
  VkQueue queue() const { return queue_; }
  VkSurfaceKHR surface() const { return surface_; }  // VK_NULL_HANDLE when headless
  std::uint32_t queueFamily() const { return queueFamily_; }
  const DeviceInfo& info() const { return info_; }
  const VkPhysicalDeviceLimits& limits() const { return properties_.limits; }
  std::uint32_t subgroupSize() const { return subgroupSize_; }
  VkDeviceSize maxAllocationSize() const { return maxAllocationSize_; }
  bool timestampsSupported() const { return timestampValidBits_ != 0; }
  double timestampPeriodNs() const { return properties_.limits.timestampPeriod; }
  bool validationEnabled() const { return validation_; }

  // Validation-layer messages (warnings and errors) seen so far.
  std::uint64_t validationMessageCount() const;
  std::vector<std::string> takeValidationMessages();

  // A memory type with all of `required` (and `preferred` if possible); throws if none.
  std::uint32_t memoryType(std::uint32_t typeBits, VkMemoryPropertyFlags required,
                           VkMemoryPropertyFlags preferred) const;
  VkMemoryPropertyFlags memoryFlags(std::uint32_t type) const;

  // Records with `record` into a one-time command buffer, submits it and waits. For set-up,
  // uploads and readbacks only; never inside a simulation loop.
  void runOnce(const std::function<void(VkCommandBuffer)>& record);

  // Compute pipelines shared by all stages of this context.
  PipelineCache& pipelines() { return *pipelines_; }

 private:
  static VKAPI_ATTR VkBool32 VKAPI_CALL onMessage(VkDebugUtilsMessageSeverityFlagBitsEXT severity,
                                                  VkDebugUtilsMessageTypeFlagsEXT types,
                                                  const VkDebugUtilsMessengerCallbackDataEXT* data,
                                                  void* user);
  void pickDevice(const std::string& selector);

  VkInstance instance_ = VK_NULL_HANDLE;
  VkDebugUtilsMessengerEXT messenger_ = VK_NULL_HANDLE;
  VkSurfaceKHR surface_ = VK_NULL_HANDLE;
  VkPhysicalDevice physical_ = VK_NULL_HANDLE;
  VkDevice device_ = VK_NULL_HANDLE;
  VkQueue queue_ = VK_NULL_HANDLE;
  VkCommandPool oneShotPool_ = VK_NULL_HANDLE;
  std::uint32_t queueFamily_ = 0;
  std::uint32_t timestampValidBits_ = 0;
  std::uint32_t subgroupSize_ = 0;
  VkDeviceSize maxAllocationSize_ = 0;
  VkPhysicalDeviceProperties properties_{};
  VkPhysicalDeviceMemoryProperties memory_{};
  DeviceInfo info_;
  bool validation_ = false;

  mutable std::mutex messageMutex_;
  std::uint64_t messageCount_ = 0;
  std::vector<std::string> messages_;

  std::unique_ptr<PipelineCache> pipelines_;  // destroyed before the device
};

}  // namespace hemo::gpu
