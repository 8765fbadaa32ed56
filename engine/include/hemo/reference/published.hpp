#pragma once
// Published experimental data used for validation (facts, cited; the numbers are the
// measurements as digitised in tests/data/).
#include <utility>
#include <vector>

namespace hemo::reference {

// Martin & Moyce (1952), collapse of a liquid column of width a and height 2a (n^2 = 2):
// surge front Z = x / a against T = t sqrt(2 g / a). Source: J. C. Martin, W. J. Moyce,
// Phil. Trans. R. Soc. A 244 (1952); tests/data/martin_moyce_n2_2.csv.
const std::vector<std::pair<double, double>>& martinMoyceN2();

// Linear interpolation in a (T, Z) table, clamped at its ends.
double interpolateTable(const std::vector<std::pair<double, double>>& table, double t);

}  // namespace hemo::reference
