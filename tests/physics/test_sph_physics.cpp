// SPH physics: lattice stability, hydrostatics, Poiseuille flow, dam break, momentum
// conservation, determinism, end time, hard cases (docs/physics.md has the measurements).
#include "gpu_test.hpp"
#include "run_state.hpp"
#include "hemo/reference/analytic.hpp"
#include "hemo/reference/published.hpp"
#include "hemo/sim/probes.hpp"
#include "hemo/scene/builders.hpp"
#include "hemo/scene/scene.hpp"
#include "hemo/sim/simulation.hpp"

#include <glm/geometric.hpp>

#include <cmath>
#include <cctype>
#include <cstdio>
#include <cstring>
#include <optional>
#include <fstream>
#include <iterator>
#include <random>
#include <string>
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

// Lattice stability: fluid under a uniform pressure of 10 kPa in a periodic box (no gravity,
// water's viscosity), every particle displaced by up to 0.01 dp at random. The body-centred
// arrangement is a stable equilibrium of the pressure force: over 0.3 s the displacements stay
// of their size (measured 0.011 dp; speeds up to 0.04 m/s, the sound the kicks make). The
// simple cubic dp lattice is not: with the same kicks it moved 2.0 dp at 0.38 m/s, and even
// unkicked, seeded by rounding alone, it leaves its lattice by 0.14 dp at 0.15 s
// (docs/physics.md). It is why blocks that start at rest can be filled body-centred.
TEST_F(SphPhysicsTest, BodyCentredLatticeIsAStableEquilibriumUnderPressure) {
  const scene::Scene scene = scene::parseScene(R"({
    "scene": "lattice_test",
    "particles": { "spacing_m": 0.01 },
    "fluid": { "density_kg_m3": 1000, "viscosity_pa_s": 0.001, "expected_max_speed_m_s": 1.4,
               "background_pressure_Pa": 10000,
               "blocks": [ { "min_m": [0, 0, 0], "max_m": [0.1, 0.1, 0.1], "lattice": "bcc" } ] },
    "forces": { "gravity_m_s2": [0, 0, 0] },
    "time": { "max_dt_s": 0.001, "steps_per_batch": 128 },
    "domain": { "min_m": [0, 0, 0], "max_m": [0.1, 0.1, 0.1], "periodic": ["x", "y", "z"] }
  })", "lattice_test");
  const double dp = scene.sph.spacing, period = 0.1;
  sim::Simulation sim(ctx(), scene);
  ASSERT_EQ(sim.fluidParticles(), 2u * 8u * 8u * 8u);
  std::vector<glm::vec4> pos = sim.store().readPositions();
  const std::vector<glm::vec4> vel = sim.store().readVelocities();
  const std::vector<std::uint32_t> ids = sim.store().readIds();
  std::vector<glm::vec3> site(pos.size());
  std::uint32_t state = 12345u;
  auto unit = [&state] {  // deterministic, in [-1, 1)
    state = state * 1664525u + 1013904223u;
    return float(state >> 8) / float(1u << 23) - 1.0f;
  };
  for (std::size_t i = 0; i < pos.size(); ++i) {
    site[ids[i]] = glm::vec3(pos[i]);
    const glm::vec3 kick(unit(), unit(), unit());
    pos[i] += glm::vec4(kick * float(0.01 * dp / std::sqrt(3.0)), 0.0f);
  }
  sim.store().upload(pos, vel, ids);
  double worst = 0.0, fastest = 0.0;
  for (double t : {0.1, 0.2, 0.3}) {
    sim::RunOptions opt;
    opt.until = t;
    sim.run(opt);
    const sim::Snapshot s = sim.snapshot();
    for (std::size_t i = 0; i < s.ids.size(); ++i) {
      glm::dvec3 d = glm::dvec3(glm::vec3(s.positions[i])) - glm::dvec3(site[s.ids[i]]);
      for (int a = 0; a < 3; ++a) d[a] -= period * std::round(d[a] / period);
      worst = std::max(worst, glm::length(d) / dp);
      fastest = std::max(fastest, double(glm::length(glm::vec3(s.velocities[i]))));
    }
  }
  RecordProperty("max_displacement_dp", std::to_string(worst));
  std::printf("body-centred lattice under 10 kPa: largest displacement %.4f dp, speed %.2e m/s over %llu steps\n", worst,
              fastest, static_cast<unsigned long long>(sim.steps()));
  EXPECT_LT(worst, 0.03) << "the lattice did not hold";
  EXPECT_LT(fastest, 0.1) << "m/s";
}

// The open test column: 0.1 m of water filled body-centred (576 particles) in an open tank,
// settled with damping until 0.8 s; `density` is fluid.density.
scene::Scene openColumn(const std::string& density) {
  return scene::parseScene(R"({
    "scene": "hydrostatic_test",
    "particles": { "spacing_m": 0.01 },
    "fluid": { "density_kg_m3": 1000, "viscosity_pa_s": 0.5, "expected_max_speed_m_s": 1.4, "density": ")" + density + R"(",
               "blocks": [ { "min_m": [0, 0, 0], "max_m": [0.08, 0.08, 0.1], "lattice": "bcc" } ] },
    "boundary": { "tanks": [ { "min_m": [0, 0, 0], "max_m": [0.08, 0.08, 0.11], "layers": 3 } ] },
    "time": { "max_dt_s": 0.001, "steps_per_batch": 128, "settle_damping_1_s": 30, "settle_until_s": 0.8 },
    "domain": { "min_m": [-0.04, -0.04, -0.04], "max_m": [0.12, 0.12, 0.15] }
  })", "hydrostatic_test");
}

