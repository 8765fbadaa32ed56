#include "gpu_test.hpp"

#include <functional>
#include <iostream>
#include <memory>

namespace hemo::test {

namespace {
std::unique_ptr<gpu::Context>& slot() {
  static std::unique_ptr<gpu::Context> context;
  return context;
}
bool& probed() {
  static bool done = false;
  return done;
}
}  // namespace

gpu::Context* sharedContext() {
  if (!probed()) {
    probed() = true;
    if (gpu::listDevices().empty()) return nullptr;
    gpu::ContextOptions options;
    options.validation = true;
    slot() = std::make_unique<gpu::Context>(options);  // throws (fails the test) if unusable
    std::cerr << "[hemo] device: " << slot()->info().name << " (" << slot()->info().typeName()
              << "), subgroup size " << slot()->subgroupSize() << ", "
              << gpu::validationName(slot()->validation()) << " validation\n";
  }
  return slot().get();
}

void destroySharedContext() { slot().reset(); }

void GpuTest::SetUp() {
  context_ = sharedContext();
  if (!context_) GTEST_SKIP() << "no Vulkan device on this machine";
  context_->takeValidationMessages();
}

void GpuTest::TearDown() {
  if (!context_) return;
  const auto messages = context_->takeValidationMessages();
  for (const auto& m : messages) ADD_FAILURE() << m;
}

std::mt19937_64 rngFor(const char* salt) {
  const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
  std::string key = info ? std::string(info->test_suite_name()) + "." + info->name() : "";
  key += salt;
  return std::mt19937_64(std::hash<std::string>{}(key));
}

}  // namespace hemo::test
