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

// Cells scaled per axis (the SPH list grid: narrow along x); a periodic axis splits its
// period into whole cells of at least the scaled size.
TEST(GridSpec, CellScaleWidensAxes) {
  const auto s = sim::GridSpec::covering({0, 0, 0}, {1.0f, 0.55f, 0.9f}, 0.1f, glm::bvec3(false, false, true),
                                         glm::vec3(1.0f, 2.0f, 2.5f));
  EXPECT_EQ(s.dims.x, 10u);
  EXPECT_EQ(s.dims.y, 3u);  // 0.55 / 0.2, rounded up
  EXPECT_EQ(s.dims.z, 3u);  // floor(0.9 / 0.25)
  EXPECT_FLOAT_EQ(s.invCellSize().x, 10.0f);
  EXPECT_FLOAT_EQ(s.invCellSize().y, 5.0f);
  EXPECT_FLOAT_EQ(s.invCellSize().z, 3.0f / 0.9f);
}

TEST(GridSpec, BadCellScaleIsRejectedWithAMessage) {
  for (const glm::vec3 scale : {glm::vec3(0.5f, 1.0f, 1.0f), glm::vec3(1.0f, NAN, 1.0f), glm::vec3(1.0f, 1.0f, INFINITY)}) {
    try {
      sim::GridSpec::covering({0, 0, 0}, {1, 1, 1}, 0.1f, glm::bvec3(false), scale);
      ADD_FAILURE() << "scale " << scale.x << " " << scale.y << " " << scale.z << " accepted";
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find("cell scale along"), std::string::npos) << e.what();
    }
  }
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
