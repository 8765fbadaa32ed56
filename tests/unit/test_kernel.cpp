// Mathematical properties of the SPH kernel (reference implementation, double precision).
#include "hemo/reference/sph.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <utility>

namespace hemo::reference {
namespace {

TEST(Kernel, IntegratesToOne) {
  // Radial quadrature: 4 pi int_0^{2h} W(r) r^2 dr = 1.
  for (double h : {0.001, 0.013, 1.0}) {
    const int steps = 200000;
    const double dr = 2.0 * h / steps;
    double sum = 0.0;
    for (int k = 0; k < steps; ++k) {
      const double r = (k + 0.5) * dr;
      sum += kernelW(r, h) * r * r * dr;
    }
    EXPECT_NEAR(4.0 * std::numbers::pi * sum, 1.0, 1e-8) << "h = " << h;
  }
}

TEST(Kernel, CompactSupportAndSmoothEdge) {
  const double h = 0.01;
  EXPECT_EQ(kernelW(2.0 * h, h), 0.0);
  EXPECT_EQ(kernelW(3.0 * h, h), 0.0);
  EXPECT_NEAR(kernelW(2.0 * h * (1 - 1e-9), h), 0.0, 1e-20);
  EXPECT_GT(kernelW(0.0, h), kernelW(0.5 * h, h));
  EXPECT_EQ(kernelDwdr(0.0, h), 0.0);
}

TEST(Kernel, DerivativeMatchesFiniteDifferences) {
  const double h = 0.02;
  for (double q = 0.05; q < 1.99; q += 0.07) {
    const double r = q * h, e = 1e-7 * h;
    const double fd = (kernelW(r + e, h) - kernelW(r - e, h)) / (2 * e);
    EXPECT_NEAR(kernelDwdr(r, h), fd, 1e-6 * std::abs(fd) + 1e-3) << "q = " << q;
  }
}

// Partition of unity on a lattice: sum_j W(x_i - x_j) dp^3 ~ 1 and the gradient sum ~ 0.
TEST(Kernel, LatticeSumsArePartitionOfUnity) {
  const double dp = 0.01;
  // (h/dp, bound on |sum gradW dp^3| h): the error of the discrete gradient falls with h/dp.
  // Measured: 0.054, 0.031, 0.011, 0.0027; the sums of W are within 0.32% of 1.
  const std::pair<double, double> cases[] = {{1.2, 0.06}, {1.3, 0.035}, {1.5, 0.015}, {2.0, 0.004}};
  for (const auto& [ratio, gradBound] : cases) {
    const double h = ratio * dp;
    double sum = 0.0;
    glm::dvec3 grad(0.0);
    const glm::dvec3 xi(0.3 * dp, 0.1 * dp, -0.2 * dp);  // off-lattice point
    for (int a = -6; a <= 6; ++a)
      for (int b = -6; b <= 6; ++b)
        for (int c = -6; c <= 6; ++c) {
          const glm::dvec3 xj(a * dp, b * dp, c * dp);
          const glm::dvec3 d = xi - xj;
          const double r = std::sqrt(d.x * d.x + d.y * d.y + d.z * d.z);
          sum += kernelW(r, h) * dp * dp * dp;
          if (r > 0) grad += d * (kernelDwdr(r, h) / r) * dp * dp * dp;
        }
    EXPECT_NEAR(sum, 1.0, 0.005) << "h/dp = " << ratio;
    EXPECT_LT(std::sqrt(grad.x * grad.x + grad.y * grad.y + grad.z * grad.z) * h, gradBound) << "h/dp = " << ratio;
  }
}

TEST(Kernel, GradientIsAntisymmetric) {
  const double h = 0.013;
  const glm::dvec3 xi(0.001, 0.002, -0.003), xj(-0.004, 0.005, 0.0);
  const glm::dvec3 dij = xi - xj, dji = xj - xi;
  const double r = std::sqrt(dij.x * dij.x + dij.y * dij.y + dij.z * dij.z);
  const glm::dvec3 gij = dij * (kernelDwdr(r, h) / r), gji = dji * (kernelDwdr(r, h) / r);
  EXPECT_DOUBLE_EQ(gij.x, -gji.x);
  EXPECT_DOUBLE_EQ(gij.y, -gji.y);
  EXPECT_DOUBLE_EQ(gij.z, -gji.z);
}

}  // namespace
}  // namespace hemo::reference
