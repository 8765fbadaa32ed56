#include "hemo/reference/neighbours.hpp"

#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>
#include <numeric>

namespace hemo::reference {

glm::ivec3 cellCoords(const glm::dvec3& p, const Grid& grid, bool* outside) {
  glm::ivec3 c;
  bool out = false;
  for (int a = 0; a < 3; ++a) {
    const double f = std::floor((p[a] - grid.origin[a]) / grid.cellSize);
    const double hi = double(grid.dims[a]) - 1.0;
    if (f < 0.0 || f > hi) out = true;
    c[a] = static_cast<int>(std::clamp(f, 0.0, hi));
  }
  if (outside) *outside = out;
  return c;
}

std::uint32_t cellLinear(const glm::ivec3& c, const Grid& grid) {
  return std::uint32_t(c.x) + grid.dims.x * (std::uint32_t(c.y) + grid.dims.y * std::uint32_t(c.z));
}

GridBuild buildGrid(const std::vector<glm::dvec3>& positions, const Grid& grid, const std::vector<bool>& fluid) {
  GridBuild b;
  const std::size_t n = positions.size();
  const std::size_t cells = std::size_t(grid.dims.x) * grid.dims.y * grid.dims.z;
  const std::size_t keys = cells * grid.parts;
  b.cellOfParticle.resize(n);
  std::vector<std::uint32_t> counts(keys + 1, 0);
  for (std::size_t i = 0; i < n; ++i) {
    bool out = false;
    b.cellOfParticle[i] = cellLinear(cellCoords(positions[i], grid, &out), grid);
    if (grid.parts == 2 && !(i < fluid.size() && fluid[i])) b.cellOfParticle[i] += std::uint32_t(cells);
    b.outside += out ? 1 : 0;
    ++counts[b.cellOfParticle[i]];
  }
  b.cellStart.resize(keys + 1);
  std::exclusive_scan(counts.begin(), counts.end(), b.cellStart.begin(), 0u);
  b.order.resize(n);
  std::iota(b.order.begin(), b.order.end(), 0u);
  std::stable_sort(b.order.begin(), b.order.end(),
                   [&](std::uint32_t a, std::uint32_t c) { return b.cellOfParticle[a] < b.cellOfParticle[c]; });
  return b;
}

std::vector<std::vector<std::uint32_t>> neighboursBruteForce(const std::vector<glm::dvec3>& positions, double radius,
                                                             const glm::dvec3& period) {
  const std::size_t n = positions.size();
  std::vector<std::vector<std::uint32_t>> out(n);
  const double r2 = radius * radius;
  for (std::size_t i = 0; i < n; ++i) {
    for (std::size_t j = 0; j < n; ++j) {
      if (i == j) continue;
      glm::dvec3 d = positions[i] - positions[j];
      for (int a = 0; a < 3; ++a) {
        if (period[a] > 0.0) d[a] -= period[a] * std::round(d[a] / period[a]);
      }
      if (glm::dot(d, d) < r2) out[i].push_back(static_cast<std::uint32_t>(j));
    }
  }
  return out;
}

}  // namespace hemo::reference
