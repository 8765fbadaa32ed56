// Surgical tools: the contact stage against its double-precision twin on random inputs, and
// the tool force against the momentum the particles take.
#include "gpu_test.hpp"
#include "hemo/gpu/commands.hpp"
#include "hemo/reference/tools.hpp"
#include "hemo/scene/scene.hpp"
#include "hemo/sim/simulation.hpp"
#include "hemo/sim/sph.hpp"
#include "hemo/sim/tools.hpp"
#include "interface/sph.h"
#include "interface/tool.h"

#include <glm/geometric.hpp>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <numbers>

namespace hemo::test {
namespace {

glm::quat axisAngle(glm::vec3 axis, float angle) { return glm::angleAxis(angle, glm::normalize(axis)); }

class ToolTest : public GpuTest {};

// 3,000 particles in a box periodic along x: fluid (mass), wall points (their own mass; some
// anchored, some past the network's ids) and rigid boundary particles, around two tools: a
// tilted capsule moving and turning between keyframes, and a sphere across the periodic seam.
// The pushes (added to random accelerations), the wall's held record, the time step's partials
// and each tool's force, torque and pose match the twin.
TEST_F(ToolTest, ContactMatchesReference) {
  auto rng = rngFor();
  std::uniform_real_distribution<double> u(0.0, 1.0);
  sim::SphSettings s;
  s.spacing = 0.002f;
  s.soundSpeed = 5.0f;
  const double h = s.h();
  const glm::dvec3 period(0.04, 0.0, 0.0);

  std::vector<sim::ToolSpec> tools(2);
  tools[0].name = "capsule";
  tools[0].radius = 0.004f;
  tools[0].length = 0.012f;
  tools[0].contactDistance = 0.002f;
  tools[0].keys = {{0.0, {0.01f, 0.015f, 0.012f}, axisAngle({1, 1, 0}, 0.3f)},
                   {0.2, {0.016f, 0.013f, 0.010f}, axisAngle({0, 1, 1}, 0.9f)},
                   {0.5, {0.02f, 0.02f, 0.02f}, axisAngle({0, 1, 1}, 1.2f)}};
  tools[1].name = "sphere";
  tools[1].radius = 0.005f;
  tools[1].contactDistance = 0.003f;
  tools[1].contactScale = 0.03f;
  tools[1].keys = {{0.0, {0.039f, 0.02f, 0.02f}, glm::quat(1, 0, 0, 0)}};
  const double t = 0.13;  // between the capsule's first two keys

  const std::uint32_t n = 3000, wallPoints = 900;
  std::vector<glm::vec4> pos(n), vel(n), acc(n), held(n);
  std::vector<std::uint32_t> ids(n);
  std::vector<glm::vec4> info(wallPoints);
  std::vector<glm::dvec3> x(n);
  std::vector<double> mass(n, 0.0);
  for (std::uint32_t i = 0; i < n; ++i) {
    x[i] = glm::dvec3(glm::vec3(u(rng) * 0.04, u(rng) * 0.04, u(rng) * 0.04));
    const double r = u(rng);
    const std::uint32_t kind = r < 0.5 ? HEMO_KIND_FLUID : r < 0.9 ? HEMO_KIND_WALL : HEMO_KIND_BOUNDARY;
    const float sphMass = float(1e-5 * (0.5 + u(rng)));
    pos[i] = glm::vec4(glm::vec3(x[i]), sphMass);
    vel[i] = glm::vec4(0.1f * glm::vec3(u(rng) - 0.5, u(rng) - 0.5, u(rng) - 0.5), float(kind));
    acc[i] = glm::vec4(glm::vec3(u(rng) - 0.5, u(rng) - 0.5, u(rng) - 0.5) * 20.0f, u(rng) < 0.1 ? -1.0f : 0.0f);
    held[i] = glm::vec4(glm::vec3(u(rng) - 0.5, u(rng), u(rng)), 0.0f);
    ids[i] = i < wallPoints ? i : std::uint32_t(u(rng) * 1e6) + wallPoints;  // wall ids below wallPoints have records
    if (kind == HEMO_KIND_FLUID) mass[i] = sphMass;
    if (kind == HEMO_KIND_WALL) mass[i] = sphMass;
  }
  for (std::uint32_t id = 0; id < wallPoints; ++id) {
    const bool anchored = u(rng) < 0.15;
    info[id] = glm::vec4(float(1e-4 * (0.5 + u(rng))), anchored ? 1.0f : 0.0f, 0.0f, 0.0f);
  }
  for (std::uint32_t i = 0; i < n; ++i) {
    if (uint32_t(vel[i].w) == HEMO_KIND_WALL && ids[i] < wallPoints) mass[i] = info[ids[i]].y != 0.0f ? 0.0 : info[ids[i]].x;
  }

  sim::ParticleStore store(ctx(), n);
  store.upload(pos, vel, ids);
  sim::SphParams params = sim::makeParams(s);
  params.period[0] = float(period.x);
  params.invPeriod[0] = float(1.0 / period.x);
  gpu::Buffer paramsBuffer(ctx(), sizeof(params), gpu::MemoryUse::Device, "params");
  paramsBuffer.upload(std::vector<sim::SphParams>{params});
  struct Clock {
    float time, compensation, lastDt;
    std::uint32_t steps;
  };
  gpu::Buffer clock(ctx(), 2 * sizeof(Clock), gpu::MemoryUse::Device, "clock");
  clock.upload(std::vector<Clock>{{0.9f, 0.0f, 0.0f, 0u}, {float(t), 0.0f, 1e-4f, 7u}});
  gpu::Buffer accel(ctx(), n * 16, gpu::MemoryUse::Device, "accel");
  accel.upload(acc);
  gpu::Buffer heldBuffer(ctx(), n * 16, gpu::MemoryUse::Device, "held");
  heldBuffer.upload(held);
  gpu::Buffer dtCounts(ctx(), 16, gpu::MemoryUse::Device, "dt counts");
  dtCounts.upload(std::vector<std::uint32_t>{0, 0, 0, 0});
  gpu::Buffer wallInfo(ctx(), wallPoints * 16, gpu::MemoryUse::Device, "wall info");
  wallInfo.upload(info);
  const double psiPerScale = double(s.soundSpeed) * s.soundSpeed / (2.0 * h);
  sim::ToolContact contact(ctx(), store, {&accel, &paramsBuffer, &clock, &dtCounts, &wallInfo, wallPoints, &heldBuffer},
                           tools, float(psiPerScale), s.spacing, 4);
  gpu::CommandRecorder rec(ctx());
  rec.begin();
  contact.record(rec, n, 1u, true);
  rec.end();
  rec.submitAndWait();

  const reference::RefToolContact ref = reference::toolContact(tools, double(float(t)), x, mass, psiPerScale, h, period);
  const auto accOut = accel.readback<glm::vec4>(n);
  const auto heldOut = heldBuffer.readback<glm::vec4>(n);
  std::uint32_t touched = 0;
  double minLimit = 3e38;
  for (std::uint32_t i = 0; i < n; ++i) {
    const glm::dvec3 got = glm::dvec3(accOut[i]) - glm::dvec3(acc[i]);
    const double scale = glm::length(ref.accel[i]) + 1e-3 * glm::length(glm::dvec3(acc[i]));
    EXPECT_LE(glm::length(got - ref.accel[i]), 1e-4 * std::max(scale, 1.0)) << "particle " << i;
    EXPECT_EQ(accOut[i].w, acc[i].w) << "particle " << i << ": the wall's detach marker is kept";
    const bool wall = std::uint32_t(vel[i].w) == HEMO_KIND_WALL;
    const glm::dvec3 heldAdded = glm::dvec3(heldOut[i]) - glm::dvec3(held[i]);
    EXPECT_LE(glm::length(heldAdded - (wall ? ref.accel[i] : glm::dvec3(0.0))), 1e-4 * std::max(scale, 1.0)) << "particle " << i;
    if (glm::length(ref.accel[i]) > 0.0) {
      ++touched;
      const double after = glm::length(glm::dvec3(acc[i]) + ref.accel[i]);
      minLimit = std::min(minLimit, double(s.cflForce) * std::sqrt(h / after));
    }
  }
  EXPECT_GT(touched, 100u);
  EXPECT_LT(touched, n / 2);
  // the tools' own limit: the capsule's surface moves at most D / 4 per step
  for (std::size_t k = 0; k < tools.size(); ++k) {
    if (ref.poses[k].speed > 0.0) minLimit = std::min(minLimit, 0.25 * tools[k].contactDistance / ref.poses[k].speed);
  }
  const auto counts = dtCounts.readback<std::uint32_t>(4);
  ASSERT_GT(counts[2], 0u);
  const auto dtPartials = contact.dtPartials().readback<glm::vec2>(counts[2]);
  float gpuMin = 3e38f;
  for (const glm::vec2& p : dtPartials) gpuMin = std::min(gpuMin, p.x);
  EXPECT_NEAR(gpuMin, minLimit, 1e-4 * minLimit);

  // the force and torque partials, summed here (sph/dt_reduce.comp sums them on the GPU: the
  // scene test below checks its log)
  const auto partialCount = contact.partialCount().readback<std::uint32_t>(1)[0];
  ASSERT_GT(partialCount, 0u);
  ASSERT_LE(partialCount, contact.partialStride());
  const auto partials = contact.partials().readback<glm::vec4>(std::size_t(contact.partialStride()) * tools.size() * 2);
  for (std::size_t k = 0; k < tools.size(); ++k) {
    glm::dvec3 force(0.0), torque(0.0);
    for (std::uint32_t p = 0; p < partialCount; ++p) {
      force += glm::dvec3(partials[(k * contact.partialStride() + p) * 2]);
      torque += glm::dvec3(partials[(k * contact.partialStride() + p) * 2 + 1]);
    }
    double sumForces = 0.0;
    for (std::uint32_t i = 0; i < n; ++i) {
      sumForces += mass[i] * glm::length(reference::toolAcceleration(tools[k], ref.poses[k], tools[k].contactScale * psiPerScale,
                                                                      h, x[i], period));
    }
    ASSERT_GT(sumForces, 0.0) << tools[k].name;
    EXPECT_LE(glm::length(force - ref.force[k]), 1e-4 * sumForces) << tools[k].name;
    EXPECT_LE(glm::length(torque - ref.torque[k]), 1e-4 * sumForces * 0.03) << tools[k].name;
  }
}

// A scene with a probe swept through a block of still fluid without gravity: the momentum
// the particles hold at the end equals minus the impulse the tool log records (sum of F dt),
// within 1e-5 of it; and the run, repeated, gives the same log and particles bit for bit.
TEST_F(ToolTest, ToolForceIsMinusTheMomentumGivenToTheParticles) {
  const nlohmann::json j = nlohmann::json::parse(R"({
    "scene": "probe_sweep",
    "particles": { "spacing_m": 0.002 },
    "fluid": { "expected_max_speed_m_s": 0.5, "viscosity_pa_s": 0.001,
               "blocks": [ { "min_m": [0, 0, 0], "max_m": [0.02, 0.016, 0.016] } ] },
    "forces": { "gravity_m_s2": [0, 0, 0] },
    "tools": [ { "name": "probe", "radius_m": 0.002, "length_m": 0.01,
                 "path": [ { "time_s": 0.0, "position_m": [-0.004, 0.008, 0.006] },
                           { "time_s": 0.06, "position_m": [0.024, 0.008, 0.006] } ] } ],
    "time": { "end_time_s": 0.03, "steps_per_batch": 64 },
    "domain": { "min_m": [-0.01, -0.01, -0.01], "max_m": [0.03, 0.026, 0.03] }
  })");
  const scene::Scene sc = scene::parseScene(j.dump(), "probe_sweep.json");
  struct Outcome {
    std::vector<sim::ToolLogRow> rows;
    sim::Snapshot snap;
  };
  auto runOnce = [&] {
    Outcome o;
    sim::Simulation sim(ctx(), sc);
    sim::RunOptions opt;
    opt.onToolLog = [&](const std::vector<sim::ToolLogRow>& rows) { o.rows.insert(o.rows.end(), rows.begin(), rows.end()); };
    sim.run(opt);
    o.snap = sim.snapshot();
    return o;
  };
  const Outcome a = runOnce();
  ASSERT_GT(a.rows.size(), 50u);
  glm::dvec3 impulse(0.0), momentum(0.0);
  double scale = 0.0;
  for (const sim::ToolLogRow& r : a.rows) {
    impulse += glm::dvec3(r.sample.force) * double(r.dt);
    scale += glm::length(glm::dvec3(r.sample.force)) * double(r.dt);
  }
  for (std::size_t i = 0; i < a.snap.velocities.size(); ++i) {
    momentum += double(a.snap.positions[i].w) * glm::dvec3(a.snap.velocities[i]);
  }
  ASSERT_GT(scale, 0.0);
  std::printf("[tools] %zu steps to t = %.4f s: tool impulse (%.6g, %.6g, %.6g) N s, |momentum + impulse| / sum |F| dt = %.3g\n",
              a.rows.size(), double(a.rows.back().sample.force.w + a.rows.back().dt), impulse.x, impulse.y, impulse.z,
              glm::length(momentum + impulse) / scale);
  EXPECT_GT(-impulse.x, 0.5 * scale) << "the probe pushes the fluid along +x";
  EXPECT_LE(glm::length(momentum + impulse), 1e-5 * scale)
      << "momentum " << momentum.x << " " << momentum.y << " " << momentum.z << ", tool impulse " << impulse.x << " "
      << impulse.y << " " << impulse.z;

