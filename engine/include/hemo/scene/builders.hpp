#pragma once
// Geometry builders: turn a Scene into particles on the dp lattice.
#include "hemo/scene/scene.hpp"

#include <glm/vec4.hpp>

#include <cstdint>
#include <vector>

namespace hemo::scene {

// Particle arrays in the layout of sim::ParticleStore and the SPH solver:
// positions (xyz m, w mass kg), velocities (xyz m/s, w kind), normals (xyz, boundary only).
struct ParticleSet {
  std::vector<glm::vec4> positions;
  std::vector<glm::vec4> velocities;
  std::vector<glm::vec4> normals;
  std::vector<std::uint32_t> ids;
  std::uint32_t fluid = 0;
  std::uint32_t boundary = 0;
  std::uint32_t parked = 0;  // free fluid slots of open vessel ends (HEMO_KIND_PARKED), last
  std::uint32_t size() const { return static_cast<std::uint32_t>(positions.size()); }
  // Appends a particle at rest.
  void add(glm::vec3 position, float mass, float kind, glm::vec3 normal = glm::vec3(0.0f)) {
    positions.emplace_back(position, mass);
    velocities.emplace_back(0.0f, 0.0f, 0.0f, kind);
    normals.emplace_back(normal, 0.0f);
  }
  // ids = input order.
  void numberIds() {
    ids.resize(size());
    for (std::uint32_t i = 0; i < size(); ++i) ids[i] = i;
  }
};

// Particle count the scene will produce, without building (for memory checks).
std::uint64_t countParticles(const Scene& scene);
ParticleSet buildParticles(const Scene& scene);

// For quasi-2D slab scenes (periodic along `axis`, every fluid block and tank spanning the
// domain there): a copy with the slab `spacings` particle spacings thick. Used when a scene
// is run at another resolution, since a periodic slab must stay a whole number of spacings
// and at least 2.5 neighbour-list radii thick. Throws SceneError otherwise.
Scene withSlabThickness(Scene scene, int axis, int spacings);

}  // namespace hemo::scene
