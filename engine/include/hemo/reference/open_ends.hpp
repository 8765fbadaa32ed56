#pragma once
// CPU twin of the open ends' refill (sph/open_spawn.comp, hemo/sim/inflow.hpp): over the
// fluid's slots [0, n), the k-th slot flagged pending (in slot order) gives its image to the
// k-th parked slot (in slot order), at its position less `inletShift` (pending 1, the inlet's)
// or `outletShift` (pending 2, the outlet's; OpenEnd::shift, a buffer length back along the
// end's axis); the pending slots served clear their flag, the others stay pending and are
// counted as the shortfall.
#include <glm/vec3.hpp>
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
RefillResult openRefill(std::uint32_t n, glm::vec3 inletShift, glm::vec3 outletShift, std::vector<glm::vec4>& positions,
                        std::vector<glm::vec4>& velocities, std::vector<glm::vec4>& normals,
                        std::vector<std::uint32_t>& pending);

}  // namespace hemo::reference
