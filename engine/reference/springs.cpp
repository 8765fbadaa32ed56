#include "hemo/reference/springs.hpp"

#include <glm/geometric.hpp>

#include <cmath>

namespace hemo::reference {

double springTension(const RefSpring& s, const std::vector<glm::dvec3>& x, const std::vector<glm::dvec3>& v,
                     glm::dvec3* forceOnA, const glm::dvec3& period) {
  glm::dvec3 delta = x[s.b] - x[s.a];
  for (int c = 0; c < 3; ++c) {
    if (period[c] > 0.0) delta[c] -= period[c] * std::round(delta[c] / period[c]);
  }
  const double len = glm::length(delta);
  if (len <= 0.0) {
    if (forceOnA) *forceOnA = glm::dvec3(0.0);
    return 0.0;
  }
  const glm::dvec3 d = delta / len;
  const double tension = s.stiffness * (len - s.restLength) + s.damping * glm::dot(v[s.b] - v[s.a], d);
  if (forceOnA) *forceOnA = tension * d;
  return tension;
}

std::uint32_t rupture(std::vector<RefSpring>& springs, const std::vector<glm::dvec3>& x, const std::vector<glm::dvec3>& v,
                      const glm::dvec3& period) {
  std::uint32_t broke = 0;
  for (RefSpring& s : springs) {
    if (!s.broken && springTension(s, x, v, nullptr, period) > s.maxForce) {
      s.broken = true;
      ++broke;
    }
  }
  return broke;
}

std::vector<glm::dvec3> springAccelerations(const std::vector<RefSpring>& springs, const std::vector<glm::dvec3>& x,
                                            const std::vector<glm::dvec3>& v, const std::vector<double>& mass,
                                            const std::vector<bool>& anchored, const glm::dvec3& gravity,
                                            const glm::dvec3& period) {
  std::vector<glm::dvec3> force(mass.size(), glm::dvec3(0.0));
  for (const RefSpring& s : springs) {
    if (s.broken) continue;
    glm::dvec3 fa;
    springTension(s, x, v, &fa, period);
    force[s.a] += fa;
    force[s.b] -= fa;
  }
  std::vector<glm::dvec3> a(mass.size());
  for (std::size_t i = 0; i < mass.size(); ++i) a[i] = anchored[i] ? glm::dvec3(0.0) : force[i] / mass[i] + gravity;
  return a;
}

}  // namespace hemo::reference
