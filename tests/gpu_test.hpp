#pragma once
// Shared GPU test fixture: one validation-enabled Context per test process. A test fails if
// the validation layer reported anything during it; it is skipped only when the machine has
// no Vulkan device at all.
#include "hemo/gpu/context.hpp"

#include <gtest/gtest.h>

#include <random>

namespace hemo::test {

// The process-wide context, or nullptr when no Vulkan device exists.
gpu::Context* sharedContext();
void destroySharedContext();

class GpuTest : public ::testing::Test {
 protected:
  void SetUp() override;
  void TearDown() override;
  gpu::Context& ctx() { return *context_; }

 private:
  gpu::Context* context_ = nullptr;
};

// Deterministic per-test random engine (seeded from the test name).
std::mt19937_64 rngFor(const char* salt = "");

}  // namespace hemo::test
