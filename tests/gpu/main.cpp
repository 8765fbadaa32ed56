#include "gpu_test.hpp"

namespace {
// Destroys the shared context after the last test, while the Vulkan loader is still alive.
class ContextEnvironment : public ::testing::Environment {
 public:
  void TearDown() override { hemo::test::destroySharedContext(); }
};
}  // namespace

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  ::testing::AddGlobalTestEnvironment(new ContextEnvironment);
  return RUN_ALL_TESTS();
}
