// Issue 4, test 5: with inflow, fluid enters the sac; a pressurised saccular aneurysm
// ruptures in the sac, not in the parent tube; blood escapes through the hole.
#include "gpu_test.hpp"
#include "hemo/scene/build.hpp"
#include "hemo/sim/simulation.hpp"
#include "hemo/sim/stats.hpp"

#include <glm/geometric.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <nlohmann/json.hpp>
#include <string>

namespace hemo::test {
namespace {

class AneurysmTest : public GpuTest {};

// scenes/aneurysm.json's geometry at a coarser spacing (25 instead of 32 spacings along the
// tube: about 3,700 particles), the lumen pressure raised to `target` x the sac's rupture
// pressure over 30 ms.
scene::Scene coarseAneurysm(double target) {
  auto j = nlohmann::json::parse(R"({
    "scene": "aneurysm_test",
    "particles": { "spacing_m": 4.48e-4 },
    "fluid": { "density_kg_m3": 1060.0, "viscosity_pa_s": 0.0035, "expected_max_speed_m_s": 0.5 },
    "vessel": { "shape": "saccular_aneurysm", "length_m": 0.0112, "radius_m": 0.00175, "point_mass_kg": 5e-6,
                "stiffness_N_m": 5.0, "damping_N_s_m": 0.002, "max_force_N": 2e-4, "sac_radius_m": 0.0028,
                "neck_width_m": 0.0024, "sac_strength_scale": 0.5 },
    "forces": { "gravity_m_s2": [0, 0, 0] },
    "time": { "steps_per_batch": 100, "settle_damping_1_s": 1000.0, "settle_until_s": 0.005 },
    "domain": { "min_m": [0.0, -0.006, -0.004], "max_m": [0.0112, 0.006, 0.013], "periodic": ["x"] }
  })");
  scene::Scene s = scene::parseScene(j.dump(), "aneurysm_test");
  const scene::AneurysmBuild b = scene::buildSaccularAneurysm(scene::vesselSpec(s));
  s.sph.backgroundPressure = float(target * scene::sacRupturePressure(b));
  s.sph.backgroundPressureRamp = 0.03f;
  return s;
}

// The same with test 5's blood flow: a parabolic inflow of mean 0.2 m/s in the tube's first
// four spacings, ramped over 10 ms, the zone also the lumen's supply.
scene::Scene coarseAneurysmWithSupply(double target) {
  scene::Scene s = coarseAneurysm(target);
  sim::Inflow inflow;
  inflow.zoneStart = 0.0f;
  inflow.zoneEnd = 4.0f * s.sph.spacing;
  inflow.radius = scene::vesselSpec(s).tube.radius;
  inflow.meanSpeed = 0.2f;
  inflow.ramp = 0.01f;
  inflow.holdPressure = true;
  s.vessel->inflow = inflow;
  return s;
}

// Springs of the built network by where they are: in the sac (both ends sac points), joining
// the sac to the tube, on the neck's rim (tube springs with an end joined to a sac point), or
// in the parent tube (the rest).
struct SpringPlaces {
  enum Place : std::uint8_t { Sac, Junction, Rim, Tube };
  std::vector<std::uint8_t> place;
  explicit SpringPlaces(const scene::AneurysmBuild& b) {
    std::vector<std::uint8_t> rimPoint(b.inSac.size(), 0);
    for (const auto& s : b.network.springs) {
      if (b.inSac[s.a] != b.inSac[s.b]) rimPoint[b.inSac[s.a] ? s.b : s.a] = 1;
    }
    for (const auto& s : b.network.springs) {
      place.push_back(b.inSac[s.a] && b.inSac[s.b] ? Sac
                      : b.inSac[s.a] || b.inSac[s.b] ? Junction
                      : rimPoint[s.a] || rimPoint[s.b] ? Rim : Tube);
    }
  }
  std::array<std::uint32_t, 4> broken(const std::vector<sim::GpuSpring>& springs) const {
    std::array<std::uint32_t, 4> n{0, 0, 0, 0};
    for (std::size_t k = 0; k < springs.size(); ++k) n[place[k]] += springs[k].broken ? 1 : 0;
    return n;
  }
};

// Test 5. Blood flows along the tube (parabolic inflow, mean 0.2 m/s, the zone also holding
// the lumen pressure) while the lumen pressure rises to 1.5 x the sac's rupture pressure
// P*_sac (0.58 x the tube's). Fluid from the tube enters the sac; the first springs to break
// are the sac's (or its rim's, where the sac's tension meets the tube lattice); the parent
// tube away from the rim tears, if at all, only after the sac is open (at least 100 of its
// and its junction's springs broken); blood escapes through
// the hole, and every particle stays finite and counted.
TEST_F(AneurysmTest, SacRupturesFirstAndBloodEscapes) {
  scene::Scene scene = coarseAneurysmWithSupply(1.5);
  const scene::AneurysmSpec spec = scene::vesselSpec(scene);
  const scene::AneurysmBuild build = scene::buildSaccularAneurysm(spec);
  const double sacP = scene::sacRupturePressure(build), tubeP = scene::hoopRupturePressure(spec.tube, scene::buildTube(spec.tube));
  ASSERT_LT(1.5 * sacP, 0.7 * tubeP) << "the test needs a lumen pressure the tube holds";
  const SpringPlaces places(build);
  sim::Simulation sim(ctx(), scene);
  ASSERT_EQ(sim.wallParticles(), build.wall);
  const glm::dvec3 centre(build.sacCentre);
  auto inSacLumen = [&](const glm::vec4& x) {
    const double r = std::hypot(double(x.y) - spec.tube.centreYZ.x, double(x.z) - spec.tube.centreYZ.y);
    return r > spec.tube.radius && glm::length(glm::dvec3(x) - centre) < spec.sacRadius;
  };
  const sim::Snapshot start = sim.snapshot();
  sim::RunOptions opt;
  opt.steps = 100;
  double firstBreak = -1.0, firstTube = -1.0;
  std::array<std::uint32_t, 4> atFirst{}, atFirstTube{};
  while (sim.time() < 0.06) {
    sim.run(opt);
    const auto broken = places.broken(sim.solver().wall()->readSprings());
    if (firstBreak < 0.0 && broken[0] + broken[1] + broken[2] + broken[3] > 0) firstBreak = sim.time(), atFirst = broken;
    if (firstTube < 0.0 && broken[SpringPlaces::Tube] > 0) firstTube = sim.time(), atFirstTube = broken;
  }
  ASSERT_GE(firstBreak, 0.0) << "the sac did not rupture by t = " << sim.time() << " s";
  EXPECT_EQ(atFirst[SpringPlaces::Tube], 0u) << "at the first rupture (t = " << firstBreak << " s) parent-tube springs broke";
  EXPECT_GE(atFirst[SpringPlaces::Sac], atFirst[SpringPlaces::Rim]) << "the rim broke before the sac";
  if (firstTube >= 0.0) {
    EXPECT_GE(atFirstTube[SpringPlaces::Sac] + atFirstTube[SpringPlaces::Junction], 100u)
        << "the parent tube tore (t = " << firstTube << " s) before the sac was open";
  }
  const sim::Snapshot end = sim.snapshot();
  std::uint32_t entered = 0;
  for (std::uint32_t i = build.wall; i < end.positions.size(); ++i) {
    if (!inSacLumen(start.positions[i]) && inSacLumen(end.positions[i])) ++entered;
  }
  for (const auto& x : end.positions) ASSERT_TRUE(std::isfinite(x.x) && std::isfinite(x.y) && std::isfinite(x.z));
  EXPECT_EQ(end.positions.size(), start.positions.size());
  const std::uint32_t escaped = sim.escapedParticles();
  // Where the escaped blood left: through the sac's side (above the tube's outer wall) or
  // through the parent tube.
  std::uint32_t viaSac = 0;
  const double tubeTop = double(spec.tube.centreYZ.y) + spec.tube.radius + spec.tube.layers * spec.tube.spacing;
  for (std::uint32_t i = build.wall; i < end.positions.size(); ++i) {
    const glm::vec4& x = end.positions[i];
    if (scene::outsideVessel(spec, glm::vec3(x), scene.sph.spacing) && x.z > tubeTop) ++viaSac;
  }
  EXPECT_GE(entered, 50u) << "fluid from the tube did not enter the sac";
  // (Since the repulsion stops at dp - D behind a wall particle, fluid that slips between the
  // wall's layers or out through a tear no longer pushes the wall outward from behind, and the
  // rupture is milder than it was: first break at 0.0175 s instead of 0.0098 s, 35 escaped
  // instead of 583 by 0.06 s, about half through the sac's side, the rest where the tube tore
  // next to the neck.)
  EXPECT_GE(escaped, 20u) << "blood did not escape through the hole";
  EXPECT_GT(viaSac, 0u) << "no blood left through the sac";
  const auto broken = places.broken(sim.solver().wall()->readSprings());
  std::printf("sac P* %.0f Pa, tube P* %.0f Pa; first rupture at t = %.4f s (sac %u, junction %u, rim %u); first "
              "parent-tube break at t = %.4f s (sac %u, junction %u, rim %u broken by then); at t = %.4f s broken: sac %u, "
              "junction %u, rim %u, tube %u; %u fluid particles entered the sac, %u escaped (%u through the sac's side)\n",
              sacP, tubeP, firstBreak, atFirst[0], atFirst[1], atFirst[2], firstTube, atFirstTube[0], atFirstTube[1],
              atFirstTube[2], sim.time(), broken[0], broken[1], broken[2], broken[3], entered, escaped, viaSac);
}

// The large-step solver's sac tears near WCSPH's lumen pressure. The coarse aneurysm with
// test 5's inflow and supply, the lumen pressure raised to 1.5 P*_sac over 30 ms, under WCSPH
// (the wall at its own step) and under DFSPH (the wall in 8 substeps): the background pressure
// at the first broken spring (from per-step statistics). Measured on lavapipe: DFSPH at 0.855
// of WCSPH's, in an eighth of the steps; with p = p_bg in DFSPH's density pass (its first
// model) at 0.58-0.60. A tear's onset under the flow's loads
// varies by some 10-20% with the step and the device's rounding, so the test asks for 30%,
// which the first model fails; scenes/aneurysm.json's 10% goal is measured with hemo-run
// (docs/physics.md, "Not yet" under "The pressure solver").
TEST_F(AneurysmTest, DfsphSacTearsNearWcsphsLumenPressure) {
  struct Tear {
    double pressure = -1.0;  // p_bg at the first broken spring (Pa)
    std::uint32_t steps = 0;
  };
  auto firstTear = [&](sim::PressureSolver solver) {
    scene::Scene scene = coarseAneurysmWithSupply(1.5);
    scene.sph.pressureSolver = solver;
    if (solver == sim::PressureSolver::Dfsph) scene.vessel->substeps = 8;
    sim::Simulation sim(ctx(), scene);
    sim.enableStepStats(1);
    Tear tear;
    sim::RunOptions opt;
    opt.steps = 100;
    opt.onStepStats = [&](const std::vector<sim::StepStatsRow>& rows) {
      for (const sim::StepStatsRow& r : rows) {
        if (tear.pressure >= 0.0 || r.brokenSprings == 0) continue;
        tear.pressure = scene.sph.backgroundPressure * std::min(1.0, double(r.time) / scene.sph.backgroundPressureRamp);
        tear.steps = r.steps;
      }
    };
    while (tear.pressure < 0.0 && sim.time() < 0.04) sim.run(opt);
    return tear;
  };
  const Tear wcsph = firstTear(sim::PressureSolver::Wcsph);
  const Tear dfsph = firstTear(sim::PressureSolver::Dfsph);
  ASSERT_GT(wcsph.pressure, 0.0) << "no spring broke under WCSPH by 0.04 s";
  ASSERT_GT(dfsph.pressure, 0.0) << "no spring broke under DFSPH by 0.04 s";
  std::printf("first broken spring: WCSPH at p_bg %.0f Pa after %u steps, DFSPH (8 wall substeps) at %.0f Pa (%.3f) "
              "after %u steps\n",
              wcsph.pressure, wcsph.steps, dfsph.pressure, dfsph.pressure / wcsph.pressure, dfsph.steps);
  EXPECT_NEAR(dfsph.pressure / wcsph.pressure, 1.0, 0.30) << "DFSPH's sac tears at another lumen pressure";
  EXPECT_LT(2 * dfsph.steps, wcsph.steps) << "DFSPH should take far larger steps";
}

}  // namespace
}  // namespace hemo::test
