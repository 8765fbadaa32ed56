// The worker-thread count hemo asks lavapipe for (gpu::cpuDriverThreads).
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

}  // namespace
}  // namespace hemo::test
