// Snapshot measurements shared by the tests and hemo-bench (hemo/sim/probes.hpp), on
// hand-made snapshots whose answers are known.
#include "hemo/sim/probes.hpp"

#include <gtest/gtest.h>

#include <stdexcept>

namespace hemo::sim {
namespace {

Snapshot snapshotOf(const std::vector<glm::vec3>& x, const std::vector<ParticleKind>& kinds,
                    const std::vector<std::uint32_t>& ids) {
  Snapshot s;
  for (std::size_t i = 0; i < x.size(); ++i) {
    s.positions.emplace_back(x[i], 1.0f);
    s.velocities.emplace_back(0.0f, 0.0f, 0.0f, float(kinds[i]));
    s.densityPressure.emplace_back(1000.0f, 0.0f);
    s.ids.push_back(ids[i]);
  }
  return s;
}

// Particles are matched by id (the second snapshot lists them in another order), only fluid
// counts, and belowZ selects by where a particle started.
TEST(Probes, LargestDisplacementMatchesParticlesByIdAndSkipsBoundaries) {
  const auto F = ParticleKind::Fluid, B = ParticleKind::Boundary;
  const Snapshot a = snapshotOf({{0, 0, 0}, {0, 0, 1}, {5, 5, 5}}, {F, F, B}, {0, 1, 2});
  const Snapshot b = snapshotOf({{9, 9, 9}, {0, 0.6f, 1}, {0.3f, 0.4f, 0}}, {B, F, F}, {2, 1, 0});
  EXPECT_NEAR(largestDisplacement(a, b), 0.6, 1e-6);        // id 1; the boundary's 6.9 m is ignored
  EXPECT_NEAR(largestDisplacement(a, b, 0.5), 0.5, 1e-6);   // id 0 only (id 1 started at z = 1)
  EXPECT_NEAR(largestDisplacement(a, b, -1.0), 0.0, 1e-12);  // nobody started below z = -1
  const Snapshot fewer = snapshotOf({{0, 0, 0}}, {F}, {0});
  EXPECT_THROW(largestDisplacement(a, fewer), std::invalid_argument);
  const Snapshot badId = snapshotOf({{0, 0, 0}, {0, 0, 1}, {5, 5, 5}}, {F, F, B}, {0, 1, 7});
  EXPECT_THROW(largestDisplacement(a, badId), std::invalid_argument);
}

}  // namespace
}  // namespace hemo::sim
