#pragma once
// Shared by the vessel builders (engine/scene/): a spring appended to the network with each end
// recorded among the other's neighbours (the frames are chosen from those neighbours).
#include "hemo/sim/wall.hpp"

#include <cstdint>
#include <vector>

namespace hemo::scene {

inline void linkSpring(sim::SpringNetwork& net, std::vector<std::vector<std::uint32_t>>& adjacent, const sim::Spring& s) {
  net.springs.push_back(s);
  adjacent[s.a].push_back(s.b);
  adjacent[s.b].push_back(s.a);
}

}  // namespace hemo::scene
