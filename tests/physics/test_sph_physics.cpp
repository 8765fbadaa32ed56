// SPH physics: momentum conservation, determinism, end time. (Hydrostatic, Poiseuille and
// dam-break validation are in progress: see docs/physics.md.)
#include "gpu_test.hpp"
#include "hemo/scene/scene.hpp"
#include "hemo/sim/simulation.hpp"

#include <glm/geometric.hpp>

#include <cmath>
#include <cstring>
#include <limits>

namespace hemo::test {
namespace {

class SphPhysicsTest : public GpuTest {};

// A small column of fluid falling into place in a tank.
const char* kColumn = R"({
  "scene": "column_test",
  "particles": { "spacing_m": 0.01 },
  "fluid": { "density_kg_m3": 1000, "viscosity_pa_s": 0.5, "expected_max_speed_m_s": 1.4,
             "blocks": [ { "min_m": [0, 0, 0], "max_m": [0.05, 0.05, 0.08] } ] },
  "boundary": { "tanks": [ { "min_m": [0, 0, 0], "max_m": [0.05, 0.05, 0.1], "layers": 3 } ] },
  "time": { "max_dt_s": 0.001, "steps_per_batch": 128 },
  "domain": { "min_m": [-0.04, -0.04, -0.04], "max_m": [0.09, 0.09, 0.15] }
})";

// A blob with no gravity and no walls keeps its total momentum.
const char* kBlob = R"({
  "scene": "momentum_test",
  "particles": { "spacing_m": 0.01 },
  "fluid": { "density_kg_m3": 1000, "viscosity_pa_s": 0.01, "expected_max_speed_m_s": 2,
             "clamp_negative_pressure": false,
             "blocks": [ { "min_m": [0, 0, 0], "max_m": [0.1, 0.08, 0.06], "velocity_m_s": [0.3, -0.2, 0.1] } ] },
  "forces": { "gravity_m_s2": [0, 0, 0] },
  "time": { "steps_per_batch": 100 },
  "domain": { "min_m": [-0.2, -0.2, -0.2], "max_m": [0.4, 0.3, 0.3] }
})";

glm::dvec3 momentum(const sim::Snapshot& s, std::uint32_t fluid) {
  glm::dvec3 p(0.0);
  for (std::uint32_t i = 0; i < fluid; ++i) p += double(s.positions[i].w) * glm::dvec3(s.velocities[i]);
  return p;
}

TEST_F(SphPhysicsTest, FreeBlobConservesMomentum) {
  scene::Scene scene = scene::parseScene(kBlob, "momentum_test");
  sim::Simulation sim(ctx(), scene);
  // Stir it: give every particle a different velocity so internal forces are far from zero.
  {
    auto vel = sim.store().readVelocities();
    const auto ids = sim.store().readIds();
    for (std::size_t i = 0; i < vel.size(); ++i) {
      const float s = float(ids[i] % 7) - 3.0f, t = float(ids[i] % 5) - 2.0f;
      vel[i] += glm::vec4(0.1f * s, 0.1f * t, -0.05f * s * t, 0.0f);
    }
    sim.store().half(sim.store().parity()).velocities.upload(vel);
  }
  const sim::Snapshot start = sim.snapshot();
  const glm::dvec3 p0 = momentum(start, sim.fluidParticles());
  sim::RunOptions run;
  run.steps = 1000;
  sim.run(run);
  const sim::Snapshot s = sim.snapshot();
  const glm::dvec3 p1 = momentum(s, sim.fluidParticles());
  const double rel = glm::length(p1 - p0) / glm::length(p0);
  EXPECT_LT(rel, 1e-5) << "momentum drift " << rel;
  // ... while the internal forces were far from trivial: the velocities changed a lot.
  double change = 0.0, scale = 0.0;
  for (std::uint32_t i = 0; i < sim.fluidParticles(); ++i) {
    change += glm::length(glm::vec3(s.velocities[i]) - glm::vec3(start.velocities[i]));
    scale += glm::length(glm::vec3(start.velocities[i]) - glm::vec3(0.3f, -0.2f, 0.1f));
  }
  EXPECT_GT(change, 0.3 * scale) << "the stirring should have been reshaped by pressure and viscosity";
  EXPECT_EQ(sim.steps(), 1000u);
}

TEST_F(SphPhysicsTest, TwoRunsAreBitIdentical) {
  const scene::Scene scene = scene::parseScene(kColumn, "column_test");
  std::vector<glm::vec4> first;
  for (int run = 0; run < 2; ++run) {
    sim::Simulation sim(ctx(), scene);
    sim::RunOptions opt;
    opt.steps = 300;
    sim.run(opt);
    const auto s = sim.snapshot();
    std::vector<glm::vec4> state = s.positions;
    state.insert(state.end(), s.velocities.begin(), s.velocities.end());
    if (run == 0) {
      first = state;
    } else {
      ASSERT_EQ(state.size(), first.size());
      EXPECT_EQ(0, std::memcmp(state.data(), first.data(), state.size() * sizeof(glm::vec4)))
          << "positions/velocities differ between two runs of the same scene";
    }
  }
}

TEST_F(SphPhysicsTest, EndTimeIsHitExactlyAndStepsAfterItDoNothing) {
  const scene::Scene scene = scene::parseScene(kColumn, "column_test");
  sim::Simulation sim(ctx(), scene);
  sim::RunOptions opt;
  opt.until = 0.0123;
  const auto r = sim.run(opt);
  EXPECT_NEAR(sim.time(), 0.0123, 1e-7);
  EXPECT_GT(r.steps, 10u);
  const auto before = sim.snapshot();
  sim.run(opt);  // already there: nothing happens
  const auto after = sim.snapshot();
  EXPECT_EQ(0, std::memcmp(before.positions.data(), after.positions.data(), before.positions.size() * 16));
}

// A particle that becomes non-finite stops the run with the step, the time and the particle.
TEST_F(SphPhysicsTest, NonFiniteStateStopsWithStepTimeAndParticle) {
  const scene::Scene scene = scene::parseScene(kColumn, "column_test");
  sim::Simulation sim(ctx(), scene);
  sim::RunOptions opt;
  opt.steps = 7;
  sim.run(opt);
  // Poison the velocity of particle id 42 (a hidden host-side fault, as a bad force would).
  auto vel = sim.store().readVelocities();
  const auto ids = sim.store().readIds();
  for (std::size_t i = 0; i < ids.size(); ++i) {
    if (ids[i] == 42) vel[i].x = std::numeric_limits<float>::quiet_NaN();
  }
  sim.store().half(sim.store().parity()).velocities.upload(vel);
  try {
    sim.run(opt);
    FAIL() << "the run should have stopped";
  } catch (const sim::SimulationError& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("non-finite at step 7"), std::string::npos) << m;
    EXPECT_NE(m.find("particle id 42"), std::string::npos) << m;
    EXPECT_NE(m.find("t = "), std::string::npos) << m;
  }
}

}  // namespace
}  // namespace hemo::test
