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

std::complex<double> womersleyMeanSpeed(std::complex<double> G1, double omega, double rho, double mu, double R) {
  const double alpha = R * std::sqrt(omega * rho / mu);
  const std::complex<double> i(0.0, 1.0);
  const std::complex<double> L = std::pow(i, 1.5) * alpha;
  // J0 and J1 from their power series: sum_k (-L^2/4)^k / (k! k!) and (L/2) sum_k (-L^2/4)^k / (k! (k+1)!)
  // (converge for every L; 80 terms cover |L| up to about 15, alpha up to 15).
  const std::complex<double> q = -L * L / 4.0;
  std::complex<double> term0 = 1.0, term1 = 1.0, j0 = 1.0, j1 = 1.0;
  for (int k = 1; k < 80; ++k) {
    term0 *= q / (double(k) * double(k));
    term1 *= q / (double(k) * double(k + 1));
    j0 += term0;
    j1 += term1;
  }
  j1 *= L / 2.0;
  if (alpha < 1e-3) return G1 * R * R / (8.0 * mu);  // (the series' difference loses its digits)
  return G1 / (i * omega * rho) * (1.0 - 2.0 * j1 / (L * j0));
}

}  // namespace hemo::reference
