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

// A buffer that the device's memory cannot hold (a heap's size, or the cap that
// LimitOverrides::deviceMemoryBytes or HEMO_DEVICE_MEMORY_MIB sets), thrown before anything is
// allocated for it. The message names the buffer and the figures; `needed` is the device
// memory hemo would hold with it, a lower bound of what the whole scene needs.
class OutOfDeviceMemory : public GpuError {
 public:
  OutOfDeviceMemory(const std::string& what, std::uint64_t neededBytes, std::uint64_t availableBytes)
      : GpuError(what), needed(neededBytes), available(availableBytes) {}
  std::uint64_t needed;     // bytes
  std::uint64_t available;  // bytes of the heap (or the cap)
};

// The device stopped answering (VK_ERROR_DEVICE_LOST: a GPU fault, a driver reset, a
// watchdog's timeout). Nothing on it can go on; the message says so and points to checkpoints.
class DeviceLost : public GpuError {
 public:
  using GpuError::GpuError;
};

// Throws GpuError naming `what` when `result` is not VK_SUCCESS (DeviceLost for
// VK_ERROR_DEVICE_LOST).
void check(VkResult result, const char* what);
const char* resultName(VkResult result);

struct DeviceInfo {
  std::uint32_t index = 0;  // position in vkEnumeratePhysicalDevices order
  std::string name;
  VkPhysicalDeviceType type = VK_PHYSICAL_DEVICE_TYPE_OTHER;
  std::uint32_t apiVersion = 0;
  std::string typeName() const;
};

// What the validation layer checks.
enum class Validation {
  Off,
  // The core checks and synchronization validation (hazards between commands: a missing or
  // too-narrow barrier, which lavapipe's in-order execution would hide).
  Standard,
  // The core checks only (a quick check of an application that records many frames).
  Core,
  // The core checks and GPU-assisted validation (out-of-bounds descriptor accesses, checked
  // by instrumented shaders). The layer cannot run it together with synchronization validation.
  GpuAssisted,
};

// The level that HEMO_VALIDATION asks for: unset, "" or "0": Off; "1" or "sync": Standard;
// "core": Core; "gpu": GpuAssisted. Throws std::invalid_argument for any other value.
Validation validationFromText(const char* text);
const char* validationName(Validation level);

// Device limits lowered for tests (0, or true for timestamps: the device's own): the engine
// then takes the paths that a device with such limits needs (dispatches folded into y,
// buffers refused with the figure they need, stages untimed) on whatever device runs the test.
// A value above the device's own changes nothing.
struct LimitOverrides {
  std::uint32_t maxComputeWorkGroupCountX = 0;  // along x
  std::uint32_t maxTexelBufferElements = 0;
  std::uint32_t maxStorageBufferRange = 0;
  std::uint32_t maxPerStageDescriptorStorageBuffers = 0;
  bool timestamps = true;
  std::uint32_t timestampValidBits = 0;  // fewer valid bits: the counter wraps sooner
  // The most device-local memory hemo allocates (each device-local heap's size, at most), in
  // bytes. HEMO_DEVICE_MEMORY_MIB sets it too (the smaller of the two counts).
  std::uint64_t deviceMemoryBytes = 0;
};

