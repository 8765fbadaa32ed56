#pragma once
// CPU twin of the open ends' refill (sph/open_spawn.comp, hemo/sim/inflow.hpp): over the
// fluid's slots [0, n), each end serves up to its buffer's deficit of crossers, those that owe
// it an image (pending 1 inlet, 2 outlet) first and then those that spent a credit (3, 4),
// each class in slot order; the k-th served crosser (owing inlet, owing outlet, credited
// inlet, credited outlet) gives its image to the k-th parked slot (in slot order), at its
// position less `inletShift` or `outletShift` (OpenEnd::shift, a buffer length back along the
// end's axis), its normal's w (a credit) cleared. The crossers served, and those not needed,
// clear their flag; served crossers without a free slot stay pending and are counted as the
// shortfall.
#include <glm/vec3.hpp>
#include <glm/vec4.hpp>

#include <array>
#include <cstdint>
#include <vector>

namespace hemo::reference {

struct RefillResult {
  std::uint32_t spawned = 0, spawnedOutlet = 0;  // the inlet's images, the outlet's
  std::uint32_t shortfall = 0;
};

// Each buffer's deficit from the open ends' counters (HEMO_OPEN_COUNTER_*): the inlet's
// IN + PARKED_START - IN_BACK - SPAWNED, the outlet's OUT_BACK + PARKED_END - OUT -
// SPAWNED_OUTLET, modulo 2^32 as the GPU takes them, at least 0.
std::array<std::uint32_t, 2> openDeficits(const std::vector<std::uint32_t>& counters);

// Changes positions, velocities, normals (of the parked slots served) and pending in place;
// velocities[i].w is the kind (HEMO_KIND_PARKED marks a free slot).
RefillResult openRefill(std::uint32_t n, glm::vec3 inletShift, glm::vec3 outletShift, std::array<std::uint32_t, 2> deficits,
                        std::vector<glm::vec4>& positions, std::vector<glm::vec4>& velocities, std::vector<glm::vec4>& normals,
                        std::vector<std::uint32_t>& pending);

}  // namespace hemo::reference
