// Properties of the CPU reference of the neighbour grid.
#include "hemo/reference/analytic.hpp"
#include "hemo/reference/neighbours.hpp"
#include "hemo/reference/published.hpp"
#include "hemo/reference/tools.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <complex>
#include <vector>
#include <fstream>
#include <random>
#include <string>

namespace hemo::reference {
namespace {

// Womersley's mean speed against a finite-difference solution of its radial equation,
// mu (1/r) d/dr (r du/dr) - i omega rho u = -G (u(R) = 0, du/dr(0) = 0), on 2,000 cells, for
// Womersley numbers from 0.5 to 12; and its limits (Poiseuille's, in phase, as alpha -> 0).
TEST(ReferenceAnalytic, WomersleyMeanSpeedSolvesTheRadialEquation) {
  const double rho = 1060.0, mu = 0.1, R = 0.002;
  const std::complex<double> G(300.0, -120.0), i(0.0, 1.0);
  for (const double alpha : {0.5, 2.0, 3.6, 7.0, 12.0}) {
    const double omega = alpha * alpha * mu / (rho * R * R);
    const int n = 2000;
    const double h = R / n;
    // Unknowns u_0..u_{n-1} at r_k = (k + 1/2) h; u_n = 0 at the wall (a ghost at r = R + h/2: -u_{n-1}).
    std::vector<std::complex<double>> a(n), b(n), c(n), d(n, -G / mu);
    for (int k = 0; k < n; ++k) {
      const double r = (k + 0.5) * h, rm = k * h, rp = (k + 1) * h;
      a[k] = rm / (r * h * h);
      c[k] = rp / (r * h * h);
      b[k] = -(a[k] + c[k]) - i * omega * rho / mu;
    }
    b[n - 1] -= c[n - 1];  // (the ghost)
    for (int k = 1; k < n; ++k) {  // Thomas
      const std::complex<double> m = a[k] / b[k - 1];
      b[k] -= m * c[k - 1];
      d[k] -= m * d[k - 1];
    }
    std::vector<std::complex<double>> u(n);
    u[n - 1] = d[n - 1] / b[n - 1];
    for (int k = n - 2; k >= 0; --k) u[k] = (d[k] - c[k] * u[k + 1]) / b[k];
    std::complex<double> mean = 0.0;
    for (int k = 0; k < n; ++k) mean += u[k] * 2.0 * (k + 0.5) * h * h / (R * R);
    const std::complex<double> w = womersleyMeanSpeed(G, omega, rho, mu, R);
    EXPECT_LT(std::abs(w - mean), 1e-4 * std::abs(mean)) << "alpha " << alpha << ": " << w << " against " << mean;
  }
  const std::complex<double> slow = womersleyMeanSpeed(G, 1e-6, rho, mu, R);
  EXPECT_LT(std::abs(slow - G * R * R / (8.0 * mu)), 1e-6 * std::abs(slow));
}

TEST(ReferenceGrid, CellsAreXFastestAndClamped) {
  Grid g{{0, 0, 0}, 1.0, {4, 3, 2}};
  bool out = true;
  EXPECT_EQ(cellLinear(cellCoords({2.5, 1.5, 1.5}, g, &out), g), 2u + 4u * (1u + 3u * 1u));
  EXPECT_FALSE(out);
  EXPECT_EQ(cellCoords({-5, 10, 0.5}, g, &out), glm::ivec3(0, 2, 0));
  EXPECT_TRUE(out);
}

TEST(ReferenceGrid, BuildIsAStablePartitionByCell) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(0.0, 3.0);
  std::vector<glm::dvec3> p(500);
  for (auto& x : p) x = {u(rng), u(rng), u(rng)};
  Grid g{{0, 0, 0}, 1.0, {3, 3, 3}};
  const auto b = buildGrid(p, g);
  ASSERT_EQ(b.cellStart.size(), 28u);
  EXPECT_EQ(b.cellStart.back(), 500u);
  for (std::uint32_t c = 0; c < 27; ++c) {
    for (std::uint32_t s = b.cellStart[c]; s < b.cellStart[c + 1]; ++s) {
      EXPECT_EQ(b.cellOfParticle[b.order[s]], c);
      if (s > b.cellStart[c]) {
        EXPECT_LT(b.order[s - 1], b.order[s]);
      }
    }
  }
}

TEST(ReferenceNeighbours, BruteForceIsSymmetricAndExcludesSelf) {
  std::vector<glm::dvec3> p = {{0, 0, 0}, {0.5, 0, 0}, {1.2, 0, 0}, {0, 0, 0}};
  const auto nb = neighboursBruteForce(p, 1.0);
  EXPECT_EQ(nb[0], (std::vector<std::uint32_t>{1, 3}));
  EXPECT_EQ(nb[1], (std::vector<std::uint32_t>{0, 2, 3}));
  EXPECT_EQ(nb[2], (std::vector<std::uint32_t>{1}));
}

// The embedded Martin & Moyce table is the one in tests/data (no transcription slip).
TEST(Published, MartinMoyceTableMatchesTheDataFile) {
  std::ifstream in(std::string(HEMO_SOURCE_DIR) + "/tests/data/martin_moyce_n2_2.csv");
  ASSERT_TRUE(in);
  std::vector<std::pair<double, double>> rows;
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] < '0' || line[0] > '9') continue;
    const auto comma = line.find(',');
    rows.emplace_back(std::stod(line.substr(0, comma)), std::stod(line.substr(comma + 1)));
  }
  EXPECT_EQ(rows, martinMoyceN2());
  EXPECT_DOUBLE_EQ(interpolateTable(rows, 0.0), 1.0);
  EXPECT_NEAR(interpolateTable(rows, 0.205), 1.055, 1e-12);
  EXPECT_DOUBLE_EQ(interpolateTable(rows, 99.0), rows.back().second);
}

