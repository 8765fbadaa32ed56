#include "hemo/scene/statics.hpp"

#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <stdexcept>
#include <string>

namespace hemo::scene {

StaticResponse staticResponse(const sim::SpringNetwork& net, const std::vector<glm::vec4>& positions, double period,
                              const std::vector<glm::dvec3>& loads) {
  const std::size_t n = net.points.size();
  if (positions.size() < n || loads.size() < n) throw std::invalid_argument("statics: fewer positions or loads than wall points");
  // Unit directions from a to b (nearest periodic image along x).
  std::vector<glm::dvec3> dir(net.springs.size());
  double kMax = 0.0;
  for (std::size_t s = 0; s < net.springs.size(); ++s) {
    glm::dvec3 d = glm::dvec3(positions[net.springs[s].b]) - glm::dvec3(positions[net.springs[s].a]);
    if (period > 0.0) d.x -= period * std::round(d.x / period);
    dir[s] = glm::normalize(d);
    kMax = std::max(kMax, double(net.springs[s].stiffness));
  }
  if (!(kMax > 0.0)) throw std::invalid_argument("statics: the network has no stiff spring");
  const double shift = 1e-10 * kMax;  // removes the rigid motions (unloaded) without biasing the answer
  auto fixed = [&](std::size_t i) { return net.points[i].anchored; };
  auto apply = [&](const std::vector<glm::dvec3>& u, std::vector<glm::dvec3>& y) {
    for (std::size_t i = 0; i < n; ++i) y[i] = fixed(i) ? u[i] : shift * u[i];
    for (std::size_t s = 0; s < net.springs.size(); ++s) {
      const sim::Spring& sp = net.springs[s];
      const double t = sp.stiffness * glm::dot(dir[s], u[sp.b] - u[sp.a]);
      if (!fixed(sp.a)) y[sp.a] -= t * dir[s];
      if (!fixed(sp.b)) y[sp.b] += t * dir[s];
    }
  };
  // Conjugate gradients on K u = f (K symmetric positive definite with the shift; anchored
  // points' rows are the identity with a zero load).
  std::vector<glm::dvec3> u(n, glm::dvec3(0.0)), r(n), p(n), q(n);
  double fNorm2 = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    r[i] = fixed(i) ? glm::dvec3(0.0) : loads[i];
    fNorm2 += glm::dot(r[i], r[i]);
  }
  if (!(fNorm2 > 0.0)) throw std::invalid_argument("statics: no load");
  p = r;
  double rr = fNorm2;
  StaticResponse out;
  const std::uint32_t maxIterations = static_cast<std::uint32_t>(std::max<std::size_t>(2000, 20 * n));
  for (out.iterations = 0; out.iterations < maxIterations && rr > 1e-24 * fNorm2; ++out.iterations) {
    apply(p, q);
    double pq = 0.0;
    for (std::size_t i = 0; i < n; ++i) pq += glm::dot(p[i], q[i]);
    const double alpha = rr / pq;
    double next = 0.0;
    for (std::size_t i = 0; i < n; ++i) {
      u[i] += alpha * p[i];
      r[i] -= alpha * q[i];
      next += glm::dot(r[i], r[i]);
    }
    for (std::size_t i = 0; i < n; ++i) p[i] = r[i] + (next / rr) * p[i];
    rr = next;
  }
  out.residual = std::sqrt(rr / fNorm2);
  if (!(out.residual < 1e-6)) {
    throw std::invalid_argument("statics: the network's equilibrium did not converge (relative residual " + std::to_string(out.residual) +
                                " after " + std::to_string(out.iterations) + " iterations): it may have a mechanism");
  }
  out.tension.resize(net.springs.size());
  out.rupturePressure = std::numeric_limits<double>::infinity();
  for (std::size_t s = 0; s < net.springs.size(); ++s) {
    const sim::Spring& sp = net.springs[s];
    out.tension[s] = sp.stiffness * glm::dot(dir[s], u[sp.b] - u[sp.a]);
    if (out.tension[s] > 0.0 && sp.maxForce / out.tension[s] < out.rupturePressure) {
      out.rupturePressure = sp.maxForce / out.tension[s];
      out.firstSpring = static_cast<std::uint32_t>(s);
    }
  }
  if (!std::isfinite(out.rupturePressure)) throw std::invalid_argument("statics: no spring stretches under the lumen pressure");
  return out;
}

std::vector<glm::dvec3> lumenLoads(const AneurysmSpec& a, const std::vector<glm::vec4>& positions, const std::vector<glm::vec4>& inward,
                                   std::uint32_t wall) {
  if (a.sacRadius > 0.0f || a.branchLength > 0.0f) {
    throw std::invalid_argument("statics: lumen loads are for surfaces of revolution (a tube or a fusiform aneurysm)");
  }
  const TubeSpec& t = a.tube;
  const double dp = t.spacing, x0 = t.x0, L = t.length;
  auto slope = [&](double x) { return (innerRadiusAt(a, x + 1e-4 * dp) - innerRadiusAt(a, x - 1e-4 * dp)) / (2e-4 * dp); };
  // Lumen area between two axial positions (midpoint rule).
  auto area = [&](double xa, double xb) {
    const int steps = std::max(8, int(std::ceil((xb - xa) / (0.01 * dp))));
    double sum = 0.0;
    for (int k = 0; k < steps; ++k) {
      const double x = xa + (xb - xa) * (k + 0.5) / steps, s = slope(x);
      sum += 2.0 * std::numbers::pi * innerRadiusAt(a, x) * std::sqrt(1.0 + s * s) * (xb - xa) / steps;
    }
    return sum;
  };
  // Inner-layer points grouped into rings by their axial position.
  std::vector<std::pair<double, std::uint32_t>> inner;
  for (std::uint32_t i = 0; i < wall; ++i) {
    const glm::dvec3 p(positions[i]);
    const double r = std::hypot(p.y - t.centreYZ.x, p.z - t.centreYZ.y);
    if (std::abs(r - innerRadiusAt(a, p.x) - 0.5 * dp) < 0.25 * dp) inner.emplace_back(p.x, i);
  }
  std::sort(inner.begin(), inner.end());
  std::vector<double> ringX;
  std::vector<std::vector<std::uint32_t>> rings;
  for (const auto& [x, i] : inner) {
    if (ringX.empty() || x - ringX.back() > 1e-3 * dp) ringX.push_back(x), rings.emplace_back();
    rings.back().push_back(i);
  }
  if (rings.size() < 2) throw std::invalid_argument("statics: the vessel has fewer than two rings");
  std::vector<glm::dvec3> loads(wall, glm::dvec3(0.0));
  const std::size_t m = rings.size();
  for (std::size_t k = 0; k < m; ++k) {
    double lo, hi;
    if (t.periodic) {
      lo = 0.5 * (ringX[k] + (k > 0 ? ringX[k - 1] : ringX[m - 1] - L));
      hi = 0.5 * (ringX[k] + (k + 1 < m ? ringX[k + 1] : ringX[0] + L));
    } else {
      lo = k > 0 ? 0.5 * (ringX[k] + ringX[k - 1]) : x0;
      hi = k + 1 < m ? 0.5 * (ringX[k] + ringX[k + 1]) : x0 + L;
    }
    const double share = area(lo, hi) / double(rings[k].size());
    for (std::uint32_t i : rings[k]) loads[i] = -share * glm::normalize(glm::dvec3(inward[i]));
  }
  return loads;
}

}  // namespace hemo::scene
