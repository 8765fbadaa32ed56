#pragma once
// Particle state on the GPU: positions (vec4: xyz in m, w free), velocities (vec4: xyz in
// m/s, w free), normals (vec4: xyz unit wall normal for boundary and wall particles, w free)
// and stable ids (uint32). `live()` always holds the data, so every descriptor set binds the
// same buffers whether or not the GPU chose to re-sort this step; `scratch()` is the copy the
// neighbour grid gathers from when it reorders the live arrays into cell order. What the w
// components mean is up to the stages that use the store (the SPH solver: w of positions =
// mass in kg, w of velocities = particle kind).
#include "hemo/gpu/buffer.hpp"

#include <glm/vec4.hpp>

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
  // Particles of each kind at the last upload (velocities.w: HEMO_KIND_FLUID, _BOUNDARY,
  // _WALL of interface/sph.h; the fluid's count includes its parked slots, HEMO_KIND_PARKED, the
  // only kind that changes during a run: to and from fluid), and how many uploads there
  // have been (a solver that relies on the grid's order checks it has sorted this upload).
  std::uint32_t fluidCount() const { return fluid_; }
  std::uint32_t wallCount() const { return wall_; }
  std::uint64_t uploads() const { return uploads_; }
  ParticleArrays& live() { return live_; }
  const ParticleArrays& live() const { return live_; }
  const ParticleArrays& scratch() const { return scratch_; }

  // Replaces the particles (set-up only). ids default to 0 .. n-1, normals to zero.
  void upload(const std::vector<glm::vec4>& positions, const std::vector<glm::vec4>& velocities,
              const std::vector<std::uint32_t>& ids = {}, const std::vector<glm::vec4>& normals = {});
  std::vector<glm::vec4> readPositions() const;
  std::vector<glm::vec4> readVelocities() const;
  std::vector<glm::vec4> readNormals() const;
  std::vector<std::uint32_t> readIds() const;
  // Its buffers, for a checkpoint (hemo/io/checkpoint.hpp): the live arrays and the scratch.
  void checkpointBuffers(std::vector<gpu::Buffer*>& out);

 private:
  std::uint32_t capacity_;
  std::uint32_t count_ = 0;
  std::uint32_t fluid_ = 0;
  std::uint32_t wall_ = 0;
  std::uint64_t uploads_ = 0;
  ParticleArrays live_;
  ParticleArrays scratch_;
};

}  // namespace hemo::sim
