// Host-side grid description and helpers (no GPU).
#include "hemo/gpu/primitives.hpp"
#include "hemo/sim/neighbour_grid.hpp"
#include "hemo/sim/sph.hpp"

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

// The rebuild test's tiles: whole tiles of at least the minimum size per axis (one where the
// extent is shorter), the half-sum the tiles allow from the smallest tile of an axis with
// tiles that are not neighbours, and positions beyond the domain in the edge tiles.
TEST(TileGrid, CoversTheDomainWithWholeTiles) {
  const auto g = sim::TileGrid::covering({0, 0, 0}, {1.0f, 0.25f, 0.62f}, 2u, 0.3f, 0.2f, 0.02f);
  EXPECT_EQ(g.count[0], 3u);  // floor(1 / 0.3): tiles of 0.333
  EXPECT_EQ(g.count[1], 1u);  // shorter than a tile
  EXPECT_EQ(g.count[2], 2u);  // two tiles are always neighbours
  EXPECT_EQ(g.count[3], 2u);  // y periodic
  EXPECT_NEAR(g.origin[3], 0.5f * (1.0f / 3.0f - 0.2f), 1e-5f);
  EXPECT_FLOAT_EQ(g.invSize[3], 0.02f * 0.02f);
  EXPECT_EQ(g.cellOf({0.5f, 0.1f, 0.1f}), glm::uvec3(1, 0, 0));
  EXPECT_EQ(g.cellOf({-3.0f, 9.0f, 0.4f}), glm::uvec3(0, 0, 1));
  EXPECT_EQ(g.cellOf({1e30f, -1e30f, NAN}).x, 2u);
  // no axis with three tiles: every pair of tiles are neighbours, any half-sum will do
  EXPECT_GT(sim::TileGrid::covering({0, 0, 0}, {0.5f, 0.5f, 0.5f}, 0u, 0.3f, 0.2f, 0.02f).origin[3], 1e37f);
}

TEST(TileGrid, LargeDomainsGetFewerLargerTiles) {
  const auto g = sim::TileGrid::covering({0, 0, 0}, {100.0f, 100.0f, 100.0f}, 0u, 0.3f, 0.2f, 0.02f);
  EXPECT_LE(g.tiles(), sim::TileGrid::kMaxTiles);
  EXPECT_GE(g.tiles(), sim::TileGrid::kMaxTiles / 4);
  EXPECT_THROW(sim::TileGrid::covering({0, 0, 0}, {1, 1, 1}, 0u, 0.1f, 0.2f, 0.02f), std::invalid_argument);
  EXPECT_THROW(sim::TileGrid::covering({0, 0, 0}, {1, NAN, 1}, 0u, 0.3f, 0.2f, 0.02f), std::invalid_argument);
}

}  // namespace
}  // namespace hemo
