#pragma once
// Particle state on the GPU, double-buffered so the neighbour grid can gather it into cell
// order each step: positions (vec4: xyz in m relative to the domain origin, w free),
// velocities (vec4: xyz in m/s, w free), normals (vec4: xyz unit wall normal for boundary
// and wall particles, w free) and stable ids (uint32). `current()` holds the live data; the
// grid's reorder writes the other half and flips. What the w components mean is up to the
// stages that use the store (the SPH solver: w of positions = mass in kg, w of velocities =
// particle kind).
#include "hemo/gpu/buffer.hpp"

#include <glm/vec4.hpp>

#include <array>
#include <cstdint>
#include <vector>

namespace hemo::sim {

struct ParticleArrays {
  gpu::Buffer positions;
  gpu::Buffer velocities;
  gpu::Buffer normals;
  gpu::Buffer ids;
};

class ParticleStore {
 public:
  ParticleStore(gpu::Context& context, std::uint32_t capacity);

  std::uint32_t capacity() const { return capacity_; }
  std::uint32_t count() const { return count_; }
  // Index (0 or 1) of the half that holds the live data.
  int parity() const { return parity_; }
  ParticleArrays& half(int which) { return halves_[which]; }
  const ParticleArrays& half(int which) const { return halves_[which]; }
  const ParticleArrays& current() const { return halves_[parity_]; }
  void flip() { parity_ ^= 1; }

  // Replaces the particles (set-up only). ids default to 0 .. n-1, normals to zero.
  void upload(const std::vector<glm::vec4>& positions, const std::vector<glm::vec4>& velocities,
              const std::vector<std::uint32_t>& ids = {}, const std::vector<glm::vec4>& normals = {});
  std::vector<glm::vec4> readPositions() const;
  std::vector<glm::vec4> readVelocities() const;
  std::vector<glm::vec4> readNormals() const;
  std::vector<std::uint32_t> readIds() const;

 private:
  std::uint32_t capacity_;
  std::uint32_t count_ = 0;
  int parity_ = 0;
  std::array<ParticleArrays, 2> halves_;
};

}  // namespace hemo::sim
