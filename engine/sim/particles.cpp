#include "hemo/sim/particles.hpp"

#include "interface/sph.h"

#include <numeric>
#include <stdexcept>
#include <string>

namespace hemo::sim {

ParticleStore::ParticleStore(gpu::Context& context, std::uint32_t capacity) : capacity_(capacity) {
  const VkDeviceSize n = std::max<VkDeviceSize>(capacity, 1);
  for (ParticleArrays* a : {&live_, &scratch_}) {
    const std::string tag = a == &live_ ? "" : " (scratch)";
    a->positions = gpu::Buffer(context, n * 16, gpu::MemoryUse::Device, "positions" + tag);
    a->velocities = gpu::Buffer(context, n * 16, gpu::MemoryUse::Device, "velocities" + tag);
    a->normals = gpu::Buffer(context, n * 16, gpu::MemoryUse::Device, "normals" + tag);
    a->ids = gpu::Buffer(context, n * 4, gpu::MemoryUse::Device, "ids" + tag);
  }
}

void ParticleStore::checkpointBuffers(std::vector<gpu::Buffer*>& out) {
  for (ParticleArrays* a : {&live_, &scratch_}) {
    for (gpu::Buffer* b : {&a->positions, &a->velocities, &a->normals, &a->ids}) out.push_back(b);
  }
}

void ParticleStore::upload(const std::vector<glm::vec4>& positions, const std::vector<glm::vec4>& velocities,
                           const std::vector<std::uint32_t>& ids, const std::vector<glm::vec4>& normals) {
  if (positions.size() > capacity_) {
    throw std::invalid_argument(std::to_string(positions.size()) + " particles exceed the store's capacity of " +
                                std::to_string(capacity_));
  }
  if (velocities.size() != positions.size() || (!ids.empty() && ids.size() != positions.size()) ||
      (!normals.empty() && normals.size() != positions.size())) {
    throw std::invalid_argument("particle upload: positions, velocities, normals and ids differ in length");
  }
  std::vector<std::uint32_t> idList = ids;
  if (idList.empty()) {
    idList.resize(positions.size());
    std::iota(idList.begin(), idList.end(), 0u);
  }
  count_ = static_cast<std::uint32_t>(positions.size());
  fluid_ = 0;
  wall_ = 0;
  for (const glm::vec4& v : velocities) {
    // (parked fluid slots, of open vessel ends, belong to the fluid's part)
    fluid_ += std::uint32_t(v.w) == HEMO_KIND_FLUID || std::uint32_t(v.w) == HEMO_KIND_PARKED ? 1u : 0u;
    wall_ += std::uint32_t(v.w) == HEMO_KIND_WALL ? 1u : 0u;
  }
  ++uploads_;
  live_.positions.upload(positions);
  live_.velocities.upload(velocities);
  live_.ids.upload(idList);
  live_.normals.upload(normals.empty() ? std::vector<glm::vec4>(positions.size(), glm::vec4(0.0f)) : normals);
}

std::vector<glm::vec4> ParticleStore::readPositions() const {
  return live_.positions.readback<glm::vec4>(count_);
}
std::vector<glm::vec4> ParticleStore::readVelocities() const {
  return live_.velocities.readback<glm::vec4>(count_);
}
std::vector<glm::vec4> ParticleStore::readNormals() const {
  return live_.normals.readback<glm::vec4>(count_);
}
std::vector<std::uint32_t> ParticleStore::readIds() const { return live_.ids.readback<std::uint32_t>(count_); }

}  // namespace hemo::sim
