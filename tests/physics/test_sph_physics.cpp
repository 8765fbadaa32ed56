// SPH physics against analytic results: hydrostatic pressure, momentum conservation,
// determinism, and hard cases that must not blow up.
#include "gpu_test.hpp"
#include "hemo/reference/sph.hpp"
#include "hemo/scene/scene.hpp"
#include "hemo/sim/simulation.hpp"

#include <glm/geometric.hpp>

#include <cmath>
#include <cstring>

namespace hemo::test {
namespace {

class SphPhysicsTest : public GpuTest {};

// A column of height H = 0.1 m in a tank; a damped settling phase of 0.4 s, then free. The
// viscosity (0.5 Pa s, a syrup) only makes it settle sooner: hydrostatics does not depend on it.
const char* kHydrostatic = R"({
  "scene": "hydrostatic_test",
  "particles": { "spacing_m": 0.01 },
  "fluid": { "density_kg_m3": 1000, "viscosity_pa_s": 0.5, "expected_max_speed_m_s": 1.4,
             "blocks": [ { "min_m": [0, 0, 0], "max_m": [0.12, 0.12, 0.1] } ] },
  "boundary": { "tanks": [ { "min_m": [0, 0, 0], "max_m": [0.12, 0.12, 0.11], "layers": 3 } ] },
  "time": { "max_dt_s": 0.001, "steps_per_batch": 128, "settle_damping_1_s": 30, "settle_until_s": 0.4 },
  "domain": { "min_m": [-0.04, -0.04, -0.04], "max_m": [0.16, 0.16, 0.15] }
})";

TEST_F(SphPhysicsTest, HydrostaticColumnSettlesToRhoGH) {
  const scene::Scene scene = scene::parseScene(kHydrostatic, "hydrostatic_test");
  sim::Simulation sim(ctx(), scene);
  const double g = 9.81, rho0 = 1000.0, H = 0.1, dp = scene.sph.spacing;
  sim::RunOptions settle;
  settle.until = 0.5;  // damped until 0.4 s, then 0.1 s free
  sim.run(settle);
  const sim::Snapshot settled = sim.snapshot();
  sim::RunOptions more;
  more.until = 0.7;
  sim.run(more);
  const sim::Snapshot s = sim.snapshot();

  // Pressure on the bottom: the vertical force the fluid exerts on the floor's boundary
  // particles (the reaction of the symmetric pressure term, evaluated from the GPU state)
  // divided by the floor area, against rho0 g H (H = fluid volume / floor area).
  const double h = scene.sph.h();
  double floorForce = 0.0;
  for (std::uint32_t b = sim.fluidParticles(); b < s.positions.size(); ++b) {
    if (s.positions[b].z >= 0.0f) continue;
    for (std::uint32_t f = 0; f < sim.fluidParticles(); ++f) {
      const glm::dvec3 d = glm::dvec3(s.positions[b]) - glm::dvec3(s.positions[f]);
      const double r = glm::length(d);
      if (r >= 2.0 * h || r == 0.0) continue;
      const glm::dvec3 gradW = d * (reference::kernelDwdr(r, h) / r);
      const glm::dvec2 sb = s.densityPressure[b], sf = s.densityPressure[f];
      floorForce -= double(s.positions[b].w) * double(s.positions[f].w) *
                    (sb.y / (sb.x * sb.x) + sf.y / (sf.x * sf.x)) * gradW.z;
    }
  }
  const double area = 0.12 * 0.12;
  const double floorPressure = floorForce / area;
  RecordProperty("floor_pressure_pa", std::to_string(floorPressure));
  EXPECT_NEAR(floorPressure, rho0 * g * H, 0.02 * rho0 * g * H)
      << "pressure on the floor " << floorPressure << " Pa vs rho g H " << rho0 * g * H << " Pa";

  // The pressure gradient in the lower half of the column (least squares) is rho0 g.
  double sz = 0, sp = 0, szz = 0, szp = 0;
  int count = 0;
  for (std::uint32_t i = 0; i < sim.fluidParticles(); ++i) {
    const double z = s.positions[i].z, p = s.densityPressure[i].y;
    if (z > 0.5 * H) continue;
    sz += z;
    sp += p;
    szz += z * z;
    szp += z * p;
    ++count;
  }
  ASSERT_GT(count, 50);
  const double slope = (count * szp - sz * sp) / (count * szz - sz * sz);
  EXPECT_NEAR(-slope, rho0 * g, 0.05 * rho0 * g) << "pressure gradient " << -slope << " Pa/m vs rho g";

  // No particle drifts more than 0.1 dp after settling.
  double drift = 0.0;
  for (std::uint32_t i = 0; i < sim.fluidParticles(); ++i) {
    drift = std::max(drift, double(glm::length(glm::vec3(s.positions[i]) - glm::vec3(settled.positions[i]))));
  }
  EXPECT_LT(drift, 0.1 * dp) << "largest drift after settling: " << drift / dp << " dp";
  EXPECT_EQ(sim.escapedParticles(), 0u);
}

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
  const scene::Scene scene = scene::parseScene(kHydrostatic, "hydrostatic_test");
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
  const scene::Scene scene = scene::parseScene(kHydrostatic, "hydrostatic_test");
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

}  // namespace
}  // namespace hemo::test
