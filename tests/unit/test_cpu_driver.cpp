// Context settings read from the environment: the worker-thread count hemo asks lavapipe for
// (gpu::cpuDriverThreads) and the validation level (gpu::validationFromText).
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
