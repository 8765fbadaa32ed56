#pragma once
// A run's state for bit-for-bit comparisons of runs.
#include "hemo/sim/simulation.hpp"

#include <glm/vec4.hpp>

#include <vector>

namespace hemo::test {

// Every particle's position and velocity (in id order).
inline std::vector<glm::vec4> positionsAndVelocities(const sim::Simulation& sim) {
  const sim::Snapshot s = sim.snapshot();
  std::vector<glm::vec4> state = s.positions;
  state.insert(state.end(), s.velocities.begin(), s.velocities.end());
  return state;
}

}  // namespace hemo::test
