#pragma once
// CPU twin of the open ends' refill (sph/open_spawn.comp, hemo/sim/inflow.hpp): over the
// fluid's slots [0, n), the k-th slot flagged pending (in slot order) gives its image to the
// k-th parked slot (in slot order), shifted `shift` upstream along x (pending 1, the inlet's)
// or `outletShift` downstream (pending 2, the outlet's); the pending slots served clear their
// flag, the others stay pending and are counted as the shortfall.
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
RefillResult openRefill(std::uint32_t n, float shift, float outletShift, std::vector<glm::vec4>& positions,
                        std::vector<glm::vec4>& velocities, std::vector<glm::vec4>& normals,
                        std::vector<std::uint32_t>& pending);

}  // namespace hemo::reference
