#pragma once
// Per-step statistics recorded on the GPU inside the batch (no host wait): after a step, the
// largest fluid speed, the largest fluid density error |rho / rho0 - 1| (of the step's last
// density pass), the clock and the wall's broken-spring and detached-particle counters go into
// one row of a log that the host reads once per batch. Costs one pass over the particles and
// two max reductions per logged step; scenes that do not ask for it pay nothing.
#include "hemo/gpu/primitives.hpp"
#include "hemo/sim/sph.hpp"

#include <cstdint>
#include <vector>

namespace hemo::sim {

struct StepStatsRow {
  float time;             // s, after the step
  float dt;               // s
  float maxSpeed;         // m/s, fluid
  float maxDensityError;  // |rho / rho0 - 1|, fluid
  std::uint32_t brokenSprings;
  std::uint32_t detachedParticles;
  std::uint32_t steps;    // the clock's step count after the step
  std::uint32_t reserved;
};
static_assert(sizeof(StepStatsRow) == 32);

class StepStats {
 public:
  StepStats(gpu::Context& context, const ParticleStore& particles, const SphSolver& solver, std::uint32_t rows);
  // Records the statistics of the step just recorded into row `row` (< rows).
  void record(gpu::CommandRecorder& rec, std::uint32_t row);
  std::vector<StepStatsRow> read(std::uint32_t rows) const;  // a readback

 private:
  const ParticleStore* particles_;
  const SphSolver* solver_;
  std::uint32_t rows_;
  gpu::Buffer speed_, densityError_, zeros_, log_;
  gpu::MinMaxReduce speedMax_, errorMax_;
  const gpu::ComputePipeline* particleStats_;
  const gpu::ComputePipeline* logRow_;
  gpu::DescriptorSet particleSet_, logSet_;
};

}  // namespace hemo::sim
