#include "hemo/reference/open_ends.hpp"

#include "interface/sph.h"

namespace hemo::reference {

RefillResult openRefill(std::uint32_t n, glm::vec3 inletShift, glm::vec3 outletShift, std::vector<glm::vec4>& positions,
                        std::vector<glm::vec4>& velocities, std::vector<glm::vec4>& normals,
                        std::vector<std::uint32_t>& pending) {
  std::vector<std::uint32_t> crossers, parked;
  for (std::uint32_t i = 0; i < n; ++i) {
    if (pending[i] != 0) crossers.push_back(i);
    else if (std::uint32_t(velocities[i].w) == HEMO_KIND_PARKED) parked.push_back(i);
  }
  RefillResult r;
  for (std::size_t k = 0; k < crossers.size(); ++k) {
    const std::uint32_t c = crossers[k];
    if (k >= parked.size()) {
      ++r.shortfall;
      continue;
    }
    const std::uint32_t s = parked[k];
    const glm::vec3 d = pending[c] == 2 ? outletShift : inletShift;
    positions[s] = glm::vec4(glm::vec3(positions[c]) - d, positions[c].w);
    velocities[s] = velocities[c];
    normals[s] = normals[c];
    pending[c] = 0;
    ++r.spawned;
  }
  return r;
}

}  // namespace hemo::reference