// Hydrostatics: a 0.1 m column filled body-centred (576 particles; the simple cubic lattice
// is unstable under pressure, see BodyCentredLatticeIsAStableEquilibriumUnderPressure), settled
// with damping until 0.8 s. The pressure on the floor is the vertical force the fluid exerts
// on the floor's boundary particles (the reaction of the symmetric pressure term, evaluated
// from the GPU state), divided by the floor area, averaged over 0.8-1.0 s; it must be
// rho0 g H within 2% (measured 970 Pa against 981). The pressure gradient in the lower half
// must be rho0 g within 5%. Drift: the particles deeper than 2h below the free surface move
// less than 0.1 dp from 0.8 to 1.0 s (measured 0.073 dp). The free-surface layer above them
// does not stay put: summation density gives it too little density, so it packs tighter than
// the bulk and keeps rearranging (0.38 dp in the same 0.2 s; docs/physics.md); the closed
// column below holds every particle.
TEST_F(SphPhysicsTest, HydrostaticColumnLoadsTheFloorWithRhoGH) {
  const scene::Scene scene = openColumn("summation");
  sim::Simulation sim(ctx(), scene);
  const double g = 9.81, rho0 = 1000.0, H = 0.1, area = 0.08 * 0.08, h = scene.sph.h(), dp = scene.sph.spacing;
  double loadSum = 0.0, slopeSum = 0.0;
  int samples = 0;
  sim::Snapshot settled;
  double top = 0.0;
  for (double t : {0.8, 0.9, 1.0}) {
    sim::RunOptions opt;
    opt.until = t;
    sim.run(opt);
    const sim::Snapshot s = sim.snapshot();
    loadSum += sim::floorLoad(s, sim.fluidParticles(), h) / area;
    slopeSum += sim::pressureGradient(s, sim.fluidParticles(), float(0.5 * H));
    ++samples;
    if (t == 0.8) {
      settled = s;
      for (std::size_t i = 0; i < s.ids.size(); ++i) top = std::max(top, double(s.positions[i].z));
    }
  }
  const double load = loadSum / samples, gradient = -slopeSum / samples;
  const double deepDrift = sim::largestDisplacement(settled, sim.snapshot(), top - 2.0 * h) / dp;
  RecordProperty("floor_pressure_pa", std::to_string(load));
  RecordProperty("deep_drift_dp", std::to_string(deepDrift));
  std::printf("open column: floor %.1f Pa, gradient %.1f Pa/m, drift below the surface layer %.3f dp, of all %.3f dp\n",
              load, gradient, deepDrift, sim::largestDisplacement(settled, sim.snapshot(), 1e9) / dp);
  EXPECT_NEAR(load, rho0 * g * H, 0.02 * rho0 * g * H) << "pressure on the floor " << load << " Pa";
  EXPECT_NEAR(gradient, rho0 * g, 0.05 * rho0 * g) << "pressure gradient " << gradient << " Pa/m";
  EXPECT_EQ(sim.escapedParticles(), 0u);
}

// A column held at rest: settled (damped) until 0.8 s, then left alone until 1.4 s. Gives the
// mean of `load` (Pa) at 1.0, 1.2 and 1.4 s, the largest drift of any fluid particle from 0.8
// to 1.4 s (dp) and the largest speed at 1.4 s (m/s).
struct HeldColumn {
  double load = 0.0, driftDp = 0.0, fastest = 0.0;
  sim::Snapshot last;
};
template <class Load>
HeldColumn holdColumn(sim::Simulation& sim, double dp, Load load) {
  sim::RunOptions opt;
  opt.until = 0.8;
  sim.run(opt);
  const sim::Snapshot settled = sim.snapshot();
  HeldColumn r;
  const double times[] = {1.0, 1.2, 1.4};
  for (double t : times) {
    opt.until = t;
    sim.run(opt);
    r.load += load(sim.snapshot()) / std::size(times);
  }
  r.last = sim.snapshot();
  r.driftDp = sim::largestDisplacement(settled, r.last) / dp;
  for (const glm::vec4& v : r.last.velocities) r.fastest = std::max(r.fastest, double(glm::length(glm::vec3(v))));
  return r;
}

// The issue's drift criterion with a free surface: the open column with continuity density
// (fluid.density "continuity", delta-SPH diffusion less its hydrostatic part). Each particle
// carries the fill's rest density, so the top layers are not short of density as summation
// leaves them (docs/physics.md, "The free-surface drift"), and do not sink and rearrange. From
// 0.8 to 1.4 s no particle moves more than 0.1 dp; the floor load is rho0 g H within 2%.
TEST_F(SphPhysicsTest, OpenHydrostaticColumnWithContinuityDensityStaysPut) {
  const scene::Scene scene = openColumn("continuity");
  sim::Simulation sim(ctx(), scene);
  const double g = 9.81, rho0 = 1000.0, H = 0.1, area = 0.08 * 0.08, h = scene.sph.h();
  const HeldColumn c = holdColumn(sim, scene.sph.spacing, [&](const sim::Snapshot& s) {
    return sim::floorLoad(s, sim.fluidParticles(), h) / area;
  });
  RecordProperty("drift_dp", std::to_string(c.driftDp));
  std::printf("open column, continuity density: drift %.3f dp, speed %.2e m/s, floor %.1f Pa (rho0 g H %.1f)\n", c.driftDp,
              c.fastest, c.load, rho0 * g * H);
  EXPECT_LT(c.driftDp, 0.1) << "dp, 0.8-1.4 s";
  EXPECT_NEAR(c.load, rho0 * g * H, 0.02 * rho0 * g * H) << "pressure on the floor, Pa";
  EXPECT_EQ(sim.escapedParticles(), 0u);
}