  // the log's time and pose against the twin's, at every 10th step
  for (std::size_t k = 0; k < a.rows.size(); k += 10) {
    const sim::ToolSample& got = a.rows[k].sample;
    const reference::RefToolPose pose = reference::toolPose(sc.tools[0], double(got.force.w));
    EXPECT_LE(glm::length(glm::dvec3(got.position) - pose.position), 1e-6) << "row " << k;
    EXPECT_NEAR(got.position.w, pose.speed, 1e-5 * pose.speed) << "row " << k;
    EXPECT_NEAR(std::abs(got.orientation.w * pose.orientation.w + got.orientation.x * pose.orientation.x +
                         got.orientation.y * pose.orientation.y + got.orientation.z * pose.orientation.z),
                1.0, 1e-6);
    if (k > 0) {
      EXPECT_FLOAT_EQ(got.force.w, a.rows[k - 1].sample.force.w + a.rows[k - 1].dt) << "row " << k;
    }
  }

  const Outcome b = runOnce();
  ASSERT_EQ(b.rows.size(), a.rows.size());
  for (std::size_t k = 0; k < a.rows.size(); ++k) {
    ASSERT_EQ(std::memcmp(&a.rows[k].sample, &b.rows[k].sample, sizeof(sim::ToolSample)), 0) << "row " << k;
    ASSERT_EQ(a.rows[k].dt, b.rows[k].dt) << "row " << k;
  }
  ASSERT_EQ(std::memcmp(a.snap.positions.data(), b.snap.positions.data(), a.snap.positions.size() * 16), 0);
  ASSERT_EQ(std::memcmp(a.snap.velocities.data(), b.snap.velocities.data(), a.snap.velocities.size() * 16), 0);
}

}  // namespace
}  // namespace hemo::test
