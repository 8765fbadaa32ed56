#pragma once
// CPU double-precision twins of the neighbour-grid stages, for tests and validation.
// Plain functions over plain arrays; no Vulkan.
#include <glm/vec3.hpp>

#include <cstdint>
#include <vector>

namespace hemo::reference {

struct Grid {
  glm::dvec3 origin{0.0};
  double cellSize = 0.0;
  glm::uvec3 dims{0u};
  std::uint32_t parts = 1;  // 2: fluid first (hemo::sim::GridSpec::parts)
};

// Cell coordinates clamped into the grid (as grid/hash.comp); `outside` tells if clamped.
glm::ivec3 cellCoords(const glm::dvec3& p, const Grid& grid, bool* outside = nullptr);
std::uint32_t cellLinear(const glm::ivec3& c, const Grid& grid);

struct GridBuild {
  std::vector<std::uint32_t> cellOfParticle;  // input order: the sort key, cell + part * cellCount
  std::vector<std::uint32_t> order;           // sorted slot -> input index (stable by key)
  std::vector<std::uint32_t> cellStart;       // parts * cellCount + 1 entries
  std::uint32_t outside = 0;
};
// With grid.parts = 2, `fluid` flags the fluid particles (part 0; the others are part 1).
GridBuild buildGrid(const std::vector<glm::dvec3>& positions, const Grid& grid,
                    const std::vector<bool>& fluid = {});

// All j != i with |x_i - x_j| < radius, ascending, by O(N^2) comparison; on axes with a
// non-zero `period` the distance is the minimum image.
std::vector<std::vector<std::uint32_t>> neighboursBruteForce(const std::vector<glm::dvec3>& positions, double radius,
                                                             const glm::dvec3& period = glm::dvec3(0.0));

}  // namespace hemo::reference
