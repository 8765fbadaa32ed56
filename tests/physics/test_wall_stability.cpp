// Issue 4, test 6: hard cases for the vessel wall. A wall hit by a fast jet, very stiff
// springs at the largest time-step factor the integrator is stable with, and a wall whose
// springs all break: the state stays finite, speeds stay bounded, and every particle is still
// there (none lost; those outside the vessel are counted as escaped).
#include "gpu_test.hpp"
#include "hemo/scene/build.hpp"
#include "hemo/sim/simulation.hpp"

#include <glm/geometric.hpp>

#include <cmath>
#include <cstdio>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>

namespace hemo::test {
namespace {

class WallStabilityTest : public GpuTest {};

// A periodic tube of radius 4 dp (dp 0.5 mm), 16 dp long, blood, c0 = 5 m/s.
nlohmann::json tube() {
  return nlohmann::json::parse(R"({
    "scene": "wall_stability",
    "particles": { "spacing_m": 5e-4 },
    "fluid": { "density_kg_m3": 1060.0, "viscosity_pa_s": 0.0035, "expected_max_speed_m_s": 0.5,
               "background_pressure_Pa": 300.0, "background_pressure_ramp_s": 0.002 },
    "vessel": { "shape": "tube", "length_m": 0.008, "radius_m": 0.002, "point_mass_kg": 2e-5,
                "stiffness_N_m": 50.0, "damping_N_s_m": 0.005 },
    "forces": { "gravity_m_s2": [0, 0, 0] },
    "time": { "steps_per_batch": 100 },
    "domain": { "min_m": [0.0, -0.008, -0.008], "max_m": [0.008, 0.008, 0.012], "periodic": ["x"] }
  })");
}

struct Outcome {
  double maxSpeed = 0.0;
  std::uint32_t escaped = 0;
};

std::unique_ptr<sim::Simulation> make(gpu::Context& ctx, const nlohmann::json& j) {
  return std::make_unique<sim::Simulation>(ctx, scene::parseScene(j.dump(), "wall_stability"));
}

// Runs to `until` and checks what every case must keep: all particles present and finite.
Outcome runAndCheck(sim::Simulation& sim, double until) {
  const std::size_t count = sim.snapshot().positions.size();
  sim::RunOptions opt;
  opt.until = until;
  EXPECT_NO_THROW(sim.run(opt));
  const sim::Snapshot s = sim.snapshot();
  EXPECT_EQ(s.positions.size(), count);
  Outcome o;
  for (std::size_t i = 0; i < s.positions.size(); ++i) {
    EXPECT_EQ(s.ids[i], i) << "particle " << i << " is missing";
    const glm::vec3 x(s.positions[i]), v(s.velocities[i]);
    EXPECT_TRUE(std::isfinite(x.x) && std::isfinite(x.y) && std::isfinite(x.z)) << "particle " << i;
    o.maxSpeed = std::max(o.maxSpeed, double(glm::length(v)));
  }
  o.escaped = sim.escapedParticles();
  EXPECT_NEAR(sim.time(), until, 1e-6);
  return o;
}

// A block of blood shot at 1.5 m/s (3x the design speed) against the outside of the tube.
TEST_F(WallStabilityTest, FastJetOnTheWall) {
  nlohmann::json j = tube();
  j["vessel"]["max_force_N"] = 5e-3;
  j["fluid"]["blocks"] = nlohmann::json::parse(R"([{ "min_m": [0.0, -0.0015, 0.0035], "max_m": [0.008, 0.0015, 0.0055],
                                                     "velocity_m_s": [0.0, 0.0, -1.5] }])");
  const auto sim = make(ctx(), j);
  const Outcome o = runAndCheck(*sim, 0.01);
  EXPECT_LT(o.maxSpeed, 5.0) << "a particle outran the speed of sound c0 = 5 m/s (the jet: 1.5 m/s)";
  std::printf("jet: max speed %.3f m/s after 10 ms, %u springs broken, %u particles outside the vessel\n", o.maxSpeed,
              sim->brokenSprings(), o.escaped);
}

// The tube with springs 200x stiffer (1e4 N/m, undamped) at the largest time-step factor, in
// `substeps` per step; and the wall's own explicit limit sqrt(m / sum k) (about 14 springs per
// point).
nlohmann::json stiffTube(int substeps) {
  nlohmann::json j = tube();
  j["vessel"]["stiffness_N_m"] = 1e4;
  j["vessel"]["damping_N_s_m"] = 0.0;
  j["vessel"]["time_step_factor"] = 1.0;
  j["vessel"]["substeps"] = substeps;
  return j;
}
const double kStiffWallLimit = std::sqrt(2e-5 / (1e4 * 14.0));