// The start-up series: zero at t = 0 and at the walls, the steady parabola F L^2 / (8 nu) at
// the centre for large t, the analytic e-folding of the slowest mode in between, symmetric.
TEST(ReferencePoiseuille, StartupSeriesHasTheRightLimits) {
  const double L = 1e-3, F = 2e-4, nu = 1e-6, peak = F * L * L / (8 * nu);
  for (double z : {0.1e-3, 0.3e-3, 0.5e-3, 0.9e-3}) {
    EXPECT_NEAR(poiseuilleStartup(z, 0.0, L, F, nu), 0.0, 1e-5 * peak) << z;
    EXPECT_NEAR(poiseuilleStartup(z, 10.0, L, F, nu), F / (2 * nu) * z * (L - z), 1e-9 * peak) << z;
    EXPECT_NEAR(poiseuilleStartup(z, 0.05, L, F, nu), poiseuilleStartup(L - z, 0.05, L, F, nu), 1e-9 * peak);
  }
  EXPECT_NEAR(poiseuilleStartup(0.0, 0.1, L, F, nu), 0.0, 1e-12);
  EXPECT_NEAR(poiseuilleStartup(L, 0.1, L, F, nu), 0.0, 1e-12);
  // Late enough for the n = 0 mode alone: deficit = 32/pi^3 peak exp(-pi^2 nu t / L^2).
  const double t = 0.3, pi = 3.14159265358979323846;
  const double deficit = peak - poiseuilleStartup(L / 2, t, L, F, nu);
  EXPECT_NEAR(deficit, 32.0 / (pi * pi * pi) * peak * std::exp(-pi * pi * nu * t / (L * L)), 1e-6 * peak);
}

}  // namespace
}  // namespace hemo::reference

// The tool pose's velocity and spin against finite differences of the pose itself: the tip's
// displacement, and the rotation q(t + d) q(t)^-1 over d, between two keys that move and turn.
TEST(ReferenceTools, PoseVelocityAndSpinAreThePoseDerivatives) {
  hemo::sim::ToolSpec tool;
  tool.name = "t";
  tool.radius = 0.001f;
  tool.keys = {{0.1, {0.01f, 0.02f, 0.03f}, glm::angleAxis(0.3f, glm::normalize(glm::vec3(1, 1, 0)))},
               {0.4, {0.02f, 0.015f, 0.01f}, glm::angleAxis(1.1f, glm::normalize(glm::vec3(0, 1, 2)))}};
  for (const double t : {0.1, 0.17, 0.25, 0.39}) {
    const double d = 1e-6;
    const auto a = hemo::reference::toolPose(tool, t), b = hemo::reference::toolPose(tool, t + d);
    const glm::dvec3 v = (b.position - a.position) / d;
    EXPECT_LT(glm::length(a.velocity - v), 1e-6 * glm::length(v)) << t;
    const glm::dquat r = b.orientation * glm::conjugate(a.orientation);
    const double sign = r.w < 0.0 ? -1.0 : 1.0;
    const glm::dvec3 spin = 2.0 * sign * glm::dvec3(r.x, r.y, r.z) / d;  // small rotation: vector part = angle/2 axis
    EXPECT_GT(glm::length(spin), 1.0) << t;
    EXPECT_LT(glm::length(a.spin - spin), 1e-5 * glm::length(spin)) << t;
  }
  // held before the first key and after the last
  EXPECT_EQ(glm::length(hemo::reference::toolPose(tool, 0.05).spin), 0.0);
  EXPECT_EQ(glm::length(hemo::reference::toolPose(tool, 0.5).velocity), 0.0);
}