struct ContextOptions {
  // Enable VK_LAYER_KHRONOS_validation at the Standard level (core and synchronization checks)
  // and count its messages. Fails if the layer is missing. The environment variable
  // HEMO_VALIDATION (validationFromText), when set, turns it on as well and picks the level.
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
  // Device buffers are never mapped, even where the device's memory is host-visible (lavapipe,
  // integrated GPUs): uploads and readbacks go through staging copies, as they must on a
  // discrete GPU whose large memory the host cannot see. HEMO_FORCE_STAGING=1 sets it too.
  bool stagingOnly = false;
  LimitOverrides limits;
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
  bool queueDraws() const { return queueDraws_; }  // the queue family has graphics
  const DeviceInfo& info() const { return info_; }
  const VkPhysicalDeviceLimits& limits() const { return properties_.limits; }
  // The device's properties (its limits as lowered by LimitOverrides).
  const VkPhysicalDeviceProperties& properties() const { return properties_; }
  // The driver as it names itself (VkPhysicalDeviceDriverProperties: name and version text,
  // e.g. "llvmpipe Mesa 22.3.6 (LLVM 15.0.6)" or "NVIDIA 580.159").
  const std::string& driver() const { return driver_; }
  std::uint32_t vendorId() const { return properties_.vendorID; }
  const VkPhysicalDeviceMemoryProperties& memoryProperties() const { return memory_; }
  std::uint32_t subgroupSize() const { return subgroupSize_; }
  VkDeviceSize maxAllocationSize() const { return maxAllocationSize_; }
  bool timestampsSupported() const { return timestampValidBits_ != 0; }
  // Bits of a timestamp that count (36 on some GPUs): differences are taken modulo 2^bits.
  std::uint32_t timestampValidBits() const { return timestampValidBits_; }
  double timestampPeriodNs() const { return properties_.limits.timestampPeriod; }
  bool validationEnabled() const { return validation_ != Validation::Off; }
  Validation validation() const { return validation_; }
  bool stagingOnly() const { return stagingOnly_; }

  // Device memory that hemo's buffers hold: device-local heaps only (on a discrete GPU the
  // staging buffers live in host memory and are not counted), now and at most so far, and
  // what the device-local heaps hold in all (lowered by LimitOverrides::deviceMemoryBytes).
  std::uint64_t deviceMemoryBytes() const;
  std::uint64_t peakDeviceMemoryBytes() const;
  std::uint64_t deviceMemoryCapacity() const;
  void resetPeakDeviceMemoryBytes();  // the peak starts again from what is held now
  // Buffer's bookkeeping: takes `bytes` of memory type `type` for buffer `name`, or throws
  // OutOfDeviceMemory when its heap cannot hold them; release gives them back.
  void takeMemory(std::uint32_t type, std::uint64_t bytes, const std::string& name);
  void releaseMemory(std::uint32_t type, std::uint64_t bytes);

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
  void lowerLimits(const LimitOverrides& overrides);
  void limitMemory(std::uint64_t cap);

  VkInstance instance_ = VK_NULL_HANDLE;
  VkDebugUtilsMessengerEXT messenger_ = VK_NULL_HANDLE;
  VkSurfaceKHR surface_ = VK_NULL_HANDLE;
  VkPhysicalDevice physical_ = VK_NULL_HANDLE;
  VkDevice device_ = VK_NULL_HANDLE;
  VkQueue queue_ = VK_NULL_HANDLE;
  VkCommandPool oneShotPool_ = VK_NULL_HANDLE;
  std::uint32_t queueFamily_ = 0;
  std::uint32_t timestampValidBits_ = 0;
  bool queueDraws_ = false;
  bool stagingOnly_ = false;
  std::uint32_t subgroupSize_ = 0;
  VkDeviceSize maxAllocationSize_ = 0;
  VkPhysicalDeviceProperties properties_{};
  VkPhysicalDeviceMemoryProperties memory_{};
  DeviceInfo info_;
  std::string driver_;
  Validation validation_ = Validation::Off;

  mutable std::mutex messageMutex_;
  std::uint64_t messageCount_ = 0;
  std::vector<std::string> messages_;

  mutable std::mutex memoryMutex_;
  std::vector<std::uint64_t> heapUsed_;   // bytes per heap
  std::vector<std::uint64_t> heapLimit_;  // bytes per heap
  std::uint64_t deviceLocalUsed_ = 0;
  std::uint64_t deviceLocalPeak_ = 0;

  std::unique_ptr<PipelineCache> pipelines_;  // destroyed before the device
};

}  // namespace hemo::gpu
