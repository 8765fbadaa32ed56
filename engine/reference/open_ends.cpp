#include "hemo/reference/open_ends.hpp"

#include "interface/sph.h"

#include <algorithm>

namespace hemo::reference {

std::array<std::uint32_t, 2> openDeficits(const std::vector<std::uint32_t>& c) {
  const auto inlet = std::int32_t(c[HEMO_OPEN_COUNTER_IN] + c[HEMO_OPEN_COUNTER_PARKED_START] - c[HEMO_OPEN_COUNTER_IN_BACK] -
                                  c[HEMO_OPEN_COUNTER_SPAWNED]);
  const auto outlet = std::int32_t(c[HEMO_OPEN_COUNTER_OUT_BACK] + c[HEMO_OPEN_COUNTER_PARKED_END] - c[HEMO_OPEN_COUNTER_OUT] -
                                   c[HEMO_OPEN_COUNTER_SPAWNED_OUTLET]);
  return {std::uint32_t(std::max(inlet, 0)), std::uint32_t(std::max(outlet, 0))};
}

RefillResult openRefill(std::uint32_t n, glm::vec3 inletShift, glm::vec3 outletShift, std::array<std::uint32_t, 2> deficits,
                        std::vector<glm::vec4>& positions, std::vector<glm::vec4>& velocities, std::vector<glm::vec4>& normals,
                        std::vector<std::uint32_t>& pending) {
  std::vector<std::uint32_t> byClass[4], parked;
  for (std::uint32_t i = 0; i < n; ++i) {
    if (pending[i] >= 1 && pending[i] <= 4) byClass[pending[i] - 1].push_back(i);
    else if (pending[i] == 0 && std::uint32_t(velocities[i].w) == HEMO_KIND_PARKED) parked.push_back(i);
  }
  // The served crossers in order: owing inlet, owing outlet, credited inlet, credited outlet.
  std::vector<std::uint32_t> served;
  std::uint32_t owingServed[2] = {};
  for (std::uint32_t c = 0; c < 4; ++c) {
    const std::uint32_t e = c & 1;
    const std::uint32_t limit = c < 2 ? std::min<std::uint32_t>(deficits[e], std::uint32_t(byClass[c].size()))
                                      : std::min<std::uint32_t>(deficits[e] - owingServed[e], std::uint32_t(byClass[c].size()));
    if (c < 2) owingServed[e] = limit;
    for (std::uint32_t r = 0; r < byClass[c].size(); ++r) {
      const std::uint32_t i = byClass[c][r];
      if (r < limit) served.push_back(i);
      else pending[i] = 0;  // not needed: its buffer is full
    }
  }
  RefillResult out;
  for (std::size_t k = 0; k < served.size(); ++k) {
    const std::uint32_t from = served[k];
    if (k >= parked.size()) {
      ++out.shortfall;
      continue;
    }
    const bool outlet = ((pending[from] - 1) & 1) != 0;
    const std::uint32_t slot = parked[k];
    positions[slot] = glm::vec4(glm::vec3(positions[from]) - (outlet ? outletShift : inletShift), positions[from].w);
    velocities[slot] = velocities[from];
    normals[slot] = glm::vec4(glm::vec3(normals[from]), 0.0f);
    (outlet ? out.spawnedOutlet : out.spawned) += 1;
  }
  for (std::size_t k = 0; k < served.size() && k < parked.size(); ++k) pending[served[k]] = 0;
  return out;
}

}  // namespace hemo::reference