// Continuity density is carried by the particle through every grid rebuild (the reorder moves
// normals.w with it). A fully periodic box translating uniformly, every particle with its own
// density below rho0 (so the clamped pressure is 0 everywhere), no viscosity, no gravity, no
// diffusion: nothing accelerates, every pair's v_i - v_j is exactly 0, so each particle's
// density must come out exactly as it went in, by id, after the list has been rebuilt and the
// slots reordered many times. (A uniform translation never brings a new pair within reach:
// the tile test keeps the list until the particles have moved half of a tile less the support,
// here (0.0433 - 0.026) / 2 m, about every 31 steps, in a box of three tiles a side.)
TEST_F(SphPhysicsTest, ContinuityDensityTravelsWithItsParticle) {
  const scene::Scene scene = scene::parseScene(R"({
    "scene": "carried_density_test",
    "particles": { "spacing_m": 0.01 },
    "fluid": { "viscosity_pa_s": 0, "expected_max_speed_m_s": 3.0, "density": "continuity", "delta_sph": 0,
               "blocks": [ { "min_m": [0, 0, 0], "max_m": [0.13, 0.13, 0.13], "velocity_m_s": [0, 2.0, 1.2] } ] },
    "forces": { "gravity_m_s2": [0, 0, 0] },
    "time": { "steps_per_batch": 64 },
    "domain": { "min_m": [0, 0, 0], "max_m": [0.13, 0.13, 0.13], "periodic": ["x", "y", "z"] }
  })", "carried_density_test");
  sim::Simulation sim(ctx(), scene);
  sim::ParticleStore& store = sim.store();
  const auto pos = store.readPositions(), vel = store.readVelocities();
  const auto ids = store.readIds();
  std::vector<glm::vec4> normals(pos.size(), glm::vec4(0.0f));
  std::vector<float> carried(pos.size());
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> spread(950.0f, 999.0f);
  for (std::size_t k = 0; k < pos.size(); ++k) {
    carried[ids[k]] = spread(rng);
    normals[k].w = carried[ids[k]];
  }
  store.upload(pos, vel, ids, normals);
  sim::RunOptions opt;
  opt.steps = 512;
  sim.run(opt);
  const sim::Snapshot s = sim.snapshot();
  const std::uint32_t rebuilds = sim.solver().readRebuilds();
  std::size_t same = 0;
  for (std::size_t k = 0; k < s.ids.size(); ++k) same += s.densityPressure[k].x == carried[s.ids[k]];
  std::printf("carried density: %zu of %zu particles kept theirs exactly over %u list rebuilds\n", same, s.ids.size(),
              rebuilds);
  EXPECT_GT(rebuilds, 10u) << "the test must reorder the slots";
  EXPECT_EQ(same, s.ids.size());
}

// The issue's drift criterion for every particle: the same column in a closed tank filled to
// the lid, at a background pressure of 1 kPa (so no part of it is near zero pressure, where
// the lattice has nothing to hold it), settled until 0.8 s. From 0.8 to 1.4 s no particle
// moves more than 0.1 dp (measured 0.053 dp; filled on the simple cubic lattice instead, it
// moved 0.77 dp) and the speeds die away (measured 1.3e-4 m/s at 1.4 s). The floor's load less
// the lid's is the column's weight per area within 2% (measured 968.5 Pa against 973.7; the
// body-centred fill's mass is 0.75% short of rho0 V: on its stretched cells the kernel sum
// exceeds the particles per volume by that much).
TEST_F(SphPhysicsTest, ClosedHydrostaticColumnStaysPut) {
  const scene::Scene scene = scene::parseScene(R"({
    "scene": "hydrostatic_closed_test",
    "particles": { "spacing_m": 0.01 },
    "fluid": { "density_kg_m3": 1000, "viscosity_pa_s": 0.5, "expected_max_speed_m_s": 1.4,
               "background_pressure_Pa": 1000,
               "blocks": [ { "min_m": [0, 0, 0], "max_m": [0.08, 0.08, 0.1], "lattice": "bcc" } ] },
    "boundary": { "tanks": [ { "min_m": [0, 0, 0], "max_m": [0.08, 0.08, 0.1], "layers": 3, "open_top": false } ] },
    "time": { "max_dt_s": 0.001, "steps_per_batch": 128, "settle_damping_1_s": 30, "settle_until_s": 0.8 },
    "domain": { "min_m": [-0.04, -0.04, -0.04], "max_m": [0.12, 0.12, 0.15] }
  })", "hydrostatic_closed_test");
  sim::Simulation sim(ctx(), scene);
  const double g = 9.81, rho0 = 1000.0, H = 0.1, area = 0.08 * 0.08, h = scene.sph.h();
  const HeldColumn c = holdColumn(sim, scene.sph.spacing, [&](const sim::Snapshot& s) {
    return (sim::floorLoad(s, sim.fluidParticles(), h) - sim::lidLoad(s, sim.fluidParticles(), h, float(H))) / area;
  });
  RecordProperty("drift_dp", std::to_string(c.driftDp));
  double weight = 0.0;
  for (std::size_t i = 0; i < c.last.ids.size(); ++i) {
    if (c.last.velocities[i].w == float(sim::ParticleKind::Fluid)) weight += double(c.last.positions[i].w) * g;
  }
  std::printf("closed column: drift %.3f dp, speed %.2e m/s, floor - lid %.1f Pa, weight / area %.1f Pa (rho0 g H %.1f)\n",
              c.driftDp, c.fastest, c.load, weight / area, rho0 * g * H);
  EXPECT_LT(c.driftDp, 0.1) << "dp, 0.8-1.4 s";
  EXPECT_LT(c.fastest, 1e-3) << "m/s at 1.4 s";
  EXPECT_NEAR(c.load, weight / area, 0.02 * weight / area) << "floor load less the lid's, Pa";
  EXPECT_EQ(sim.escapedParticles(), 0u);
}

