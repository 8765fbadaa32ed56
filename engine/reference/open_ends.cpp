#include "hemo/reference/open_ends.hpp"

#include "interface/sph.h"

#include <algorithm>
#include <stdexcept>

namespace hemo::reference {

std::vector<std::uint32_t> openDeficits(const std::vector<std::uint32_t>& c, std::uint32_t ends) {
  std::vector<std::uint32_t> out;
  for (std::uint32_t e = 0; e < ends; ++e) {
    const auto d = std::int32_t(c.at(HEMO_OPEN_COUNTER_LEAVE(e)) + c.at(HEMO_OPEN_COUNTER_PARKED(e)) - c.at(HEMO_OPEN_COUNTER_ENTER(e)) -
                                c.at(HEMO_OPEN_COUNTER_SPAWNED(e)));
    out.push_back(std::uint32_t(std::max(d, 0)));
  }
  return out;
}

RefillResult openRefill(std::uint32_t n, const std::vector<glm::vec3>& shifts, const std::vector<std::uint32_t>& deficits,
                        std::vector<glm::vec4>& positions, std::vector<glm::vec4>& velocities, std::vector<glm::vec4>& normals,
                        std::vector<std::uint32_t>& pending) {
  const auto ends = std::uint32_t(shifts.size());
  if (deficits.size() != ends || ends == 0 || ends > HEMO_OPEN_MAX_ENDS) throw std::invalid_argument("openRefill: one shift and deficit per end");
  // The classes: owing of ends 0..E-1 (pending 1 + e), credited of ends 0..E-1 (1 + MAX + e).
  std::vector<std::vector<std::uint32_t>> byClass(2 * ends);
  std::vector<std::uint32_t> parked;
  for (std::uint32_t i = 0; i < n; ++i) {
    const std::uint32_t c = pending[i];
    if (c >= HEMO_OPEN_OWING(0u) && c < HEMO_OPEN_OWING(ends)) byClass[c - HEMO_OPEN_OWING(0u)].push_back(i);
    else if (c >= HEMO_OPEN_CREDITED(0u) && c < HEMO_OPEN_CREDITED(ends)) byClass[ends + c - HEMO_OPEN_CREDITED(0u)].push_back(i);
    else if (c == 0 && std::uint32_t(velocities[i].w) == HEMO_KIND_PARKED) parked.push_back(i);
  }
  // The served crossers in order, with their ends.
  std::vector<std::uint32_t> served, servedEnd;
  std::vector<std::uint32_t> owingServed(ends, 0);
  for (std::uint32_t k = 0; k < 2 * ends; ++k) {
    const std::uint32_t e = k % ends;
    const auto size = std::uint32_t(byClass[k].size());
    const std::uint32_t limit = k < ends ? std::min(deficits[e], size) : std::min(deficits[e] - owingServed[e], size);
    if (k < ends) owingServed[e] = limit;
    for (std::uint32_t r = 0; r < size; ++r) {
      const std::uint32_t i = byClass[k][r];
      if (r < limit) {
        served.push_back(i);
        servedEnd.push_back(e);
      } else {
        pending[i] = 0;  // not needed: its buffer is full
      }
    }
  }
  RefillResult out;
  out.spawned.assign(ends, 0);
  for (std::size_t k = 0; k < served.size(); ++k) {
    const std::uint32_t from = served[k];
    if (k >= parked.size()) {
      ++out.shortfall;
      continue;
    }
    const std::uint32_t slot = parked[k];
    positions[slot] = glm::vec4(glm::vec3(positions[from]) - shifts[servedEnd[k]], positions[from].w);
    velocities[slot] = velocities[from];
    normals[slot] = glm::vec4(glm::vec3(normals[from]), 0.0f);
    ++out.spawned[servedEnd[k]];
  }
  for (std::size_t k = 0; k < served.size() && k < parked.size(); ++k) pending[served[k]] = 0;
  return out;
}

}  // namespace hemo::reference
