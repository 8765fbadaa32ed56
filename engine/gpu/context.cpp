#include "hemo/gpu/context.hpp"

#include "hemo/gpu/pipeline_cache.hpp"

#include <algorithm>
#include <cctype>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <sstream>
#include <thread>

#if defined(__SANITIZE_ADDRESS__)
#define HEMO_SANITIZED 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define HEMO_SANITIZED 1
#endif
#endif
#ifdef HEMO_SANITIZED
#include <dlfcn.h>
#include <link.h>
#endif

namespace hemo::gpu {

const char* resultName(VkResult result) {
  switch (result) {
    case VK_SUCCESS: return "VK_SUCCESS";
    case VK_NOT_READY: return "VK_NOT_READY";
    case VK_TIMEOUT: return "VK_TIMEOUT";
    case VK_INCOMPLETE: return "VK_INCOMPLETE";
    case VK_ERROR_OUT_OF_HOST_MEMORY: return "VK_ERROR_OUT_OF_HOST_MEMORY";
    case VK_ERROR_OUT_OF_DEVICE_MEMORY: return "VK_ERROR_OUT_OF_DEVICE_MEMORY";
    case VK_ERROR_INITIALIZATION_FAILED: return "VK_ERROR_INITIALIZATION_FAILED";
    case VK_ERROR_DEVICE_LOST: return "VK_ERROR_DEVICE_LOST";
    case VK_ERROR_MEMORY_MAP_FAILED: return "VK_ERROR_MEMORY_MAP_FAILED";
    case VK_ERROR_LAYER_NOT_PRESENT: return "VK_ERROR_LAYER_NOT_PRESENT";
    case VK_ERROR_EXTENSION_NOT_PRESENT: return "VK_ERROR_EXTENSION_NOT_PRESENT";
    case VK_ERROR_FEATURE_NOT_PRESENT: return "VK_ERROR_FEATURE_NOT_PRESENT";
    case VK_ERROR_INCOMPATIBLE_DRIVER: return "VK_ERROR_INCOMPATIBLE_DRIVER";
    case VK_ERROR_TOO_MANY_OBJECTS: return "VK_ERROR_TOO_MANY_OBJECTS";
    case VK_ERROR_OUT_OF_POOL_MEMORY: return "VK_ERROR_OUT_OF_POOL_MEMORY";
    default: return "VkResult error";
  }
}

void check(VkResult result, const char* what) {
  if (result == VK_ERROR_DEVICE_LOST) {
    throw DeviceLost(std::string(what) + " failed: VK_ERROR_DEVICE_LOST: the device was lost (a GPU fault, a driver " +
                     "reset or a watchdog's timeout) and nothing more can run on it; a run that wrote checkpoints " +
                     "(hemo-run --checkpoint-every) continues from its last one with --resume");
  }
  if (result != VK_SUCCESS) {
    throw GpuError(std::string(what) + " failed: " + resultName(result) + " (" +
                   std::to_string(static_cast<int>(result)) + ")");
  }
}

std::string DeviceInfo::typeName() const {
  switch (type) {
    case VK_PHYSICAL_DEVICE_TYPE_DISCRETE_GPU: return "discrete GPU";
    case VK_PHYSICAL_DEVICE_TYPE_INTEGRATED_GPU: return "integrated GPU";
    case VK_PHYSICAL_DEVICE_TYPE_VIRTUAL_GPU: return "virtual GPU";
    case VK_PHYSICAL_DEVICE_TYPE_CPU: return "CPU";
    default: return "other";
  }
}

namespace {

constexpr const char* kValidationLayer = "VK_LAYER_KHRONOS_validation";

// Sanitizer builds only: every shared library loaded now (the Vulkan loader has loaded the
// driver and the layers) stays loaded until the process exits. Some drivers and layers keep
// allocations to the end (lavapipe's LLVM, the validation layer), and the loader unloads them
// when the last instance goes; LeakSanitizer, which reports at exit, then cannot name their
// module, and tests/lsan.supp, which suppresses those libraries by name and nothing of hemo,
// cannot match them. Pinned, they are named, and a leak from hemo's own code still fails.
void keepDriverLibrariesLoaded() {
#ifdef HEMO_SANITIZED
  std::vector<std::string> names;
  dl_iterate_phdr(
      [](dl_phdr_info* info, std::size_t, void* out) {
        if (info->dlpi_name && info->dlpi_name[0]) static_cast<std::vector<std::string>*>(out)->push_back(info->dlpi_name);
        return 0;
      },
      &names);
  // (after the iteration, which holds the dynamic linker's lock: dlopen takes it too)
  for (const std::string& name : names) dlopen(name.c_str(), RTLD_LAZY | RTLD_NOLOAD | RTLD_NODELETE);
#endif
}

bool hasLayer(const char* name) {
  std::uint32_t count = 0;
  vkEnumerateInstanceLayerProperties(&count, nullptr);
  std::vector<VkLayerProperties> layers(count);
  vkEnumerateInstanceLayerProperties(&count, layers.data());
  return std::any_of(layers.begin(), layers.end(),
                     [&](const VkLayerProperties& l) { return std::strcmp(l.layerName, name) == 0; });
}

bool layerHasExtension(const char* layer, const char* extension) {
  std::uint32_t count = 0;
  vkEnumerateInstanceExtensionProperties(layer, &count, nullptr);
  std::vector<VkExtensionProperties> extensions(count);
  vkEnumerateInstanceExtensionProperties(layer, &count, extensions.data());
  return std::any_of(extensions.begin(), extensions.end(),
                     [&](const VkExtensionProperties& e) { return std::strcmp(e.extensionName, extension) == 0; });
}

// lavapipe reads LP_NUM_THREADS when an instance enumerates its device (cpuDriverThreads).
void tuneCpuDriver() {
  const std::string threads = cpuDriverThreads(std::getenv("LP_NUM_THREADS"), std::thread::hardware_concurrency());
  if (!threads.empty()) setenv("LP_NUM_THREADS", threads.c_str(), 0);
}

VkInstance createInstance(Validation validation, const std::vector<std::string>& extra = {}) {
  tuneCpuDriver();
  std::uint32_t loaderVersion = VK_API_VERSION_1_0;
  vkEnumerateInstanceVersion(&loaderVersion);
  if (loaderVersion < VK_API_VERSION_1_2) {
    throw GpuError("the Vulkan loader supports only API " +
                   std::to_string(VK_API_VERSION_MAJOR(loaderVersion)) + "." +
                   std::to_string(VK_API_VERSION_MINOR(loaderVersion)) + "; hemo needs 1.2");
  }
  VkApplicationInfo app{VK_STRUCTURE_TYPE_APPLICATION_INFO};
  app.pApplicationName = "hemo";
  app.pEngineName = "hemo";
  app.apiVersion = VK_API_VERSION_1_2;
  std::vector<const char*> layers;
  std::vector<const char*> extensions;
  // The layer's optional checks, enabled through VK_EXT_validation_features (the layer
  // provides the extension). Environment settings such as VK_LAYER_ENABLES add to these.
  std::vector<VkValidationFeatureEnableEXT> enables;
  switch (validation) {
    case Validation::Standard:
      enables.push_back(VK_VALIDATION_FEATURE_ENABLE_SYNCHRONIZATION_VALIDATION_EXT);
      break;
    case Validation::GpuAssisted:
      enables.push_back(VK_VALIDATION_FEATURE_ENABLE_GPU_ASSISTED_EXT);
      enables.push_back(VK_VALIDATION_FEATURE_ENABLE_GPU_ASSISTED_RESERVE_BINDING_SLOT_EXT);
      break;
    case Validation::Core:
    case Validation::Off:
      break;
  }
  VkValidationFeaturesEXT features{VK_STRUCTURE_TYPE_VALIDATION_FEATURES_EXT};
  features.enabledValidationFeatureCount = static_cast<std::uint32_t>(enables.size());
  features.pEnabledValidationFeatures = enables.data();
  if (validation != Validation::Off) {
    if (!hasLayer(kValidationLayer)) {
      throw GpuError(std::string("validation was requested but ") + kValidationLayer +
                     " is not installed (Debian package vulkan-validationlayers)");
    }
    layers.push_back(kValidationLayer);
    extensions.push_back(VK_EXT_DEBUG_UTILS_EXTENSION_NAME);
    if (!enables.empty()) {
      if (!layerHasExtension(kValidationLayer, VK_EXT_VALIDATION_FEATURES_EXTENSION_NAME)) {
        throw GpuError(std::string(kValidationLayer) + " lacks " + VK_EXT_VALIDATION_FEATURES_EXTENSION_NAME +
                       ", needed for " + validationName(validation) + " validation");
      }
      extensions.push_back(VK_EXT_VALIDATION_FEATURES_EXTENSION_NAME);
    }
  }
  for (const std::string& e : extra) extensions.push_back(e.c_str());
  VkInstanceCreateInfo info{VK_STRUCTURE_TYPE_INSTANCE_CREATE_INFO};
  if (!enables.empty()) info.pNext = &features;
  info.pApplicationInfo = &app;
  info.enabledLayerCount = static_cast<std::uint32_t>(layers.size());
  info.ppEnabledLayerNames = layers.data();
  info.enabledExtensionCount = static_cast<std::uint32_t>(extensions.size());
  info.ppEnabledExtensionNames = extensions.data();
  VkInstance instance = VK_NULL_HANDLE;
  const VkResult r = vkCreateInstance(&info, nullptr, &instance);
  if (r == VK_ERROR_INCOMPATIBLE_DRIVER) {
    throw GpuError("no Vulkan driver is installed (on Debian: mesa-vulkan-drivers for lavapipe)");
  }
  check(r, "vkCreateInstance");
  keepDriverLibrariesLoaded();
  return instance;
}

std::vector<VkPhysicalDevice> physicalDevices(VkInstance instance) {
  std::uint32_t count = 0;
  check(vkEnumeratePhysicalDevices(instance, &count, nullptr), "vkEnumeratePhysicalDevices");
  std::vector<VkPhysicalDevice> devices(count);
  check(vkEnumeratePhysicalDevices(instance, &count, devices.data()), "vkEnumeratePhysicalDevices");
  keepDriverLibrariesLoaded();
  devices.resize(count);
  return devices;
}

DeviceInfo describe(VkPhysicalDevice device, std::uint32_t index) {
  VkPhysicalDeviceProperties p{};
  vkGetPhysicalDeviceProperties(device, &p);
  return DeviceInfo{index, p.deviceName, p.deviceType, p.apiVersion};
}

int typeRank(VkPhysicalDeviceType type) {
  switch (type) {
    case VK_PHYSICAL_DEVICE_TYPE_DISCRETE_GPU: return 0;
    case VK_PHYSICAL_DEVICE_TYPE_INTEGRATED_GPU: return 1;
    case VK_PHYSICAL_DEVICE_TYPE_VIRTUAL_GPU: return 2;
    case VK_PHYSICAL_DEVICE_TYPE_CPU: return 3;
    default: return 4;
  }
}

std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return std::tolower(c); });
  return s;
}

