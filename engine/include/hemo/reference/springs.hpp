#pragma once
// CPU double-precision twin of the wall stage (wall/spring_forces.comp: rupture, spring forces).
#include <glm/vec3.hpp>

#include <cstdint>
#include <vector>

namespace hemo::reference {

struct RefSpring {
  std::uint32_t a = 0, b = 0;  // particle ids
  double restLength = 0.0, stiffness = 0.0, damping = 0.0, maxForce = 0.0;
  bool broken = false;
};

// Tension of a spring (positive when stretched) and the force on end a (the force on b is
// its negative), from positions and velocities indexed by particle id; on axes with a
// non-zero `period` the spring spans the minimum image.
double springTension(const RefSpring& s, const std::vector<glm::dvec3>& x, const std::vector<glm::dvec3>& v,
                     glm::dvec3* forceOnA = nullptr, const glm::dvec3& period = glm::dvec3(0.0));

// Flags (for good) the springs whose tension exceeds their maximum force; returns how many
// broke now.
std::uint32_t rupture(std::vector<RefSpring>& springs, const std::vector<glm::dvec3>& x, const std::vector<glm::dvec3>& v,
                      const glm::dvec3& period = glm::dvec3(0.0));

// Acceleration of each point (by id): unbroken spring forces / mass + gravity; zero when
// anchored.
std::vector<glm::dvec3> springAccelerations(const std::vector<RefSpring>& springs, const std::vector<glm::dvec3>& x,
                                            const std::vector<glm::dvec3>& v, const std::vector<double>& mass,
                                            const std::vector<bool>& anchored, const glm::dvec3& gravity,
                                            const glm::dvec3& period = glm::dvec3(0.0));

}  // namespace hemo::reference
