#include "hemo/reference/published.hpp"

namespace hemo::reference {

const std::vector<std::pair<double, double>>& martinMoyceN2() {
  static const std::vector<std::pair<double, double>> table = {
      {0.00, 1.00},
      {0.41, 1.11},
      {0.84, 1.22},
      {1.19, 1.44},
      {1.43, 1.67},
      {1.63, 1.89},
      {1.83, 2.11},
      {1.98, 2.33},
      {2.20, 2.56},
      {2.32, 2.78},
      {2.51, 3.00},
      {2.65, 3.22},
      {2.83, 3.44},
      {2.98, 3.67},
      {3.11, 3.89},
      {3.33, 4.11}};
  return table;
}

double interpolateTable(const std::vector<std::pair<double, double>>& table, double t) {
  if (table.empty()) return 0.0;
  if (t <= table.front().first) return table.front().second;
  for (std::size_t k = 1; k < table.size(); ++k) {
    if (t <= table[k].first) {
      const auto [t0, z0] = table[k - 1];
      const auto [t1, z1] = table[k];
      return z0 + (z1 - z0) * (t - t0) / (t1 - t0);
    }
  }
  return table.back().second;
}

}  // namespace hemo::reference