std::string deviceListText(const std::vector<DeviceInfo>& infos) {
  std::ostringstream out;
  if (infos.empty()) {
    out << " (no Vulkan devices found)";
  }
  for (const auto& d : infos) {
    out << "\n  [" << d.index << "] " << d.name << " (" << d.typeName() << ", Vulkan "
        << VK_API_VERSION_MAJOR(d.apiVersion) << "." << VK_API_VERSION_MINOR(d.apiVersion) << ")";
  }
  return out.str();
}

// The compute-capable queue family of `device`, or -1. With a presentation surface, only a
// family with compute, graphics and present to that surface qualifies.
int computeFamily(VkPhysicalDevice device, VkSurfaceKHR surface = VK_NULL_HANDLE) {
  std::uint32_t count = 0;
  vkGetPhysicalDeviceQueueFamilyProperties(device, &count, nullptr);
  std::vector<VkQueueFamilyProperties> families(count);
  vkGetPhysicalDeviceQueueFamilyProperties(device, &count, families.data());
  // Prefer a family that also does graphics: the renderer shares the queue.
  int computeOnly = -1;
  for (std::uint32_t i = 0; i < count; ++i) {
    const VkQueueFlags flags = families[i].queueFlags;
    const bool both = (flags & VK_QUEUE_COMPUTE_BIT) && (flags & VK_QUEUE_GRAPHICS_BIT);
    if (surface) {
      VkBool32 present = VK_FALSE;
      if (both && vkGetPhysicalDeviceSurfaceSupportKHR(device, i, surface, &present) == VK_SUCCESS && present) {
        return static_cast<int>(i);
      }
      continue;
    }
    if (both) return static_cast<int>(i);
    if ((flags & VK_QUEUE_COMPUTE_BIT) && computeOnly < 0) computeOnly = static_cast<int>(i);
  }
  return computeOnly;
}

}  // namespace

