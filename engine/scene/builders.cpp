#include "hemo/scene/builders.hpp"

#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>

namespace hemo::scene {

namespace {

glm::ivec3 cellsAlong(const Box& b, float dp) {
  glm::ivec3 n;
  for (int a = 0; a < 3; ++a) n[a] = std::max(1, int(std::lround((b.max[a] - b.min[a]) / dp)));
  return n;
}

// Calls f(lattice point, normal) for every boundary particle of the tank.
template <class F>
void forEachTankParticle(const Tank& t, float dp, F&& f) {
  const glm::ivec3 n = cellsAlong(t.box, dp);
  const int L = int(t.layers);
  const int zTop = t.openTop ? n.z : n.z + L;
  for (int k = -L; k < zTop; ++k)
    for (int j = -L; j < n.y + L; ++j)
      for (int i = -L; i < n.x + L; ++i) {
        const bool inside = i >= 0 && i < n.x && j >= 0 && j < n.y && k >= 0 && k < n.z;
        if (inside) continue;
        const glm::vec3 p = t.box.min + (glm::vec3(i, j, k) + 0.5f) * dp;
        const glm::vec3 q = glm::clamp(p, t.box.min, t.box.max);
        f(p, glm::normalize(q - p));
      }
}

}  // namespace

std::uint64_t countParticles(const Scene& s) {
  std::uint64_t count = 0;
  for (const auto& b : s.blocks) {
    const glm::ivec3 n = cellsAlong(b.box, s.sph.spacing);
    count += std::uint64_t(n.x) * n.y * n.z;
  }
  for (const auto& t : s.tanks) {
    const glm::ivec3 n = cellsAlong(t.box, s.sph.spacing);
    const std::uint64_t L = t.layers;
    const std::uint64_t outer = (n.x + 2 * L) * (n.y + 2 * L) * (n.z + (t.openTop ? L : 2 * L));
    count += outer - std::uint64_t(n.x) * n.y * n.z;
  }
  return count;
}

ParticleSet buildParticles(const Scene& s) {
  ParticleSet set;
  const float dp = s.sph.spacing;
  const float mass = s.sph.particleMass();
  for (const auto& b : s.blocks) {
    const glm::ivec3 n = cellsAlong(b.box, dp);
    for (int k = 0; k < n.z; ++k)
      for (int j = 0; j < n.y; ++j)
        for (int i = 0; i < n.x; ++i) {
          set.positions.emplace_back(b.box.min + (glm::vec3(i, j, k) + 0.5f) * dp, mass);
          set.velocities.emplace_back(b.velocity, float(sim::ParticleKind::Fluid));
          set.normals.emplace_back(0.0f);
        }
  }
  set.fluid = set.size();
  for (const auto& t : s.tanks) {
    forEachTankParticle(t, dp, [&](const glm::vec3& p, const glm::vec3& normal) {
      set.positions.emplace_back(p, mass);
      set.velocities.emplace_back(0.0f, 0.0f, 0.0f, float(sim::ParticleKind::Boundary));
      set.normals.emplace_back(normal, 0.0f);
    });
  }
  set.boundary = set.size() - set.fluid;
  set.ids.resize(set.size());
  for (std::uint32_t i = 0; i < set.size(); ++i) set.ids[i] = i;
  return set;
}

}  // namespace hemo::scene
