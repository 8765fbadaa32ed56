#include "hemo/sim/stats.hpp"

#include "hemo/gpu/pipeline_cache.hpp"
#include "interface/stats.h"

#include <stdexcept>
#include <string>

namespace hemo::sim {

namespace {
constexpr std::uint32_t kWorkgroup = 256;
struct CountPush {
  std::uint32_t n;
};
struct LogPush {
  std::uint32_t clockIn, row;
};
std::uint64_t slots(const ParticleStore& p) { return std::max(p.capacity(), 1u); }
}  // namespace

StepStats::StepStats(gpu::Context& context, const ParticleStore& particles, const SphSolver& solver, std::uint32_t rows)
    : particles_(&particles),
      solver_(&solver),
      rows_(std::max(rows, 1u)),
      speed_(context, slots(particles) * 4, gpu::MemoryUse::Device, "stats speed"),
      densityError_(context, slots(particles) * 4, gpu::MemoryUse::Device, "stats density error"),
      zeros_(context, 16, gpu::MemoryUse::Device, "stats no-wall counters"),
      log_(context, std::uint64_t(rows_) * sizeof(StepStatsRow), gpu::MemoryUse::Device, "stats log"),
      speedMax_(context, speed_, slots(particles)),
      errorMax_(context, densityError_, slots(particles)) {
  zeros_.upload(std::vector<std::uint32_t>(4, 0u));
  auto& cache = context.pipelines();
  particleStats_ = &cache.get({"stats/particle_stats", HEMO_PSTATS_BINDING_COUNT, sizeof(CountPush), kWorkgroup, {}, 1u << HEMO_PSTATS_BINDING_PARAMS});
  logRow_ = &cache.get({"stats/log_row", HEMO_STATSLOG_BINDING_COUNT, sizeof(LogPush), 64, {}});
  particleSet_ = particleStats_->makeSet({{HEMO_PSTATS_BINDING_VELOCITIES, &particles.live().velocities},
                                          {HEMO_PSTATS_BINDING_STATE, &solver.state()},
                                          {HEMO_PSTATS_BINDING_PARAMS, &solver.paramsBuffer()},
                                          {HEMO_PSTATS_BINDING_SPEED, &speed_},
                                          {HEMO_PSTATS_BINDING_DENSITY_ERROR, &densityError_}});
  const gpu::Buffer& wall = solver.wall() ? solver.wall()->counters() : zeros_;
  logSet_ = logRow_->makeSet({{HEMO_STATSLOG_BINDING_CLOCK, &solver.clockBuffer()},
                              {HEMO_STATSLOG_BINDING_SPEED, &speedMax_.result()},
                              {HEMO_STATSLOG_BINDING_DENSITY_ERROR, &errorMax_.result()},
                              {HEMO_STATSLOG_BINDING_WALL, &wall},
                              {HEMO_STATSLOG_BINDING_LOG, &log_}});
}

void StepStats::record(gpu::CommandRecorder& rec, std::uint32_t row) {
  if (row >= rows_) throw std::out_of_range("stats row " + std::to_string(row) + " exceeds " + std::to_string(rows_));
  const std::uint32_t n = particles_->count();
  rec.dispatch(*particleStats_, particleSet_, CountPush{n}, particleStats_->groupsFor(std::max(n, 1u)));
  rec.computeToCompute();
  speedMax_.record(rec, n);
  errorMax_.record(rec, n);
  rec.dispatch(*logRow_, logSet_, LogPush{solver_->clockParity(), row}, logRow_->groupsFor(1));
  rec.computeToCompute();
}

std::vector<StepStatsRow> StepStats::read(std::uint32_t rows) const {
  return log_.readback<StepStatsRow>(std::min(rows, rows_));
}

}  // namespace hemo::sim