std::vector<DeviceInfo> listDevices() {
  VkInstance instance = createInstance(Validation::Off);
  std::vector<DeviceInfo> infos;
  try {
    const auto devices = physicalDevices(instance);
    for (std::uint32_t i = 0; i < devices.size(); ++i) infos.push_back(describe(devices[i], i));
  } catch (...) {
    vkDestroyInstance(instance, nullptr);
    throw;
  }
  vkDestroyInstance(instance, nullptr);
  return infos;
}

VKAPI_ATTR VkBool32 VKAPI_CALL Context::onMessage(VkDebugUtilsMessageSeverityFlagBitsEXT severity,
                                                  VkDebugUtilsMessageTypeFlagsEXT /*types*/,
                                                  const VkDebugUtilsMessengerCallbackDataEXT* data,
                                                  void* user) {
  auto* self = static_cast<Context*>(user);
  const char* level = (severity & VK_DEBUG_UTILS_MESSAGE_SEVERITY_ERROR_BIT_EXT) ? "error" : "warning";
  std::lock_guard<std::mutex> lock(self->messageMutex_);
  ++self->messageCount_;
  if (self->messages_.size() < 64) {
    self->messages_.push_back(std::string("validation ") + level + ": " +
                              (data && data->pMessage ? data->pMessage : "(no text)"));
  }
  return VK_FALSE;
}

