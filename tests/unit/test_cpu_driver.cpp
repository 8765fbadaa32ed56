// Context settings read from the environment: the worker-thread count hemo asks lavapipe for
// (gpu::cpuDriverThreads) and the validation level (gpu::validationFromText); and how Vulkan
// failures are named (gpu::check).
#include "hemo/gpu/context.hpp"

#include <gtest/gtest.h>

namespace hemo::test {
namespace {

TEST(CpuDriverThreads, ThreePerCoreUnlessTheUserSetsIt) {
  EXPECT_EQ(gpu::cpuDriverThreads(nullptr, 2), "6");
  EXPECT_EQ(gpu::cpuDriverThreads(nullptr, 1), "3");
  EXPECT_EQ(gpu::cpuDriverThreads(nullptr, 0), "3");  // an unknown core count counts as one
  EXPECT_EQ(gpu::cpuDriverThreads(nullptr, 16), "48");  // lavapipe caps it at its maximum
  EXPECT_EQ(gpu::cpuDriverThreads("2", 8), "");  // the user's setting stands
  EXPECT_EQ(gpu::cpuDriverThreads("", 8), "");
}

TEST(ValidationLevel, ReadFromHemoValidation) {
  EXPECT_EQ(gpu::validationFromText(nullptr), gpu::Validation::Off);
  EXPECT_EQ(gpu::validationFromText(""), gpu::Validation::Off);
  EXPECT_EQ(gpu::validationFromText("0"), gpu::Validation::Off);
  EXPECT_EQ(gpu::validationFromText("1"), gpu::Validation::Standard);
  EXPECT_EQ(gpu::validationFromText("sync"), gpu::Validation::Standard);
  EXPECT_EQ(gpu::validationFromText("core"), gpu::Validation::Core);
  EXPECT_EQ(gpu::validationFromText("gpu"), gpu::Validation::GpuAssisted);
  try {
    gpu::validationFromText("yes");
    ADD_FAILURE() << "no error for 'yes'";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("HEMO_VALIDATION is 'yes'"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace hemo::test

namespace hemo::test {

// A lost device is named as such, with what the user can do; other failures name the result.
TEST(VulkanErrors, LostDeviceIsNamedWithTheWayOut) {
  try {
    gpu::check(VK_ERROR_DEVICE_LOST, "vkQueueSubmit");
    FAIL() << "no exception";
  } catch (const gpu::DeviceLost& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("vkQueueSubmit failed: VK_ERROR_DEVICE_LOST: the device was lost"), std::string::npos) << m;
    EXPECT_NE(m.find("--resume"), std::string::npos) << m;
  }
  try {
    gpu::check(VK_ERROR_OUT_OF_DEVICE_MEMORY, "vkAllocateMemory");
    FAIL() << "no exception";
  } catch (const gpu::DeviceLost&) {
    FAIL() << "not a lost device";
  } catch (const gpu::GpuError& e) {
    EXPECT_NE(std::string(e.what()).find("vkAllocateMemory failed: VK_ERROR_OUT_OF_DEVICE_MEMORY"), std::string::npos);
  }
  EXPECT_NO_THROW(gpu::check(VK_SUCCESS, "vkQueueWaitIdle"));
}

}  // namespace hemo::test
