// Host-side grid description and helpers (no GPU).
#include "hemo/gpu/primitives.hpp"
#include "hemo/sim/neighbour_grid.hpp"

#include <gtest/gtest.h>

#include <cmath>

namespace hemo {
namespace {

TEST(GridSpec, CoveringBoxRoundsUp) {
  const auto s = sim::GridSpec::covering({0, 0, 0}, {1.0f, 0.55f, 0.05f}, 0.1f);
  EXPECT_EQ(s.dims.x, 10u);
  EXPECT_EQ(s.dims.y, 6u);
  EXPECT_EQ(s.dims.z, 1u);
  EXPECT_EQ(s.cellCount(), 60u);
}

TEST(GridSpec, BadInputIsRejectedWithAMessage) {
  EXPECT_THROW(sim::GridSpec::covering({0, 0, 0}, {1, 1, 1}, 0.0f), std::invalid_argument);
  EXPECT_THROW(sim::GridSpec::covering({0, 0, 0}, {1, 1, 1}, -1.0f), std::invalid_argument);
  EXPECT_THROW(sim::GridSpec::covering({0, 0, 0}, {1, 1, 1}, NAN), std::invalid_argument);
  EXPECT_THROW(sim::GridSpec::covering({1, 0, 0}, {0, 1, 1}, 0.1f), std::invalid_argument);
  EXPECT_THROW(sim::GridSpec::covering({0, 0, 0}, {INFINITY, 1, 1}, 0.1f), std::invalid_argument);
  EXPECT_THROW(sim::GridSpec::covering({0, 0, 0}, {3000, 3000, 3000}, 1e-3f), std::invalid_argument);
  try {
    sim::GridSpec::covering({0, 0, 0}, {1, 1, 1}, -2.0f);
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("cell size"), std::string::npos);
  }
}

TEST(Primitives, BitsFor) {
  EXPECT_EQ(gpu::bitsFor(0), 0u);
  EXPECT_EQ(gpu::bitsFor(1), 1u);
  EXPECT_EQ(gpu::bitsFor(255), 8u);
  EXPECT_EQ(gpu::bitsFor(256), 9u);
  EXPECT_EQ(gpu::bitsFor(0xffffffffull), 32u);
  EXPECT_EQ(gpu::RadixSort::passesFor(0), 0u);
  EXPECT_EQ(gpu::RadixSort::passesFor(9), 2u);
  EXPECT_EQ(gpu::RadixSort::passesFor(32), 4u);
}

}  // namespace
}  // namespace hemo