std::string cpuDriverThreads(const char* current, unsigned cores) {
  if (current != nullptr) return {};
  // Measured on a 2-core VM (hemo-bench speed), paired runs against one thread
  // per core: the dam break 10% faster with the same particle order, 18% with the fluid-first
  // order (which loses 16% at one thread per core).
  return std::to_string(3u * std::max(cores, 1u));
}

Validation validationFromText(const char* text) {
  const std::string v = text ? text : "";
  if (v.empty() || v == "0") return Validation::Off;
  if (v == "1" || v == "sync") return Validation::Standard;
  if (v == "core") return Validation::Core;
  if (v == "gpu") return Validation::GpuAssisted;
  throw std::invalid_argument("HEMO_VALIDATION is '" + v + "'; expected 0, 1, sync, core or gpu");
}

const char* validationName(Validation level) {
  switch (level) {
    case Validation::Off: return "no";
    case Validation::Standard: return "core and synchronization";
    case Validation::Core: return "core";
    case Validation::GpuAssisted: return "core and GPU-assisted";
  }
  return "unknown";
}

namespace {
bool flagFromEnvironment(const char* name) {
  const char* v = std::getenv(name);
  return v && std::string(v) != "" && std::string(v) != "0";
}

// The level HEMO_VALIDATION names, else Standard when the options ask for validation
// (HEMO_VALIDATION=gpu switches the test suite to GPU-assisted validation).
Validation chooseValidation(const ContextOptions& options) {
  const Validation fromEnvironment = validationFromText(std::getenv("HEMO_VALIDATION"));
  if (fromEnvironment != Validation::Off) return fromEnvironment;
  return options.validation ? Validation::Standard : Validation::Off;
}
}  // namespace