// Plane Poiseuille flow, scenes/poiseuille.json (the case of Morris, Fox & Zhu 1997): walls
// at z = 0 and z = L = 1 mm (three layers of boundary particles each), periodic in x and y,
// nu = 1e-6 m^2/s, driven by a body force F = 2e-4 m/s^2 along x from rest; steady peak
// F L^2 / (8 nu) = 25 um/s. 20 particles across the channel, 9 x 9 along the periodic axes.
// The mean velocity of each particle layer is compared with the start-up series at several
// times; RMS error relative to the steady peak (measured 0.2-0.4%, docs/physics.md).
TEST_F(SphPhysicsTest, PoiseuilleStartupFollowsTheSeriesSolution) {
  const double L = 1e-3, F = 2e-4, nu = 1e-6, peak = F * L * L / (8 * nu);
  const scene::Scene scene = scene::loadScene(std::string(HEMO_SOURCE_DIR) + "/scenes/poiseuille.json");
  ASSERT_NEAR(scene.sph.viscosity / scene.sph.restDensity, nu, 1e-12);
  ASSERT_FLOAT_EQ(scene.sph.bodyForce.x, float(F));
  sim::Simulation sim(ctx(), scene);
  std::string measured;
  for (double t : {0.05, 0.1, 0.2, 0.5, 1.0}) {
    sim::RunOptions opt;
    opt.until = t;
    sim.run(opt);
    const sim::Snapshot snap = sim.snapshot();
    const double rms = sim::poiseuilleProfileError(snap, sim.fluidParticles(), scene.sph.spacing, L, F, nu, t);
    double maxCross = 0.0;
    for (std::uint32_t i = 0; i < sim.fluidParticles(); ++i) {
      maxCross = std::max({maxCross, std::abs(double(snap.velocities[i].y)), std::abs(double(snap.velocities[i].z))});
    }
    measured += " t=" + std::to_string(t) + ": " + std::to_string(rms);
    EXPECT_LT(rms, 0.02) << "RMS error of the velocity profile at t = " << t << " s, relative to the steady peak";
    EXPECT_LT(maxCross, 0.05 * peak) << "velocity across the flow at t = " << t;
  }
  RecordProperty("rms_over_peak", measured);
  std::printf("Poiseuille RMS / peak:%s (%llu steps, %u neighbour-list builds)\n", measured.c_str(),
              static_cast<unsigned long long>(sim.steps()), sim.solver().readRebuilds());
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

class SphIntegratorTest : public GpuTest, public ::testing::WithParamInterface<sim::Integrator> {};

TEST_P(SphIntegratorTest, FreeBlobConservesMomentum) {
  scene::Scene scene = scene::parseScene(kBlob, "momentum_test");
  scene.sph.integrator = GetParam();
  // With RK2 the blob also runs SPS turbulence: its pair terms are antisymmetric too.
  scene.sph.sps = GetParam() == sim::Integrator::Rk2Midpoint;
  sim::Simulation sim(ctx(), scene);
  // Stir it: give every particle a different velocity so internal forces are far from zero.
  {
    auto vel = sim.store().readVelocities();
    const auto ids = sim.store().readIds();
    for (std::size_t i = 0; i < vel.size(); ++i) {
      const float s = float(ids[i] % 7) - 3.0f, t = float(ids[i] % 5) - 2.0f;
      vel[i] += glm::vec4(0.1f * s, 0.1f * t, -0.05f * s * t, 0.0f);
    }
    sim.store().live().velocities.upload(vel);
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

INSTANTIATE_TEST_SUITE_P(Integrators, SphIntegratorTest,
                         ::testing::Values(sim::Integrator::SymplecticEuler, sim::Integrator::Rk2Midpoint),
                         [](const auto& param) {
                           return param.param == sim::Integrator::Rk2Midpoint ? "rk2_midpoint" : "symplectic_euler";
                         });

// With either density method (the continuity density reads its neighbours' carried densities,
// never ones this step has written).
TEST_F(SphPhysicsTest, TwoRunsAreBitIdentical) {
  for (const sim::DensityMethod method : {sim::DensityMethod::Summation, sim::DensityMethod::Continuity}) {
    SCOPED_TRACE(method == sim::DensityMethod::Continuity ? "continuity density" : "summation density");
    scene::Scene scene = scene::parseScene(kColumn, "column_test");
    scene.sph.densityMethod = method;
    std::vector<glm::vec4> first;
    for (int run = 0; run < 2; ++run) {
      sim::Simulation sim(ctx(), scene);
      sim::RunOptions opt;
      opt.steps = 300;
      sim.run(opt);
      const auto s = sim.snapshot();
      std::vector<glm::vec4> state = s.positions;
      state.insert(state.end(), s.velocities.begin(), s.velocities.end());
      for (std::size_t k = 0; k + 1 < s.densityPressure.size(); k += 2) {
        state.emplace_back(s.densityPressure[k], s.densityPressure[k + 1]);
      }
      if (run == 0) {
        first = state;
      } else {
        ASSERT_EQ(state.size(), first.size());
        EXPECT_EQ(0, std::memcmp(state.data(), first.data(), state.size() * sizeof(glm::vec4)))
            << "positions/velocities/densities differ between two runs of the same scene";
      }
    }
  }
}

// A device that allows only one workgroup along x (forced low): every dispatch folds into
// y, the boundary's active list (whose counts the GPU appends) included, and the run is
// bit-identical to the one on the device's own limits.
TEST_F(SphPhysicsTest, FoldedDispatchesGiveBitIdenticalRuns) {
  // The dam break: its active boundary list spans several workgroups.
  const scene::Scene scene = scene::loadScene(std::string(HEMO_SOURCE_DIR) + "/scenes/dam_break.json");
  auto run = [&](gpu::Context& context) {
    sim::Simulation sim(context, scene);
    sim::RunOptions opt;
    opt.steps = 100;
    sim.run(opt);
    // The active list's counts, which the GPU appends, fold at the context's limit too.
    const auto args = sim.solver().boundaryActiveArgs().readback<std::uint32_t>(4);
    const std::uint32_t maxX = context.limits().maxComputeWorkGroupCount[0];
    EXPECT_LE(args[0], maxX);
    EXPECT_GE(std::uint64_t(args[0]) * args[1] * 256, args[3]) << "the groups cover the list";
    if (maxX == 1) {
      EXPECT_GT(args[1], 1u) << "a list long enough to fold: " << args[3] << " entries";
    }
    return positionsAndVelocities(sim);
  };
  gpu::ContextOptions options;
  options.validation = true;
  options.limits.maxComputeWorkGroupCountX = 1;
  gpu::Context narrow(options);
  const auto wide = run(ctx());
  const auto folded = run(narrow);
  ASSERT_EQ(wide.size(), folded.size());
  EXPECT_EQ(0, std::memcmp(wide.data(), folded.data(), wide.size() * sizeof(glm::vec4)))
      << "the run with folded dispatches differs";
  for (const auto& m : narrow.takeValidationMessages()) ADD_FAILURE() << m;
}

// A device whose buffer limits hold only part of the neighbour list (a storage buffer's range
// or a texel buffer's elements, forced low): the list and the interacting pairs split into
// pages of 4,096 slots, the passes that walk them run once per page (the boundary pass over
// each page's own active list), and the run is bit-identical to the one with each list in one
// buffer: with the contiguous layout (four entries a texel) and the interleaved one (a GPU's:
// the page's slots are the stride), and with the SPS term's pass. Pages of 1,024 slots (about
// 20 of them) record more dispatches in the rebuild's gated region than a fixed share of the
// gate held, as a GPU's 16M particles did.
TEST_F(SphPhysicsTest, ListSplitIntoPagesGivesBitIdenticalRuns) {
  struct Case {
    const char* name;
    sim::ListLayout layout;
    bool sps;
    gpu::LimitOverrides limits;
    std::uint32_t pageSlots;
  };
  // Each holds the lists of 4,096 slots of 128 entries and a little more: a storage buffer's
  // bytes, or the texels as the pair passes read them (one entry each when interleaved, four
  // when contiguous).
  gpu::LimitOverrides storage, texels, texels4, storage1k;
  storage.maxStorageBufferRange = 4096 * 128 * 4 + 4096;
  storage1k.maxStorageBufferRange = 1024 * 128 * 4 + 4096;
  texels.maxTexelBufferElements = 4096 * 128 + 1024;
  texels4.maxTexelBufferElements = 4096 * 128 / 4 + 256;
  const Case cases[] = {{"contiguous, storage range", sim::ListLayout::Contiguous, false, storage, 4096},
                        {"interleaved, texel elements", sim::ListLayout::Interleaved, false, texels, 4096},
                        {"contiguous with SPS, texel elements", sim::ListLayout::Contiguous, true, texels4, 4096},
                        {"interleaved, pages of 1,024 slots", sim::ListLayout::Interleaved, false, storage1k, 1024}};
  for (const Case& c : cases) {
    SCOPED_TRACE(c.name);
    scene::Scene scene = scene::loadScene(std::string(HEMO_SOURCE_DIR) + "/scenes/dam_break.json");
    ASSERT_EQ(scene.sph.neighbourCapacity, 128u);
    scene.sph.listLayout = c.layout;
    scene.sph.sps = c.sps;
    auto run = [&](gpu::Context& context, std::uint32_t expectPages) {
      sim::Simulation sim(context, scene);
      EXPECT_EQ(sim.solver().listPages(), expectPages);
      EXPECT_FALSE(sim.solver().usesClusters());
      sim::RunOptions opt;
      opt.steps = 300;
      sim.run(opt);
      EXPECT_GE(sim.solver().readRebuilds(), 2u) << "the split lists were rebuilt";
      return std::make_pair(positionsAndVelocities(sim), sim.time());
    };
    gpu::ContextOptions options;
    options.validation = true;
    options.limits = c.limits;
    gpu::Context small(options);
    const auto whole = run(ctx(), 1u);
    const std::uint32_t slots = sim::Simulation(ctx(), scene).store().capacity();
    const std::uint32_t pages = (slots + c.pageSlots - 1) / c.pageSlots;
    const auto split = run(small, pages);
    ASSERT_GE(pages, c.pageSlots == 1024 ? 13u : 3u) << "pages enough to test: " << slots << " slots";
    ASSERT_EQ(whole.first.size(), split.first.size());
    EXPECT_EQ(whole.second, split.second) << "the same simulated time";
    EXPECT_EQ(0, std::memcmp(whole.first.data(), split.first.data(), whole.first.size() * sizeof(glm::vec4)))
        << "the run with the list in pages differs";
    for (const auto& m : small.takeValidationMessages()) ADD_FAILURE() << m;
  }
}

// The aneurysm with its list split into pages (a storage buffer's range forced to hold 2,048
// slots' lists): the wall's reaction pass runs once per page too, and the run, springs and
// ruptures included, is bit-identical to the one with the list in one buffer.
TEST_F(SphPhysicsTest, VesselWithItsListInPagesGivesBitIdenticalRuns) {
  scene::Scene scene = scene::loadScene(std::string(HEMO_SOURCE_DIR) + "/scenes/aneurysm.json");
  scene.sph.listLayout = sim::ListLayout::Contiguous;  // (a split list never walks clusters)
  auto run = [&](gpu::Context& context) {
    sim::Simulation sim(context, scene);
    EXPECT_FALSE(sim.solver().usesClusters());
    sim::RunOptions opt;
    opt.steps = 150;
    sim.run(opt);
    return std::make_tuple(positionsAndVelocities(sim), sim.solver().listPages(), sim.time());
  };
  gpu::ContextOptions options;
  options.validation = true;
  options.limits.maxStorageBufferRange = 2048 * scene.sph.neighbourCapacity * 4 + 4096;
  gpu::Context small(options);
  const auto [whole, wholePages, wholeTime] = run(ctx());
  const auto [split, splitPages, splitTime] = run(small);
  EXPECT_EQ(wholePages, 1u);
  EXPECT_GE(splitPages, 3u);
  EXPECT_EQ(wholeTime, splitTime);
  ASSERT_EQ(whole.size(), split.size());
  EXPECT_EQ(0, std::memcmp(whole.data(), split.data(), whole.size() * sizeof(glm::vec4)))
      << "the vessel's run with the list in pages differs";
  for (const auto& m : small.takeValidationMessages()) ADD_FAILURE() << m;
}

// Without a list (NeighbourSearch::Cells) every pair pass walks the grid cells around each
// particle's position at the last build, in the order the list build takes them: the run is
// bit-identical to the one that reads the list, with summation and continuity density, with
// the SPS term, with RK2, and on both layouts of the list it replaces; and it allocates
// neither the list nor the interacting pairs.
TEST_F(SphPhysicsTest, CellWalkGivesTheListsRunsBitForBit) {
  struct Case {
    const char* name;
    sim::ListLayout layout;
    bool sps;
    bool continuityRk2;
  };
  const Case cases[] = {{"summation, contiguous", sim::ListLayout::Contiguous, false, false},
                        {"summation, interleaved", sim::ListLayout::Interleaved, false, false},
                        {"SPS", sim::ListLayout::Contiguous, true, false},
                        {"continuity density, RK2", sim::ListLayout::Contiguous, false, true}};
  for (const Case& c : cases) {
    SCOPED_TRACE(c.name);
    scene::Scene scene = scene::loadScene(std::string(HEMO_SOURCE_DIR) + "/scenes/dam_break.json");
    scene.sph.listLayout = c.layout;
    scene.sph.sps = c.sps;
    scene.sph.listSkin = 0.03f;  // a thin skin: rebuilds within the few steps the test runs
    if (c.continuityRk2) {
      scene.sph.densityMethod = sim::DensityMethod::Continuity;
      scene.sph.integrator = sim::Integrator::Rk2Midpoint;
    }
    auto run = [&](sim::NeighbourSearch search) {
      scene.sph.neighbourSearch = search;
      ctx().resetPeakDeviceMemoryBytes();
      sim::Simulation sim(ctx(), scene);
      EXPECT_EQ(sim.solver().walksCells(), search == sim::NeighbourSearch::Cells);
      EXPECT_FALSE(sim.solver().usesClusters());
      sim::RunOptions opt;
      opt.steps = 100;
      sim.run(opt);
      EXPECT_GE(sim.solver().readRebuilds(), 2u) << "the grid was rebuilt";
      return std::make_tuple(positionsAndVelocities(sim), sim.time(), ctx().peakDeviceMemoryBytes());
    };
    const auto [list, listTime, listBytes] = run(sim::NeighbourSearch::List);
    const auto [cells, cellsTime, cellsBytes] = run(sim::NeighbourSearch::Cells);
    ASSERT_EQ(list.size(), cells.size());
    EXPECT_EQ(listTime, cellsTime) << "the same simulated time";
    EXPECT_EQ(0, std::memcmp(list.data(), cells.data(), list.size() * sizeof(glm::vec4)))
        << "the run that walks cells differs from the one that reads the list";
    // The list and the pairs: 2 x 4 B x 128 entries a slot.
    EXPECT_GE(listBytes - cellsBytes, std::uint64_t(list.size() / 2) * 1024u) << "no list allocated";
  }
}

// The aneurysm without a list: the wall's reaction pass and the boundary pass's active list
// walk cells too, and the run, springs and ruptures included, is bit-identical to the list's.
TEST_F(SphPhysicsTest, VesselWalkingCellsGivesTheListsRunBitForBit) {
  scene::Scene scene = scene::loadScene(std::string(HEMO_SOURCE_DIR) + "/scenes/aneurysm.json");
  scene.sph.listLayout = sim::ListLayout::Contiguous;
  auto run = [&](sim::NeighbourSearch search) {
    scene.sph.neighbourSearch = search;
    sim::Simulation sim(ctx(), scene);
    EXPECT_EQ(sim.solver().walksCells(), search == sim::NeighbourSearch::Cells);
    sim::RunOptions opt;
    opt.steps = 150;
    sim.run(opt);
    return std::make_pair(positionsAndVelocities(sim), sim.time());
  };
  const auto [list, listTime] = run(sim::NeighbourSearch::List);
  const auto [cells, cellsTime] = run(sim::NeighbourSearch::Cells);
  EXPECT_EQ(listTime, cellsTime);
  ASSERT_EQ(list.size(), cells.size());
  EXPECT_EQ(0, std::memcmp(list.data(), cells.data(), list.size() * sizeof(glm::vec4)))
      << "the vessel's run walking cells differs from the list's";
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
  sim.store().live().velocities.upload(vel);
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

// A blow-up that stays finite (one particle at 1e8 m/s) shrinks the step until the clock no
// longer advances: the run stops with the step, the time and the limit instead of running on.
TEST_F(SphPhysicsTest, CollapsedTimeStepStopsTheRun) {
  scene::Scene scene = scene::parseScene(kColumn, "column_test");
  for (const double minStep : {0.0, 1.0e-9}) {
    SCOPED_TRACE(testing::Message() << "time.min_dt_s " << minStep);
    scene.minTimeStep = minStep;
    sim::Simulation sim(ctx(), scene);
    const double own = sim.designTimeStep();
    EXPECT_GT(own, 0.0);
    EXPECT_LE(own, double(sim.solver().params().dtMax));
    EXPECT_DOUBLE_EQ(sim.minTimeStep(), minStep > 0.0 ? minStep : 1.0e-4 * own);
    sim::RunOptions opt;
    opt.steps = 5;
    sim.run(opt);  // a healthy start stays above the limit
    auto vel = sim.store().readVelocities();
    const auto ids = sim.store().readIds();
    for (std::size_t i = 0; i < ids.size(); ++i) {
      if (ids[i] == 42) vel[i].x = 1.0e8f;
    }
    sim.store().live().velocities.upload(vel);
    opt.steps = 3 * scene.stepsPerBatch;
    try {
      sim.run(opt);
      FAIL() << "the run should have stopped";
    } catch (const sim::SimulationError& e) {
      const std::string m = e.what();
      EXPECT_NE(m.find("time step collapsed to "), std::string::npos) << m;
      EXPECT_NE(m.find("at step 5 (t = "), std::string::npos) << m;
      EXPECT_NE(m.find("time.min_dt_s"), std::string::npos) << m;
      EXPECT_EQ(m.find("of the scene's own step") != std::string::npos, minStep == 0.0) << m;
    }
  }
}

// ---- Hard cases: finite state, bounded speed, nothing lost without being counted ----------

void expectHealthy(sim::Simulation& sim, float speedBound) {
  const sim::Snapshot s = sim.snapshot();
  for (std::uint32_t i = 0; i < sim.fluidParticles(); ++i) {
    const glm::vec3 x(s.positions[i]), v(s.velocities[i]);
    ASSERT_TRUE(std::isfinite(x.x) && std::isfinite(x.y) && std::isfinite(x.z)) << "particle " << i;
    ASSERT_LT(glm::length(v), speedBound) << "particle " << i << " at speed " << glm::length(v);
  }
}

TEST_F(SphPhysicsTest, SingleParticleFallsFreely) {
  const scene::Scene scene = scene::parseScene(R"({
    "scene": "single",
    "particles": { "spacing_m": 0.01 },
    "fluid": { "expected_max_speed_m_s": 1.0, "blocks": [ { "min_m": [0, 0, 0.5], "max_m": [0.01, 0.01, 0.51] } ] },
    "time": { "max_dt_s": 0.0005 },
    "domain": { "min_m": [-0.1, -0.1, -0.1], "max_m": [0.1, 0.1, 0.6] }
  })", "single");
  sim::Simulation sim(ctx(), scene);
  ASSERT_EQ(sim.fluidParticles(), 1u);
  sim::RunOptions opt;
  opt.until = 0.2;
  sim.run(opt);
  const sim::Snapshot s = sim.snapshot();
  const double t = sim.time(), z0 = 0.505, g = 9.81;
  // Symplectic Euler gives v = -g t exactly and falls ahead of the parabola by
  // g sum(t_k dt_k) - g t^2 / 2 <= g t dt_max / 2, dt_max = C_a h / c0 (the step at rest).
  const double exact = z0 - 0.5 * g * t * t;
  const double dtMax = scene.sph.cflAcoustic * scene.sph.h() / scene.sph.soundSpeed;
  EXPECT_LT(s.positions[0].z, exact);
  EXPECT_GT(s.positions[0].z, exact - 0.5 * g * t * dtMax - 1e-6);
  EXPECT_NEAR(s.velocities[0].z, -g * t, 1e-4);
}

// The midpoint rule integrates constant gravity exactly: z = z0 - g t^2 / 2.
TEST_F(SphPhysicsTest, SingleParticleFallsExactlyWithRk2) {
  scene::Scene scene = scene::parseScene(R"({
    "scene": "single_rk2",
    "particles": { "spacing_m": 0.01 },
    "fluid": { "expected_max_speed_m_s": 1.0, "blocks": [ { "min_m": [0, 0, 0.5], "max_m": [0.01, 0.01, 0.51] } ] },
    "time": { "integrator": "rk2_midpoint", "max_dt_s": 0.0005 },
    "domain": { "min_m": [-0.1, -0.1, -0.1], "max_m": [0.1, 0.1, 0.6] }
  })", "single_rk2");
  ASSERT_EQ(scene.sph.integrator, sim::Integrator::Rk2Midpoint);
  sim::Simulation sim(ctx(), scene);
  sim::RunOptions opt;
  opt.until = 0.2;
  sim.run(opt);
  const sim::Snapshot s = sim.snapshot();
  const double t = sim.time(), g = 9.81;
  EXPECT_NEAR(s.positions[0].z, 0.505 - 0.5 * g * t * t, 2e-6);
  EXPECT_NEAR(s.velocities[0].z, -g * t, 1e-4);
}

const char* kBox = R"({
  "scene": "hard_case",
  "particles": { "spacing_m": 0.01 },
  "fluid": { "expected_max_speed_m_s": 1.0,
             "blocks": [ { "min_m": [0.02, 0.02, 0.0], "max_m": [0.08, 0.06, 0.06], "velocity_m_s": [0, 0, 0] } ] },
  "boundary": { "tanks": [ { "min_m": [0, 0, 0], "max_m": [0.2, 0.08, 0.12], "layers": 3, "open_top": false } ] },
  "time": { "steps_per_batch": 50 },
  "domain": { "min_m": [-0.05, -0.05, -0.05], "max_m": [0.25, 0.13, 0.17] }
})";

