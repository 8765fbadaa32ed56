#pragma once
// CPU twin of the open ends' refill (sph/open_spawn.comp, hemo/sim/inflow.hpp): over the
// fluid's slots [0, n), each end serves up to its buffer's deficit of crossers, those that owe
// it an image (HEMO_OPEN_OWING of interface/sph.h) first and then those that spent a credit
// (HEMO_OPEN_CREDITED), each class in slot order; the k-th served crosser (the owing of every
// end in end order, then the credited likewise) gives its image to the k-th parked slot (in
// slot order), at its position less its end's shift (OpenEnd::shift, a buffer length back
// along the end's axis), its normal's w (a credit) cleared. The crossers served, and those not
// needed, clear their flag; served crossers without a free slot stay pending and are counted
// as the shortfall.
#include <glm/vec3.hpp>
#include <glm/vec4.hpp>

#include <cstdint>
#include <vector>

namespace hemo::reference {

struct RefillResult {
  std::vector<std::uint32_t> spawned;  // images per end
  std::uint32_t shortfall = 0;
};

// Each of `ends` buffers' deficit from the open ends' counters (HEMO_OPEN_COUNTER_*):
// LEAVE + PARKED - ENTER - SPAWNED, modulo 2^32 as the GPU takes them, at least 0.
std::vector<std::uint32_t> openDeficits(const std::vector<std::uint32_t>& counters, std::uint32_t ends);

// Changes positions, velocities, normals (of the parked slots served) and pending in place;
// velocities[i].w is the kind (HEMO_KIND_PARKED marks a free slot). `shifts`: per end.
RefillResult openRefill(std::uint32_t n, const std::vector<glm::vec3>& shifts, const std::vector<std::uint32_t>& deficits,
                        std::vector<glm::vec4>& positions, std::vector<glm::vec4>& velocities, std::vector<glm::vec4>& normals,
                        std::vector<std::uint32_t>& pending);

}  // namespace hemo::reference