Context::Context(const ContextOptions& options)
    : stagingOnly_(options.stagingOnly || flagFromEnvironment("HEMO_FORCE_STAGING")),
      validation_(chooseValidation(options)) {
  instance_ = createInstance(validation_, options.instanceExtensions);
  try {
    if (validation_ != Validation::Off) {
      VkDebugUtilsMessengerCreateInfoEXT info{VK_STRUCTURE_TYPE_DEBUG_UTILS_MESSENGER_CREATE_INFO_EXT};
      info.messageSeverity = VK_DEBUG_UTILS_MESSAGE_SEVERITY_WARNING_BIT_EXT |
                             VK_DEBUG_UTILS_MESSAGE_SEVERITY_ERROR_BIT_EXT;
      info.messageType = VK_DEBUG_UTILS_MESSAGE_TYPE_GENERAL_BIT_EXT |
                         VK_DEBUG_UTILS_MESSAGE_TYPE_VALIDATION_BIT_EXT |
                         VK_DEBUG_UTILS_MESSAGE_TYPE_PERFORMANCE_BIT_EXT;
      info.pfnUserCallback = &Context::onMessage;
      info.pUserData = this;
      auto create = reinterpret_cast<PFN_vkCreateDebugUtilsMessengerEXT>(
          vkGetInstanceProcAddr(instance_, "vkCreateDebugUtilsMessengerEXT"));
      if (!create) throw GpuError("VK_EXT_debug_utils is not available with the validation layer");
      check(create(instance_, &info, nullptr, &messenger_), "vkCreateDebugUtilsMessengerEXT");
    }
    std::string selector = options.device;
    if (selector.empty()) {
      if (const char* env = std::getenv("HEMO_DEVICE")) selector = env;
    }
    if (options.createSurface) {
      surface_ = options.createSurface(instance_);
      if (!surface_) throw GpuError("the window system could not create a Vulkan surface");
    }
    pickDevice(selector);
    lowerLimits(options.limits);
    limitMemory(options.limits.deviceMemoryBytes);

    const float priority = 1.0f;
    VkDeviceQueueCreateInfo queueInfo{VK_STRUCTURE_TYPE_DEVICE_QUEUE_CREATE_INFO};
    queueInfo.queueFamilyIndex = queueFamily_;
    queueInfo.queueCount = 1;
    queueInfo.pQueuePriorities = &priority;
    VkDeviceCreateInfo deviceInfo{VK_STRUCTURE_TYPE_DEVICE_CREATE_INFO};
    deviceInfo.queueCreateInfoCount = 1;
    deviceInfo.pQueueCreateInfos = &queueInfo;
    const char* swapchain = VK_KHR_SWAPCHAIN_EXTENSION_NAME;
    if (surface_) {
      deviceInfo.enabledExtensionCount = 1;
      deviceInfo.ppEnabledExtensionNames = &swapchain;
    }
    check(vkCreateDevice(physical_, &deviceInfo, nullptr, &device_), "vkCreateDevice");
    vkGetDeviceQueue(device_, queueFamily_, 0, &queue_);

    VkCommandPoolCreateInfo poolInfo{VK_STRUCTURE_TYPE_COMMAND_POOL_CREATE_INFO};
    poolInfo.flags = VK_COMMAND_POOL_CREATE_TRANSIENT_BIT;
    poolInfo.queueFamilyIndex = queueFamily_;
    check(vkCreateCommandPool(device_, &poolInfo, nullptr, &oneShotPool_), "vkCreateCommandPool");
    pipelines_ = std::make_unique<PipelineCache>(*this);
  } catch (...) {
    if (device_) vkDestroyDevice(device_, nullptr);
    if (surface_) vkDestroySurfaceKHR(instance_, surface_, nullptr);
    if (messenger_) {
      auto destroy = reinterpret_cast<PFN_vkDestroyDebugUtilsMessengerEXT>(
          vkGetInstanceProcAddr(instance_, "vkDestroyDebugUtilsMessengerEXT"));
      if (destroy) destroy(instance_, messenger_, nullptr);
    }
    vkDestroyInstance(instance_, nullptr);
    throw;
  }
}

