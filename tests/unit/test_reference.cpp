// Properties of the CPU reference of the neighbour grid.
#include "hemo/reference/neighbours.hpp"

#include <gtest/gtest.h>

#include <random>

namespace hemo::reference {
namespace {

TEST(ReferenceGrid, CellsAreXFastestAndClamped) {
  Grid g{{0, 0, 0}, 1.0, {4, 3, 2}};
  bool out = true;
  EXPECT_EQ(cellLinear(cellCoords({2.5, 1.5, 1.5}, g, &out), g), 2u + 4u * (1u + 3u * 1u));
  EXPECT_FALSE(out);
  EXPECT_EQ(cellCoords({-5, 10, 0.5}, g, &out), glm::ivec3(0, 2, 0));
  EXPECT_TRUE(out);
}

TEST(ReferenceGrid, BuildIsAStablePartitionByCell) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(0.0, 3.0);
  std::vector<glm::dvec3> p(500);
  for (auto& x : p) x = {u(rng), u(rng), u(rng)};
  Grid g{{0, 0, 0}, 1.0, {3, 3, 3}};
  const auto b = buildGrid(p, g);
  ASSERT_EQ(b.cellStart.size(), 28u);
  EXPECT_EQ(b.cellStart.back(), 500u);
  for (std::uint32_t c = 0; c < 27; ++c) {
    for (std::uint32_t s = b.cellStart[c]; s < b.cellStart[c + 1]; ++s) {
      EXPECT_EQ(b.cellOfParticle[b.order[s]], c);
      if (s > b.cellStart[c]) {
        EXPECT_LT(b.order[s - 1], b.order[s]);
      }
    }
  }
}

TEST(ReferenceNeighbours, BruteForceIsSymmetricAndExcludesSelf) {
  std::vector<glm::dvec3> p = {{0, 0, 0}, {0.5, 0, 0}, {1.2, 0, 0}, {0, 0, 0}};
  const auto nb = neighboursBruteForce(p, 1.0);
  EXPECT_EQ(nb[0], (std::vector<std::uint32_t>{1, 3}));
  EXPECT_EQ(nb[1], (std::vector<std::uint32_t>{0, 2, 3}));
  EXPECT_EQ(nb[2], (std::vector<std::uint32_t>{1}));
}

}  // namespace
}  // namespace hemo::reference