// Moves particles before a run: edit(id, kind, position) may change the position.
template <class Edit>
void editPositions(sim::Simulation& sim, Edit edit) {
  auto pos = sim.store().readPositions();
  const auto vel = sim.store().readVelocities();
  const auto ids = sim.store().readIds();
  for (std::size_t i = 0; i < pos.size(); ++i) edit(ids[i], vel[i].w, pos[i]);
  sim.store().live().positions.upload(pos);
}

// Runs `steps` steps of a hard case; it must stay finite, slower than `speedBound`, and lose
// nothing from the closed tank.
void expectSurvives(sim::Simulation& sim, std::uint64_t steps, float speedBound) {
  sim::RunOptions opt;
  opt.steps = steps;
  EXPECT_NO_THROW(sim.run(opt));
  expectHealthy(sim, speedBound);
  EXPECT_EQ(sim.escapedParticles(), 0u);
}

TEST_F(SphPhysicsTest, TwoParticlesOnTopOfEachOther) {
  sim::Simulation sim(ctx(), scene::parseScene(kBox, "hard_case"));
  glm::vec4 target = sim.snapshot().positions[5];
  editPositions(sim, [&](std::uint32_t id, float, glm::vec4& p) {
    if (id == 6) p = target;  // zero distance to particle 5
  });
  expectSurvives(sim, 300, 5.0f);
}