void Context::pickDevice(const std::string& selector) {
  const auto devices = physicalDevices(instance_);
  std::vector<DeviceInfo> infos;
  for (std::uint32_t i = 0; i < devices.size(); ++i) infos.push_back(describe(devices[i], i));
  if (devices.empty()) {
    throw GpuError("no Vulkan device found (on Debian, install mesa-vulkan-drivers for lavapipe)");
  }
  auto usable = [&](std::uint32_t i, std::string* why) {
    if (infos[i].apiVersion < VK_API_VERSION_1_2) {
      if (why) *why = "it supports only Vulkan " + std::to_string(VK_API_VERSION_MAJOR(infos[i].apiVersion)) +
                      "." + std::to_string(VK_API_VERSION_MINOR(infos[i].apiVersion)) + " (hemo needs 1.2)";
      return false;
    }
    if (computeFamily(devices[i], surface_) < 0) {
      if (why) *why = surface_ ? "it has no queue that computes, draws and presents to the window" : "it has no compute queue";
      return false;
    }
    VkPhysicalDeviceSubgroupProperties subgroup{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_SUBGROUP_PROPERTIES};
    VkPhysicalDeviceProperties2 props{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_PROPERTIES_2};
    props.pNext = &subgroup;
    vkGetPhysicalDeviceProperties2(devices[i], &props);
    const VkSubgroupFeatureFlags needed = VK_SUBGROUP_FEATURE_BASIC_BIT | VK_SUBGROUP_FEATURE_VOTE_BIT |
                                          VK_SUBGROUP_FEATURE_ARITHMETIC_BIT;
    if (!(subgroup.supportedStages & VK_SHADER_STAGE_COMPUTE_BIT) ||
        (subgroup.supportedOperations & needed) != needed) {
      if (why) *why = "it lacks subgroup basic/vote/arithmetic operations in compute shaders";
      return false;
    }
    return true;
  };

  std::int64_t chosen = -1;
  if (!selector.empty()) {
    const bool numeric = std::all_of(selector.begin(), selector.end(),
                                     [](unsigned char c) { return std::isdigit(c); });
    if (numeric) {
      const unsigned long idx = std::stoul(selector);
      if (idx >= infos.size()) {
        throw GpuError("device index " + selector + " does not exist; devices:" + deviceListText(infos));
      }
      chosen = static_cast<std::int64_t>(idx);
    } else {
      for (const auto& d : infos) {
        if (lower(d.name).find(lower(selector)) != std::string::npos) {
          chosen = d.index;
          break;
        }
      }
      if (chosen < 0) {
        throw GpuError("no device name contains '" + selector + "'; devices:" + deviceListText(infos));
      }
    }
    std::string why;
    if (!usable(static_cast<std::uint32_t>(chosen), &why)) {
      throw GpuError("device '" + infos[chosen].name + "' cannot run hemo: " + why);
    }
  } else {
    for (std::uint32_t i = 0; i < infos.size(); ++i) {
      if (!usable(i, nullptr)) continue;
      if (chosen < 0 || typeRank(infos[i].type) < typeRank(infos[chosen].type)) chosen = i;
    }
    if (chosen < 0) {
      throw GpuError("no Vulkan device can run hemo (needs Vulkan 1.2, a compute queue and subgroup "
                     "arithmetic); devices:" + deviceListText(infos));
    }
  }

  physical_ = devices[chosen];
  info_ = infos[chosen];
  queueFamily_ = static_cast<std::uint32_t>(computeFamily(physical_, surface_));

  VkPhysicalDeviceSubgroupProperties subgroup{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_SUBGROUP_PROPERTIES};
  VkPhysicalDeviceMaintenance3Properties maintenance3{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_MAINTENANCE_3_PROPERTIES};
  VkPhysicalDeviceDriverProperties driver{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_DRIVER_PROPERTIES};
  subgroup.pNext = &maintenance3;
  maintenance3.pNext = &driver;
  VkPhysicalDeviceProperties2 props{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_PROPERTIES_2};
  props.pNext = &subgroup;
  vkGetPhysicalDeviceProperties2(physical_, &props);
  properties_ = props.properties;
  subgroupSize_ = subgroup.subgroupSize;
  driver_ = driver.driverName;
  if (driver.driverInfo[0] != '\0') driver_.append(1, ' ').append(driver.driverInfo);
  maxAllocationSize_ = maintenance3.maxMemoryAllocationSize;
  vkGetPhysicalDeviceMemoryProperties(physical_, &memory_);

  std::uint32_t familyCount = 0;
  vkGetPhysicalDeviceQueueFamilyProperties(physical_, &familyCount, nullptr);
  std::vector<VkQueueFamilyProperties> families(familyCount);
  vkGetPhysicalDeviceQueueFamilyProperties(physical_, &familyCount, families.data());
  timestampValidBits_ = families[queueFamily_].timestampValidBits;
  queueDraws_ = (families[queueFamily_].queueFlags & VK_QUEUE_GRAPHICS_BIT) != 0;
}

