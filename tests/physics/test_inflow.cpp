// Issue 4: the driven inflow of a periodic vessel (hemo/sim/inflow.hpp). The zone's fluid
// moves along the axis with the CPU reference's velocity (pulsatile waveform included); the flux it sets is
// the flux downstream, with the particle count and the mass unchanged (and the per-step
// statistics match the state read back); with the lumen's
// supply on, a stretching tube keeps its fluid at the rest density.
#include "gpu_test.hpp"
#include "hemo/scene/build.hpp"
#include "interface/sph.h"
#include "hemo/sim/simulation.hpp"

#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <cstdio>
#include <nlohmann/json.hpp>
#include <string>

namespace hemo::test {
namespace {

class InflowTest : public GpuTest {};

// A periodic tube of radius 4 dp (dp 0.5 mm), 24 dp long, with a 6 dp driven zone.
nlohmann::json tubeScene() {
  return nlohmann::json::parse(R"({
    "scene": "inflow_test",
    "particles": { "spacing_m": 5e-4 },
    "fluid": { "density_kg_m3": 1060.0, "viscosity_pa_s": 0.0035, "expected_max_speed_m_s": 0.5,
               "background_pressure_Pa": 200.0, "background_pressure_ramp_s": 0.005 },
    "vessel": { "shape": "tube", "length_m": 0.012, "radius_m": 0.002, "point_mass_kg": 2e-5,
                "stiffness_N_m": 200.0, "damping_N_s_m": 0.01,
                "inflow": { "profile": "parabolic", "mean_speed_m_s": 0.1, "zone_length_m": 0.003,
                            "pulse_period_s": 0.02, "waveform": [1.0, 1.8, 0.6, 1.2], "ramp_s": 0.005 } },
    "forces": { "gravity_m_s2": [0, 0, 0] },
    "time": { "steps_per_batch": 50 },
    "domain": { "min_m": [0.0, -0.004, -0.004], "max_m": [0.012, 0.004, 0.004], "periodic": ["x"] }
  })");
}

TEST_F(InflowTest, ZoneFollowsTheWaveformAndSetsTheFlux) {
  const scene::Scene scene = scene::parseScene(tubeScene().dump(), "inflow_test");
  const sim::Inflow& inflow = *scene.vessel->inflow;
  sim::Simulation sim(ctx(), scene);
  double massBefore = 0.0;
  const sim::Snapshot first = sim.snapshot();
  for (std::uint32_t i = 0; i < first.positions.size(); ++i) massBefore += first.velocities[i].w == 0.0f ? first.positions[i].w : 0.0;
  const float dp = scene.sph.spacing;
  double worst = 0.0;
  std::uint32_t checked = 0;
  sim::RunOptions opt;
  opt.steps = 50;
  // The per-step statistics come along (hemo/sim/stats.hpp): one row per step, the last of
  // each batch checked against the state read back.
  sim.enableStepStats(1);
  std::vector<sim::StepStatsRow> rows;
  opt.onStepStats = [&](const std::vector<sim::StepStatsRow>& batch) { rows = batch; };
  for (int batch = 0; batch < 12; ++batch) {
    sim.run(opt);
    {
      ASSERT_EQ(rows.size(), 50u);
      const sim::Snapshot s = sim.snapshot();
      double speed = 0.0, error = 0.0;
      for (std::uint32_t i = 0; i < s.positions.size(); ++i) {
        if (s.velocities[i].w != 0.0f) continue;
        speed = std::max(speed, double(glm::length(glm::vec3(s.velocities[i]))));
        error = std::max(error, std::abs(double(s.densityPressure[i].x) / scene.sph.restDensity - 1.0));
      }
      const sim::StepStatsRow& last = rows.back();
      EXPECT_EQ(last.steps, sim.steps());
      EXPECT_NEAR(last.time, sim.time(), 1e-6 * sim.time());
      EXPECT_NEAR(last.maxSpeed, speed, 1e-6 * speed);
      EXPECT_NEAR(last.maxDensityError, error, 1e-5);
      EXPECT_EQ(last.brokenSprings, sim.brokenSprings());
      for (std::size_t k = 1; k < rows.size(); ++k) EXPECT_EQ(rows[k].steps, rows[k - 1].steps + 1);
    }
    const sim::SphClock clock = sim.solver().readClock();
    const double tStep = clock.time - clock.lastDt;  // the zone's velocity is set at the start of the step
    const sim::Snapshot s = sim.snapshot();
    for (std::uint32_t i = 0; i < s.positions.size(); ++i) {
      const glm::vec4 x = s.positions[i], v = s.velocities[i];
      if (v.w != 0.0f || x.x < inflow.zoneStart + dp || x.x > inflow.zoneEnd - dp) continue;  // well inside the zone
      // Across the section the particle moved freely this step: its radius at the start of
      // the step (where the zone set its axial velocity) is x - v dt (symplectic Euler).
      const double r = std::hypot(double(x.y) - v.y * clock.lastDt - inflow.centreY, double(x.z) - v.z * clock.lastDt - inflow.centreZ);
      if (r >= inflow.radius) continue;
      const double expect = inflow.axialVelocity(tStep, r);
      worst = std::max(worst, std::abs(v.x - expect) / (2.0 * inflow.meanSpeed * 1.8));
      ++checked;
    }
  }
  EXPECT_GT(checked, 1000u);
  EXPECT_LT(worst, 1e-5) << "the zone's velocity differs from the reference (relative to the peak)";
  const sim::Snapshot s = sim.snapshot();
  double massAfter = 0.0;
  for (std::uint32_t i = 0; i < s.positions.size(); ++i) massAfter += s.velocities[i].w == 0.0f ? s.positions[i].w : 0.0;
  EXPECT_EQ(massAfter, massBefore) << "the pump changed the fluid's mass";
  EXPECT_EQ(sim.escapedParticles(), 0u);
  std::printf("zone velocity vs reference: %u samples, worst |dv| / peak = %.2e\n", checked, worst);
}

TEST_F(InflowTest, FluxDownstreamMatchesTheZone) {
  nlohmann::json j = tubeScene();
  auto& in = j["vessel"]["inflow"];
  in.erase("waveform");
  in.erase("pulse_period_s");
  in["ramp_s"] = 0.01;
  const scene::Scene scene = scene::parseScene(j.dump(), "inflow_test");
  const sim::Inflow& inflow = *scene.vessel->inflow;
  sim::Simulation sim(ctx(), scene);
  sim::RunOptions opt;
  opt.until = 0.03;
  sim.run(opt);
  // Mass conservation along the tube: the fluid mass that crosses the zone's exit plane and
  // the mass that crosses a plane halfway down the rest of the tube agree (they differ by the
  // change of the mass between the planes, which the fluid's compressibility and the wall's
// stiffness keep small),
  // and match the prescribed flux rho0 U A. Crossings are counted between snapshots 20 steps
  // apart (a particle moves far less than a spacing in between), by particle id.
  const double exitPlane = inflow.zoneEnd, midPlane = 0.5 * (inflow.zoneEnd + scene.vessel->length);
  const double period = scene.vessel->length;
  auto crossing = [&](double x0, double x1, double plane) {  // +1 / -1 / 0, x1 possibly across the seam
    double d = x1 - x0;
    d -= period * std::round(d / period);
    const double xa = x0, xb = x0 + d;
    auto side = [&](double x) { return std::floor((x - plane) / period); };
    return side(xb) - side(xa);
  };
  // Fluid mass between the two planes (downstream of the exit, upstream of the middle).
  auto between = [&](const sim::Snapshot& s) {
    double m = 0.0;
    for (std::uint32_t i = 0; i < s.positions.size(); ++i) {
      const double x = s.positions[i].x;
      if (s.velocities[i].w == 0.0f && x >= exitPlane && x < midPlane) m += s.positions[i].w;
    }
    return m;
  };
  // The flux through the exit plane also as a slab average, (1 / L) sum m v_x over the
  // particles within L / 2 of the plane, integrated over time (trapezoids between the
  // snapshots): a smooth measure, where the crossings count whole particles (about 175 in the
  // window) and move by a few when rounding-level differences shift the lattice's layers.
  const double slab = 2.0 * scene.sph.spacing;
  auto slabFlux = [&](const sim::Snapshot& s) {
    double q = 0.0;
    for (std::uint32_t i = 0; i < s.positions.size(); ++i) {
      double d = s.positions[i].x - exitPlane;
      d -= period * std::round(d / period);
      if (s.velocities[i].w == 0.0f && std::abs(d) < 0.5 * slab) q += s.positions[i].w * s.velocities[i].x;
    }
    return q / slab;
  };
  sim::Snapshot before = sim.snapshot();
  const double t0 = sim.time(), storedBefore = between(before);
  double slabMass = 0.0, tBefore = t0, qBefore = slabFlux(before);
  double throughExit = 0.0, throughMid = 0.0, zoneDensity = 0.0;
  std::uint32_t zoneSamples = 0;
  opt.until.reset();
  opt.steps = 20;
  for (int k = 0; k < 100; ++k) {
    sim.run(opt);
    const sim::Snapshot after = sim.snapshot();
    for (std::uint32_t i = 0; i < after.positions.size(); ++i) {
      if (after.velocities[i].w != 0.0f) continue;
      const double m = after.positions[i].w;
      throughExit += m * crossing(before.positions[i].x, after.positions[i].x, exitPlane);
      throughMid += m * crossing(before.positions[i].x, after.positions[i].x, midPlane);
      if (after.positions[i].x >= inflow.zoneStart && after.positions[i].x < inflow.zoneEnd) {
        zoneDensity += after.densityPressure[i].x;
        ++zoneSamples;
      }
    }
    const double tAfter = sim.time(), qAfter = slabFlux(after);
    slabMass += 0.5 * (qBefore + qAfter) * (tAfter - tBefore);
    tBefore = tAfter;
    qBefore = qAfter;
    before = after;
  }
  const double seconds = sim.time() - t0;
  const double stored = between(before) - storedBefore;
  // The pump sets the velocity; the mass it moves follows the zone's density (a little below
  // rho0: the fluid next to the wall reads thin).
  zoneDensity /= std::max(zoneSamples, 1u);
  const double prescribed = zoneDensity * inflow.meanSpeed * std::numbers::pi * inflow.radius * inflow.radius * seconds;
  ASSERT_GT(throughExit, 0.0);
  // Against the prescribed flux, the slab measure (the crossings moved from 0.995 to 0.943 of
  // it with a change of the list's rebuild steps alone, where the slab measure moved from
  // 0.986 to 0.972).
  EXPECT_NEAR(slabMass / prescribed, 1.0, 0.05) << "slab flux at the zone's exit / rho_zone U A t";
  EXPECT_NEAR(throughExit / prescribed, 1.0, 0.1) << "mass through the zone's exit / rho_zone U A t";
  // Conservation, exactly: what entered through the exit plane and did not leave through the
  // middle one is still between them (counted by particle, so only float rounding differs).
  EXPECT_NEAR(throughExit - throughMid, stored, 1e-6 * throughExit) << "fluid mass appeared or vanished between the planes";
  // And the tube between the planes stores little of the flux: its wall and the fluid's
  // compressibility let that mass swing by a few percent over this window (1.006-1.054 for the
  // ratio below over runs that differ only in particle order, hence rounding).
  EXPECT_NEAR(throughMid / throughExit, 1.0, 0.1) << "mass through the middle / through the zone's exit";
  std::printf("over %.4f s: mass through the zone's exit %.4e kg, through the middle %.4e kg (ratio %.4f), stored between "
              "%.4e kg, rho_zone U A t %.4e kg (ratio %.4f, zone density %.1f kg/m^3)\n",
              seconds, throughExit, throughMid, throughMid / throughExit, stored, prescribed, throughExit / prescribed,
              zoneDensity);
  std::printf("slab flux at the exit: %.4e kg (ratio %.4f)\n", slabMass, slabMass / prescribed);
}

// A soft tube under a lumen pressure of 1 kPa stretches, and the closed loop's fluid thins out
// (its density falls 3%); with the zone as the supply, the fluid's mean density stays within
// 1% of rho0 (measured: -0.6%; the supply acts away from the wall only, see integrate.comp).
// The neighbour list is rebuilt only when particles may have moved by half the skin relative
// to the middle of the flow's x displacements (sph/integrate.comp). While the pulsatile flow
// drifts down the tube, after every step each fluid particle's list must still hold every
// particle within the kernel's support (brute force, minimum image across the seam).
TEST_F(InflowTest, NeighbourListStaysCompleteWhileTheBloodDrifts) {
  nlohmann::json j = tubeScene();
  j["vessel"]["inflow"]["mean_speed_m_s"] = 0.4;  // fast, so the list is rebuilt often
  j["vessel"]["inflow"]["ramp_s"] = 0.0;
  const scene::Scene scene = scene::parseScene(j.dump(), "inflow_test");
  sim::Simulation sim(ctx(), scene);
  const sim::SphParams& p = sim.solver().params();
  const double support = p.supportRadius, period = p.period[0];
  sim::RunOptions opt;
  opt.steps = 1;
  std::size_t pairs = 0, missing = 0;
  for (int step = 0; step < 120; ++step) {
    sim.run(opt);
    const auto pos = sim.store().readPositions();
    const auto vel = sim.store().readVelocities();
    const auto n = static_cast<std::uint32_t>(pos.size());
    // The fluid's lists: each particle's own, or (on CPU devices) its cluster's entries that
    // name it (interface/sph.h, "Clusters").
    const bool clusters = sim.solver().usesClusters();
    const gpu::Buffer& countBuffer = clusters ? sim.solver().clusterCounts() : sim.solver().neighbourCounts();
    const gpu::Buffer& listBuffer = clusters ? sim.solver().clusterLists() : sim.solver().neighbourList();
    const auto counts = countBuffer.readback<std::uint32_t>(countBuffer.size() / 4);
    const auto list = listBuffer.readback<std::uint32_t>(listBuffer.size() / 4);
    const std::uint32_t cap = sim.solver().clusterCapacity();
    for (std::uint32_t i = 0; i < n; ++i) {
      if (vel[i].w != float(sim::ParticleKind::Fluid)) continue;
      std::vector<std::uint32_t> have;
      if (clusters) {
        const std::uint32_t c = i / HEMO_CLUSTER_SIZE, bit = 1u << (HEMO_CLUSTER_MEMBER_SHIFT + i % HEMO_CLUSTER_SIZE);
        const std::uint32_t nf = counts[c] & 0xffffu, nb = counts[c] >> 16u;
        for (std::uint32_t k = 0; k < cap; ++k) {
          const std::uint32_t e = list[std::size_t(c) * cap + k];
          if ((k < nf || k >= cap - nb) && (e & bit)) have.push_back(e & HEMO_CLUSTER_SLOT_MASK);
        }
      } else {
        for (std::uint32_t k = 0; k < counts[i]; ++k) {
          have.push_back(list[std::size_t(i) * p.listParticleStride + std::size_t(k) * p.listStride] &
                         ~sim::SphSolver::kListBoundaryBit);
        }
      }
      std::sort(have.begin(), have.end());
      for (std::uint32_t k = 0; k < n; ++k) {
        if (k == i) continue;
        glm::dvec3 d = glm::dvec3(pos[i]) - glm::dvec3(pos[k]);
        d.x -= period * std::round(d.x / period);
        if (glm::length(d) >= support * (1.0 - 1e-5)) continue;
        ++pairs;
        if (!std::binary_search(have.begin(), have.end(), k) && ++missing <= 5) {
          ADD_FAILURE() << "step " << step << ": particle " << i << " does not list " << k << " at "
                        << glm::length(d) / support << " of the support";
        }
      }
    }
  }
  EXPECT_EQ(missing, 0u);
  EXPECT_GT(pairs, 1000000u);
  const std::uint32_t rebuilds = sim.solver().readRebuilds();
  std::printf("list complete over 120 steps: %zu pairs within the support, %u rebuilds\n", pairs, rebuilds);
  EXPECT_GT(rebuilds, 3u) << "the case must exercise rebuilds";
}

// The summary's counts (hemo-run's escaped_particles and lost_particles): a fluid particle
// outside the domain has escaped; one whose state is not finite is lost, and not also
// counted as escaped.
TEST_F(InflowTest, EscapedAndLostParticlesAreCountedApart) {
  const scene::Scene scene = scene::parseScene(tubeScene().dump(), "inflow_test");
  sim::Simulation sim(ctx(), scene);
  sim::RunOptions opt;
  opt.steps = 2;
  sim.run(opt);
  ASSERT_EQ(sim.escapedParticles(), 0u);
  ASSERT_EQ(sim.lostParticles(), 0u);
  auto pos = sim.store().readPositions();
  auto vel = sim.store().readVelocities();
  std::vector<std::uint32_t> fluid;
  for (std::uint32_t i = 0; i < pos.size() && fluid.size() < 3; ++i) {
    if (vel[i].w == float(sim::ParticleKind::Fluid)) fluid.push_back(i);
  }
  ASSERT_EQ(fluid.size(), 3u);
  pos[fluid[0]].z = scene.domain.max.z + 1.0f;  // out of the domain: escaped
  pos[fluid[1]].y = std::numeric_limits<float>::quiet_NaN();  // lost
  vel[fluid[2]].x = std::numeric_limits<float>::infinity();  // lost
  sim.store().live().positions.upload(pos);
  sim.store().live().velocities.upload(vel);
  EXPECT_EQ(sim.escapedParticles(), 1u);
  EXPECT_EQ(sim.lostParticles(), 2u);
}

TEST_F(InflowTest, SupplyHoldsTheLumenAtRestDensity) {
  auto meanDensity = [&](bool hold) {
    nlohmann::json j = tubeScene();
    j["vessel"]["stiffness_N_m"] = 20.0;
    j["fluid"]["background_pressure_Pa"] = 1000.0;
    j["fluid"]["background_pressure_ramp_s"] = 0.01;
    j["vessel"]["inflow"]["hold_lumen_pressure"] = hold;
    const scene::Scene scene = scene::parseScene(j.dump(), "inflow_test");
    sim::Simulation sim(ctx(), scene);
    sim::RunOptions opt;
    opt.until = 0.03;
    sim.run(opt);
    const sim::Snapshot s = sim.snapshot();
    double rho = 0.0, mass = 0.0, zrho = 0.0;
    std::uint32_t n = 0, zn = 0;
    for (std::uint32_t i = 0; i < s.positions.size(); ++i) {
      if (s.velocities[i].w != 0.0f) continue;
      if (s.positions[i].x < scene.vessel->inflow->zoneEnd) zrho += s.densityPressure[i].x, ++zn;
      rho += s.densityPressure[i].x;
      mass += s.positions[i].w;
      ++n;
    }
    std::printf("hold %d: mean fluid density %.2f kg/m^3 (in the zone %.2f), fluid mass %.4e kg\n", hold, rho / n, zrho / zn, mass);
    return rho / n / scene.sph.restDensity;
  };
  const double open = meanDensity(false), held = meanDensity(true);
  EXPECT_LT(open, 0.99) << "the test needs a tube that stretches enough to thin the fluid";
  EXPECT_NEAR(held, 1.0, 0.01);
  EXPECT_LT(std::abs(held - 1.0), std::abs(open - 1.0) / 3.0);
}

// hemo-view's live controls (Simulation::setLumenPressure, setInflowSpeed,
// setWallStiffnessScale) take effect from the next step: two runs of the same tube agree bit
// for bit until one changes all three; one step later its fluid's pressure is higher by the
// change wherever it was positive (the density pass, first in the step, saw the same
// positions; a negative sum is clamped at 0), its zone
// moves at the new speed's profile, and its springs hold the scaled stiffness and damping.
TEST_F(InflowTest, LiveControlsTakeEffectFromTheNextStep) {
  nlohmann::json json = tubeScene();
  json["fluid"]["background_pressure_ramp_s"] = 0.0;
  json["vessel"]["inflow"]["ramp_s"] = 0.0;
  const scene::Scene scene = scene::parseScene(json.dump(), "inflow_test");
  sim::Simulation a(ctx(), scene), b(ctx(), scene);
  sim::RunOptions opt;
  opt.steps = 40;
  a.run(opt);
  b.run(opt);
  ASSERT_EQ(a.snapshot().positions, b.snapshot().positions);
  EXPECT_THROW(b.setLumenPressure(std::numeric_limits<float>::quiet_NaN()), std::invalid_argument);
  EXPECT_THROW(b.setWallStiffnessScale(0.0f), std::invalid_argument);
  EXPECT_THROW(b.setInflowSpeed(std::numeric_limits<float>::infinity()), std::invalid_argument);
  EXPECT_FLOAT_EQ(b.lumenPressure(), 200.0f);
  EXPECT_FLOAT_EQ(b.inflowSpeed(), 0.1f);
  b.setLumenPressure(350.0f);
  b.setInflowSpeed(0.25f);
  b.setWallStiffnessScale(2.0f);
  EXPECT_FLOAT_EQ(b.lumenPressure(), 350.0f);
  EXPECT_FLOAT_EQ(b.inflowSpeed(), 0.25f);
  EXPECT_FLOAT_EQ(b.wallStiffnessScale(), 2.0f);
  opt.steps = 1;
  a.run(opt);
  b.run(opt);

  const sim::Snapshot sa = a.snapshot(), sb = b.snapshot();
  double worstPressure = 0.0;
  std::uint32_t fluid = 0;
  for (std::size_t i = 0; i < sa.positions.size(); ++i) {
    // Where the Tait pressure plus p_bg is clamped at 0 (a negative pressure) the change shows
    // only in part.
    if (sa.velocities[i].w != 0.0f || !(sa.densityPressure[i].y > 0.0f)) continue;
    worstPressure = std::max(worstPressure, std::abs(double(sb.densityPressure[i].y - sa.densityPressure[i].y) - 150.0));
    ++fluid;
  }
  EXPECT_GT(fluid, 300u);
  EXPECT_LT(worstPressure, 1e-3) << "the pressure did not rise by the lumen pressure's change (Pa)";

  sim::Inflow faster = *scene.vessel->inflow;
  faster.meanSpeed = 0.25f;
  const sim::SphClock clock = b.solver().readClock();
  const double tStep = clock.time - clock.lastDt;
  const float dp = scene.sph.spacing;
  double worstSpeed = 0.0;
  std::uint32_t zone = 0;
  for (std::size_t i = 0; i < sb.positions.size(); ++i) {
    const glm::vec4 x = sb.positions[i], v = sb.velocities[i];
    if (v.w != 0.0f || x.x < faster.zoneStart + dp || x.x > faster.zoneEnd - dp) continue;
    const double r = std::hypot(double(x.y) - v.y * clock.lastDt - faster.centreY, double(x.z) - v.z * clock.lastDt - faster.centreZ);
    if (r >= faster.radius) continue;
    worstSpeed = std::max(worstSpeed, std::abs(v.x - faster.axialVelocity(tStep, r)) / (2.0 * 0.25 * 1.8));
    ++zone;
  }
  EXPECT_GT(zone, 100u);
  EXPECT_LT(worstSpeed, 1e-5) << "the zone does not move at the new speed's profile (relative to the peak)";

  const std::vector<sim::GpuSpring> ka = a.solver().wall()->readSprings(), kb = b.solver().wall()->readSprings();
  ASSERT_EQ(ka.size(), kb.size());
  ASSERT_FALSE(ka.empty());
  for (std::size_t k = 0; k < ka.size(); ++k) {
    EXPECT_FLOAT_EQ(kb[k].stiffness, 2.0f * ka[k].stiffness);
    EXPECT_FLOAT_EQ(kb[k].damping, std::sqrt(2.0f) * ka[k].damping);
    EXPECT_EQ(kb[k].restLength, ka[k].restLength);
    EXPECT_EQ(kb[k].maxForce, ka[k].maxForce);
    EXPECT_EQ(kb[k].broken, ka[k].broken);
  }
  std::printf("live controls: pressure change off by %.2e Pa over %u fluid particles, zone speed off by %.2e of the peak\n",
              worstPressure, fluid, worstSpeed);
}

}  // namespace
}  // namespace hemo::test