TEST_F(SphPhysicsTest, FluidStartedTwentyPercentCompressed) {
  sim::Simulation sim(ctx(), scene::parseScene(kBox, "hard_case"));
  const float s = std::cbrt(0.8f);  // 20% less volume
  const glm::vec3 centre(0.05f, 0.04f, 0.0f);
  editPositions(sim, [&](std::uint32_t, float kind, glm::vec4& p) {
    if (kind == 0.0f) p = glm::vec4(centre + (glm::vec3(p) - centre) * s, p.w);
  });
  // Bounded by the speed of sound of the compressed state (c0 = 10 m/s, rho/rho0 = 1.25).
  expectSurvives(sim, 500, 20.0f);
}

TEST_F(SphPhysicsTest, JetAtThreeTimesTheDesignSpeedHitsAWall) {
  scene::Scene scene = scene::parseScene(kBox, "hard_case");
  scene.blocks[0].velocity = glm::vec3(3.0f * scene.expectedMaxSpeed, 0.0f, 0.0f);  // 3 m/s into the +x wall
  sim::Simulation sim(ctx(), scene);
  sim::RunOptions opt;
  opt.until = 0.08;  // reaches the wall at 0.04 s
  EXPECT_NO_THROW(sim.run(opt));
  expectHealthy(sim, 30.0f);
  EXPECT_EQ(sim.escapedParticles(), 0u) << "the closed tank must hold the jet";
}

}  // namespace
}  // namespace hemo::test

