#include "hemo/reference/analytic.hpp"

#include <cmath>
#include <numbers>

namespace hemo::reference {

double poiseuilleStartup(double z, double t, double L, double F, double nu, std::uint32_t terms) {
  const double pi = std::numbers::pi;
  double v = F / (2.0 * nu) * z * (L - z);
  for (std::uint32_t n = 0; n < terms; ++n) {
    const double k = 2.0 * n + 1.0;
    v -= 4.0 * F * L * L / (nu * pi * pi * pi * k * k * k) * std::sin(k * pi * z / L) *
         std::exp(-k * k * pi * pi * nu * t / (L * L));
  }
  return v;
}

}  // namespace hemo::reference
