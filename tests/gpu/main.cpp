#include "gpu_test.hpp"

#if defined(__SANITIZE_ADDRESS__)
#include <dlfcn.h>
#endif

namespace {
// Destroys the shared context after the last test, while the Vulkan loader is still alive.
class ContextEnvironment : public ::testing::Environment {
 public:
  void TearDown() override { hemo::test::destroySharedContext(); }
};
}  // namespace

int main(int argc, char** argv) {
#if defined(__SANITIZE_ADDRESS__)
  // The Vulkan loader unloads the driver and layers at vkDestroyInstance; keep them mapped so
  // LeakSanitizer can name the few allocations they never free (suppressed in
  // tests/lsan.supp) instead of reporting an anonymous module. Our own code is not covered.
  for (const char* lib : {"libvulkan_lvp.so", "libVkLayer_khronos_validation.so"}) {
    dlopen(lib, RTLD_NOW | RTLD_NODELETE);
  }
#endif
  ::testing::InitGoogleTest(&argc, argv);
  ::testing::AddGlobalTestEnvironment(new ContextEnvironment);
  return RUN_ALL_TESTS();
}