namespace hemo::test {
namespace {

// scenes/dam_break.json at half its resolution: dp = a/10 (a = 0.05715 m), in a periodic slab
// 9 spacings thick (three neighbour-list radii), 1,800 fluid particles.
scene::Scene coarseDamBreak() {
  scene::Scene scene = scene::loadScene(std::string(HEMO_SOURCE_DIR) + "/scenes/dam_break.json");
  scene.sph.spacing = float(0.05715 / 10.0);
  return scene::withSlabThickness(scene, 1, 9);
}

// The dam break of scenes/dam_break.json at half its resolution (dp = a/10, 1,800 fluid
// particles). Front = the largest x of fluid particles within 2 dp of the floor. The
// experiment's clock includes the gate's opening, so the comparison uses a gate-release
// offset of dT = 0.15 (8.1 ms): Z_sim(T) against Z_MM(T + dT). Measured mean |dZ| over
// T in [0, 3] with it: 0.043 (0.148 without; 0.21 without / 0.05 with dT = 0.2 at dp = a/20).
TEST_F(SphPhysicsTest, DamBreakFrontFollowsMartinAndMoyce) {
  const scene::Scene scene = coarseDamBreak();
  const double a = 0.05715, g = 9.81, offset = 0.15;
  sim::Simulation sim(ctx(), scene);
  const auto& reference = reference::martinMoyceN2();
  ASSERT_GT(reference.size(), 10u);
  const double timeScale = std::sqrt(a / (2.0 * g));  // t = T * timeScale
  double sumError = 0.0;
  int samples = 0;
  for (double T = 0.25; T <= 3.0 - offset + 1e-9; T += 0.25) {
    sim::RunOptions opt;
    opt.until = T * timeScale;
    sim.run(opt);
    const sim::Snapshot s = sim.snapshot();
    const double front = sim::surgeFront(s, sim.fluidParticles(), 2.0f * scene.sph.spacing);
    const double error = std::abs(front / a - reference::interpolateTable(reference, T + offset));
    sumError += error;
    ++samples;
  }
  const double mean = sumError / samples;
  RecordProperty("mean_abs_dZ", std::to_string(mean));
  std::printf("dam break: mean |dZ| against Martin & Moyce %.4f over %d samples\n", mean, samples);
  EXPECT_LT(mean, 0.15) << "mean |dZ| against Martin & Moyce over " << samples << " samples";
}

}  // namespace
}  // namespace hemo::test