// Springs 200x stiffer (1e4 N/m) under the lumen pressure, with the wall's time step at the
// largest factor the network accepts (dt = sqrt(m / sum k), symplectic Euler; its stability
// limit is 2 / omega_max >= sqrt(2 m / sum k)). The wall's step governs: about 6 us here
// against the fluid's 40 us.
TEST_F(WallStabilityTest, StiffSpringsAtTheLargestTimeStepFactor) {
  const auto sim = make(ctx(), stiffTube(1));
  const Outcome o = runAndCheck(*sim, 0.005);
  const double meanDt = 0.005 / double(sim->steps());
  const double dtWall = kStiffWallLimit;
  EXPECT_LT(meanDt, 2.0 * dtWall) << "the wall's limit did not govern the step";
  EXPECT_LT(o.maxSpeed, 0.5);
  EXPECT_EQ(o.escaped, 0u);
  std::printf("stiff: %llu steps to 5 ms (mean dt %.3g s), max speed %.4f m/s\n",
              static_cast<unsigned long long>(sim->steps()), meanDt, o.maxSpeed);
}

// The same stiff springs in 8 substeps per step (vessel.substeps, wall/substep.comp): the
// wall no longer sets the step (the fluid's acoustic limit, about 40 us, does: three times the
// wall's own 12 us, while 8 substeps would allow 96 us), and the tube stays as quiet as at the
// wall's own step.
TEST_F(WallStabilityTest, StiffSpringsInSubstepsDoNotLimitTheStep) {
  const auto sim = make(ctx(), stiffTube(8));
  const Outcome o = runAndCheck(*sim, 0.005);
  const double meanDt = 0.005 / double(sim->steps());
  const double dtWall = kStiffWallLimit;
  EXPECT_GT(meanDt, 3.0 * dtWall) << "the wall's springs still limit the step";
  EXPECT_LT(o.maxSpeed, 0.5);
  EXPECT_EQ(o.escaped, 0u);
  EXPECT_EQ(sim->brokenSprings(), 0u);
  std::printf("stiff in 8 substeps: %llu steps to 5 ms (mean dt %.3g s, the wall's own limit %.3g s), max speed %.4f m/s\n",
              static_cast<unsigned long long>(sim->steps()), meanDt, dtWall, o.maxSpeed);
}

// Every spring breaks (maximum force 1 nN: each breaks as soon as it is stretched at all):
// every wall particle detaches, the wall stops holding the fluid, and the blood that the
// inflow keeps pumping at its pressure leaves the tube. (Without a supply a closed vessel's
// blood only expands until its pressure falls to zero, about 4% at 1 kPa and c0 = 5 m/s, and
// then stays put: no gush without a heart.)
TEST_F(WallStabilityTest, AllSpringsBroken) {
  for (const int substeps : {1, 4}) {
    SCOPED_TRACE(testing::Message() << substeps << " wall substeps");
    nlohmann::json j = tube();
    j["vessel"]["substeps"] = substeps;
    j["vessel"]["max_force_N"] = 1e-9;
    j["vessel"]["point_mass_kg"] = 1e-6;
    j["fluid"]["background_pressure_Pa"] = 1000.0;
    j["vessel"]["inflow"] = nlohmann::json::parse(R"({ "profile": "parabolic", "mean_speed_m_s": 0.2, "zone_length_m": 0.002,
                                                      "hold_lumen_pressure": true })");
    const auto sim = make(ctx(), j);
    const Outcome o = runAndCheck(*sim, 0.02);
    EXPECT_EQ(sim->brokenSprings(), sim->springs());
    EXPECT_EQ(sim->detachedParticles(), sim->wallParticles());
    EXPECT_GT(o.escaped, 0u) << "nothing left the broken tube";
    EXPECT_LT(o.maxSpeed, 3.0);
    std::printf("all broken, %d substeps: %u springs, %u detached, %u of %u fluid particles escaped, max speed %.3f m/s\n",
                substeps, sim->brokenSprings(), sim->detachedParticles(), o.escaped, sim->fluidParticles(), o.maxSpeed);
  }
}

}  // namespace
}  // namespace hemo::test