void Context::lowerLimits(const LimitOverrides& o) {
  VkPhysicalDeviceLimits& l = properties_.limits;
  auto lower = [](std::uint32_t& limit, std::uint32_t to) {
    if (to != 0) limit = std::min(limit, to);
  };
  lower(l.maxComputeWorkGroupCount[0], o.maxComputeWorkGroupCountX);
  lower(l.maxTexelBufferElements, o.maxTexelBufferElements);
  lower(l.maxStorageBufferRange, o.maxStorageBufferRange);
  lower(l.maxPerStageDescriptorStorageBuffers, o.maxPerStageDescriptorStorageBuffers);
  lower(timestampValidBits_, o.timestampValidBits);
  if (!o.timestamps) timestampValidBits_ = 0;
}

void Context::limitMemory(std::uint64_t cap) {
  if (const char* env = std::getenv("HEMO_DEVICE_MEMORY_MIB"); env && *env) {
    char* end = nullptr;
    const unsigned long long mib = std::strtoull(env, &end, 10);
    if (*end != '\0' || mib == 0 || mib > (1ull << 40)) {
      throw GpuError(std::string("HEMO_DEVICE_MEMORY_MIB must be a positive whole number of MiB, got '") + env + "'");
    }
    cap = cap == 0 ? mib << 20 : std::min<std::uint64_t>(cap, mib << 20);
  }
  heapUsed_.assign(memory_.memoryHeapCount, 0);
  heapLimit_.resize(memory_.memoryHeapCount);
  for (std::uint32_t h = 0; h < memory_.memoryHeapCount; ++h) {
    heapLimit_[h] = memory_.memoryHeaps[h].size;
    if (cap != 0 && (memory_.memoryHeaps[h].flags & VK_MEMORY_HEAP_DEVICE_LOCAL_BIT)) {
      heapLimit_[h] = std::min<std::uint64_t>(heapLimit_[h], cap);
    }
  }
}

namespace {
std::string gib(std::uint64_t bytes) {
  char text[64];
  std::snprintf(text, sizeof text, "%.3f GiB (%llu bytes)", double(bytes) / double(1ull << 30),
                static_cast<unsigned long long>(bytes));
  return text;
}
}  // namespace

void Context::takeMemory(std::uint32_t type, std::uint64_t bytes, const std::string& name) {
  std::lock_guard<std::mutex> lock(memoryMutex_);
  const std::uint32_t heap = memory_.memoryTypes[type].heapIndex;
  const bool local = (memory_.memoryHeaps[heap].flags & VK_MEMORY_HEAP_DEVICE_LOCAL_BIT) != 0;
  if (heapUsed_[heap] + bytes > heapLimit_[heap]) {
    const std::uint64_t needed = heapUsed_[heap] + bytes;
    throw OutOfDeviceMemory("the device's memory cannot hold buffer '" + name + "' of " + gib(bytes) + ": with it hemo would hold " +
                                gib(needed) + " of " + (local ? "device-local " : "host ") + "heap " + std::to_string(heap) +
                                ", which has " + gib(heapLimit_[heap]) + "; the scene needs at least " + gib(needed) +
                                " (fewer particles, or a device with more memory)",
                            needed, heapLimit_[heap]);
  }
  heapUsed_[heap] += bytes;
  if (local) {
    deviceLocalUsed_ += bytes;
    deviceLocalPeak_ = std::max(deviceLocalPeak_, deviceLocalUsed_);
  }
}

void Context::releaseMemory(std::uint32_t type, std::uint64_t bytes) {
  std::lock_guard<std::mutex> lock(memoryMutex_);
  const std::uint32_t heap = memory_.memoryTypes[type].heapIndex;
  heapUsed_[heap] -= std::min(heapUsed_[heap], bytes);
  if (memory_.memoryHeaps[heap].flags & VK_MEMORY_HEAP_DEVICE_LOCAL_BIT) {
    deviceLocalUsed_ -= std::min(deviceLocalUsed_, bytes);
  }
}

std::uint64_t Context::deviceMemoryBytes() const {
  std::lock_guard<std::mutex> lock(memoryMutex_);
  return deviceLocalUsed_;
}

std::uint64_t Context::peakDeviceMemoryBytes() const {
  std::lock_guard<std::mutex> lock(memoryMutex_);
  return deviceLocalPeak_;
}

void Context::resetPeakDeviceMemoryBytes() {
  std::lock_guard<std::mutex> lock(memoryMutex_);
  deviceLocalPeak_ = deviceLocalUsed_;
}