namespace hemo::test {
namespace {

// Hard case: the largest CFL numbers the scene format accepts (1.0 for both the acoustic and
// the force condition), on the coarse dam break, for both integrators: finite, speeds bounded
// (the surge runs at about 2 sqrt(g a) = 1.5 m/s), nothing leaves the tank.
TEST_P(SphIntegratorTest, DamBreakAtTheLargestAcceptedCfl) {
  scene::Scene scene = coarseDamBreak();
  scene.sph.cflAcoustic = 1.0f;
  scene.sph.cflForce = 1.0f;
  scene.sph.integrator = GetParam();
  sim::Simulation sim(ctx(), scene);
  sim::RunOptions opt;
  opt.until = 0.1;
  EXPECT_NO_THROW(sim.run(opt));
  expectHealthy(sim, 6.0f);
  EXPECT_EQ(sim.escapedParticles(), 0u);
}

// What a step records, the latency a GPU pays at small N: every step after the first records
// the same dispatches and barriers, whether or not the GPU rebuilds the neighbour list in it
// (the rebuild is gated, recorded every step); the RK2 midpoint records the density and force
// passes twice, and a wall adds its stage to each force evaluation.
TEST_F(SphPhysicsTest, EveryStepRecordsTheSameCommands) {
  struct Counts {
    double dispatches, barriers;
  };
  // per step over steps 2-11 and 12-71 (the first step also arms the gate and marks tiles)
  // (DFSPH: `depth` gated regions recorded per solve, RunOptions::recordedSolveIterations)
  auto steady = [&](const scene::Scene& scene, std::optional<std::uint32_t> depth = std::nullopt) {
    sim::Simulation sim(ctx(), scene);
    // the totals recorded after `steps` steps in all
    auto runTo = [&](std::uint64_t steps) {
      sim::RunOptions opt;
      opt.steps = steps - sim.steps();
      opt.recordedSolveIterations = depth;
      sim.run(opt);
      return Counts{std::round(sim.dispatchesPerStep() * double(steps)), std::round(sim.barriersPerStep() * double(steps))};
    };
    const Counts first = runTo(1), t11 = runTo(11), t71 = runTo(71);
    const Counts a{(t11.dispatches - first.dispatches) / 10, (t11.barriers - first.barriers) / 10};
    const Counts b{(t71.dispatches - t11.dispatches) / 60, (t71.barriers - t11.barriers) / 60};
    EXPECT_GE(sim.solver().readRebuilds(), 2u) << "steps with and without a rebuild";
    EXPECT_EQ(a.dispatches, b.dispatches);
    EXPECT_EQ(a.barriers, b.barriers);
    EXPECT_EQ(a.dispatches, std::round(a.dispatches)) << "the same whole number every step";
    EXPECT_GE(first.dispatches, a.dispatches);
    return a;
  };
  scene::Scene dam = scene::loadScene(std::string(HEMO_SOURCE_DIR) + "/scenes/dam_break.json");
  dam.sph.listSkin = 0.01f;
  dam.sph.listLayout = sim::ListLayout::Contiguous;
  const Counts euler = steady(dam);
  dam.sph.integrator = sim::Integrator::Rk2Midpoint;
  const Counts rk2 = steady(dam);
  EXPECT_GE(rk2.dispatches, euler.dispatches + 4) << "density, boundary pressure, forces and dt again";
  EXPECT_GT(rk2.barriers, euler.barriers);
  scene::Scene vessel = scene::loadScene(std::string(HEMO_SOURCE_DIR) + "/scenes/aneurysm.json");
  vessel.sph.listLayout = sim::ListLayout::Contiguous;
  vessel.sph.listSkin = 0.01f;
  const Counts wall = steady(vessel);
  EXPECT_GE(wall.dispatches, euler.dispatches + 1) << "the wall stage";
  // DFSPH records each solve's first prediction and reduction and, recorded to its cap, the
  // cap's worth of gated (correction, prediction) pairs with their reductions, for both solves
  // (interface/sph.h; a run records fewer where it can, DfsphTest.RecordedIterationsDoNotChangeTheResult)
  dam.sph.integrator = sim::Integrator::SymplecticEuler;
  dam.sph.pressureSolver = sim::PressureSolver::Dfsph;
  dam.sph.solverMaxIterations = 5;
  const Counts dfsph = steady(dam, 5u);
  EXPECT_EQ(dfsph.dispatches, euler.dispatches + 2 * (2 + 3 * 5));
  std::printf("per step: symplectic Euler %.0f dispatches %.0f barriers, RK2 %.0f %.0f, with a wall %.0f %.0f, DFSPH capped at 5 %.0f %.0f\n",
              euler.dispatches, euler.barriers, rk2.dispatches, rk2.barriers, wall.dispatches, wall.barriers,
              dfsph.dispatches, dfsph.barriers);
}

}  // namespace
}  // namespace hemo::test
