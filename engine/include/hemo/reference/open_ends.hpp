#pragma once
// CPU twin of the open inlet's refill (sph/open_spawn.comp, hemo/sim/inflow.hpp): over the
// fluid's slots [0, n), the k-th slot flagged pending (in slot order) gives its image, shifted
// `shift` upstream along x, to the k-th parked slot (in slot order); the pending slots served
// clear their flag, the others stay pending and are counted as the shortfall.
#include <glm/vec4.hpp>

#include <cstdint>
#include <vector>

namespace hemo::reference {

struct RefillResult {
  std::uint32_t spawned = 0;
  std::uint32_t shortfall = 0;
};

// Changes positions, velocities, normals (of the parked slots served) and pending in place;
// velocities[i].w is the kind (HEMO_KIND_PARKED marks a free slot).
RefillResult openRefill(std::uint32_t n, float shift, std::vector<glm::vec4>& positions,
                        std::vector<glm::vec4>& velocities, std::vector<glm::vec4>& normals,
                        std::vector<std::uint32_t>& pending);

}  // namespace hemo::reference