std::uint64_t Context::deviceMemoryCapacity() const {
  std::uint64_t total = 0;
  for (std::uint32_t h = 0; h < memory_.memoryHeapCount; ++h) {
    if (memory_.memoryHeaps[h].flags & VK_MEMORY_HEAP_DEVICE_LOCAL_BIT) total += heapLimit_[h];
  }
  return total;
}

Context::~Context() {
  if (device_) {
    vkDeviceWaitIdle(device_);
    pipelines_.reset();
    vkDestroyCommandPool(device_, oneShotPool_, nullptr);
    vkDestroyDevice(device_, nullptr);
  }
  if (surface_) vkDestroySurfaceKHR(instance_, surface_, nullptr);
  if (messenger_) {
    auto destroy = reinterpret_cast<PFN_vkDestroyDebugUtilsMessengerEXT>(
        vkGetInstanceProcAddr(instance_, "vkDestroyDebugUtilsMessengerEXT"));
    if (destroy) destroy(instance_, messenger_, nullptr);
  }
  vkDestroyInstance(instance_, nullptr);
}

std::uint64_t Context::validationMessageCount() const {
  std::lock_guard<std::mutex> lock(messageMutex_);
  return messageCount_;
}

std::vector<std::string> Context::takeValidationMessages() {
  std::lock_guard<std::mutex> lock(messageMutex_);
  std::vector<std::string> out;
  out.swap(messages_);
  return out;
}

std::uint32_t Context::memoryType(std::uint32_t typeBits, VkMemoryPropertyFlags required,
                                  VkMemoryPropertyFlags preferred) const {
  int fallback = -1;
  for (std::uint32_t i = 0; i < memory_.memoryTypeCount; ++i) {
    if (!(typeBits & (1u << i))) continue;
    const VkMemoryPropertyFlags flags = memory_.memoryTypes[i].propertyFlags;
    if ((flags & required) != required) continue;
    if ((flags & preferred) == preferred) return i;
    if (fallback < 0) fallback = static_cast<int>(i);
  }
  if (fallback < 0) throw GpuError("no Vulkan memory type has the properties a buffer needs");
  return static_cast<std::uint32_t>(fallback);
}

VkMemoryPropertyFlags Context::memoryFlags(std::uint32_t type) const {
  return memory_.memoryTypes[type].propertyFlags;
}

void Context::runOnce(const std::function<void(VkCommandBuffer)>& record) {
  VkCommandBufferAllocateInfo alloc{VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO};
  alloc.commandPool = oneShotPool_;
  alloc.level = VK_COMMAND_BUFFER_LEVEL_PRIMARY;
  alloc.commandBufferCount = 1;
  VkCommandBuffer cmd = VK_NULL_HANDLE;
  check(vkAllocateCommandBuffers(device_, &alloc, &cmd), "vkAllocateCommandBuffers");
  VkFence fence = VK_NULL_HANDLE;
  try {
    VkCommandBufferBeginInfo begin{VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO};
    begin.flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT;
    check(vkBeginCommandBuffer(cmd, &begin), "vkBeginCommandBuffer");
    record(cmd);
    check(vkEndCommandBuffer(cmd), "vkEndCommandBuffer");
    VkFenceCreateInfo fenceInfo{VK_STRUCTURE_TYPE_FENCE_CREATE_INFO};
    check(vkCreateFence(device_, &fenceInfo, nullptr, &fence), "vkCreateFence");
    VkSubmitInfo submit{VK_STRUCTURE_TYPE_SUBMIT_INFO};
    submit.commandBufferCount = 1;
    submit.pCommandBuffers = &cmd;
    check(vkQueueSubmit(queue_, 1, &submit, fence), "vkQueueSubmit");
    check(vkWaitForFences(device_, 1, &fence, VK_TRUE, UINT64_MAX), "vkWaitForFences");
  } catch (...) {
    if (fence) vkDestroyFence(device_, fence, nullptr);
    vkFreeCommandBuffers(device_, oneShotPool_, 1, &cmd);
    throw;
  }
  vkDestroyFence(device_, fence, nullptr);
  vkFreeCommandBuffers(device_, oneShotPool_, 1, &cmd);
}

}  // namespace hemo::gpu
