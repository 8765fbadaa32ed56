// The asan preset's leak check reaches hemo's own code: with HEMO_LEAK_ON_PURPOSE=1 (the ctest
// entry unit.leak_reported, added in sanitizer builds) this test leaks a scene after a Vulkan
// context with the validation layer has come and gone, and LeakSanitizer must report the leak
// through tests/lsan.supp, which suppresses the driver's and the layer's allocations only.
// Without the variable it is skipped.
#include "hemo/gpu/context.hpp"
#include "hemo/scene/scene.hpp"

#include <gtest/gtest.h>

#include <cstdlib>

namespace hemo::test {
namespace {

scene::Scene* volatile sink = nullptr;

TEST(Sanitizers, LeakOnPurpose) {
  if (!std::getenv("HEMO_LEAK_ON_PURPOSE")) GTEST_SKIP() << "leaks only for unit.leak_reported (HEMO_LEAK_ON_PURPOSE=1)";
  {
    gpu::ContextOptions options;
    options.validation = true;
    gpu::Context context(options);  // the driver and the layer loaded, and their allocations kept
  }
  sink = new scene::Scene(scene::loadScene(std::string(HEMO_SOURCE_DIR) + "/tests/cli/tiny_tank.json"));
  sink = nullptr;  // the only pointer to it gone: a leak
}

}  // namespace
}  // namespace hemo::test
