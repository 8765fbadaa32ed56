// Surgical tools: the contact stage against its double-precision twin on random inputs, and
// the tool force against the momentum the particles take.
#include "gpu_test.hpp"
#include "hemo/gpu/commands.hpp"
#include "hemo/reference/tools.hpp"
#include "hemo/scene/scene.hpp"
#include "hemo/sim/simulation.hpp"
#include "hemo/sim/sph.hpp"
#include "hemo/sim/tools.hpp"
#include "hemo/sim/wall.hpp"
#include "interface/sph.h"
#include "interface/tool.h"

#include <glm/geometric.hpp>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <memory>
#include <numbers>
#include <string>
#include <vector>

namespace hemo::test {
namespace {

glm::quat axisAngle(glm::vec3 axis, float angle) { return glm::angleAxis(angle, glm::normalize(axis)); }

class ToolTest : public GpuTest {};

// The SPH parameters of `s` in a device buffer, with x periodic over `period` (m).
gpu::Buffer periodicParams(gpu::Context& context, const sim::SphSettings& s, float period) {
  sim::SphParams params = sim::makeParams(s);
  params.period[0] = period;
  params.invPeriod[0] = 1.0f / period;
  gpu::Buffer buffer(context, sizeof(params), gpu::MemoryUse::Device, "params");
  buffer.upload(std::vector<sim::SphParams>{params});
  return buffer;
}

// The solver's two clock records (common/clock.glsl), as given.
struct ClockRecord {
  float time, compensation, lastDt;
  std::uint32_t steps;
};
gpu::Buffer clockAt(gpu::Context& context, const std::vector<ClockRecord>& records) {
  gpu::Buffer buffer(context, records.size() * sizeof(ClockRecord), gpu::MemoryUse::Device, "clock");
  buffer.upload(records);
  return buffer;
}

// 3,000 particles in a box periodic along x: fluid (mass), wall points (their own mass; some
// anchored, some past the network's ids) and rigid boundary particles, around four tools: a
// tilted capsule moving and turning between keyframes, a sphere across the periodic seam, a
// grasper whose flat jaws close while it moves and turns, and a gripping one nearly closed,
// moving and turning, with 400 of the particles between its jaws. The wall points' grip
// records start random (free, held by it with a random anchor, or by another tool).
// The pushes and grips (added to random accelerations), the wall's held record, the grip
// records, the time step's partials and each tool's force, torque and pose match the twin.
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
  sim::ToolSpec grasper;
  grasper.name = "grasper";
  grasper.kind = sim::ToolKind::Grasper;
  grasper.radius = 0.0015f;
  grasper.length = 0.015f;
  grasper.contactDistance = 0.002f;
  grasper.jawWidth = 0.006f;
  grasper.keys = {{0.0, {0.025f, 0.03f, 0.01f}, axisAngle({0, 0, 1}, 0.4f), false, 0.012f},
                  {0.3, {0.025f, 0.032f, 0.012f}, axisAngle({0, 1, 0}, 0.5f), false, 0.002f}};
  tools.push_back(grasper);
  sim::ToolSpec gripper = grasper;
  gripper.name = "gripper";
  gripper.radius = 0.001f;
  gripper.length = 0.01f;
  gripper.jawWidth = 0.004f;
  gripper.gripStiffness = 3.0f;
  gripper.keys = {{0.0, {0.01f, 0.01f, 0.03f}, axisAngle({1, 0, 1}, 0.2f), false, 0.0035f},
                  {0.4, {0.012f, 0.008f, 0.026f}, axisAngle({1, 2, 0}, 0.6f), false, 0.002f}};
  tools.push_back(gripper);
  const double t = 0.13;  // between the capsule's first two keys (and the graspers')
  const double timeStepFactor = 0.2;

  const std::uint32_t n = 3000, wallPoints = 900;
  std::vector<glm::vec4> pos(n), vel(n), acc(n), held(n);
  std::vector<std::uint32_t> ids(n);
  std::vector<glm::vec4> info(wallPoints);
  std::vector<glm::dvec3> x(n);
  std::vector<double> mass(n, 0.0);
  const reference::RefToolPose gripPose = reference::toolPose(gripper, double(float(t)));
  for (std::uint32_t i = 0; i < n; ++i) {
    x[i] = glm::dvec3(glm::vec3(u(rng) * 0.04, u(rng) * 0.04, u(rng) * 0.04));
    if (i < 400) {  // between the gripper's jaws (and a little beyond their edges)
      const glm::dvec3 lateral = glm::cross(gripPose.axis, gripPose.side);
      x[i] = glm::dvec3(glm::vec3(gripPose.position + (u(rng) * 1.1 - 0.05) * double(gripper.length) * gripPose.axis +
                                  (u(rng) - 0.5) * 1.1 * double(gripper.jawWidth) * lateral +
                                  (u(rng) - 0.5) * 0.6 * gripPose.opening * gripPose.side));
    }
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
  // grip records by id: free, held by the gripper (its index + 1) at a random anchor, or by
  // another tool
  std::vector<glm::vec4> gripIn(wallPoints);
  for (std::uint32_t id = 0; id < wallPoints; ++id) {
    const double r = u(rng);
    const float holder = r < 0.4 ? 0.0f : r < 0.75 ? 4.0f : r < 0.9 ? 3.0f : 1.0f;
    gripIn[id] = holder == 0.0f ? glm::vec4(0.0f) : glm::vec4(float(u(rng) * 0.01), float((u(rng) - 0.5) * 0.004), 0.0f, holder);
  }
  reference::RefGrips refGrips;
  refGrips.timeStepFactor = timeStepFactor;
  for (std::uint32_t i = 0; i < n; ++i) {
    refGrips.grippable.push_back(uint32_t(vel[i].w) == HEMO_KIND_WALL && ids[i] < wallPoints && mass[i] > 0.0);
    refGrips.velocity.push_back(glm::dvec3(glm::vec3(vel[i])));
    refGrips.record.push_back(ids[i] < wallPoints ? glm::dvec4(gripIn[ids[i]]) : glm::dvec4(0.0));
  }

  sim::ParticleStore store(ctx(), n);
  store.upload(pos, vel, ids);
  gpu::Buffer paramsBuffer = periodicParams(ctx(), s, float(period.x));
  // the force evaluation's time in record 1
  gpu::Buffer clock = clockAt(ctx(), {{0.9f, 0.0f, 0.0f, 0u}, {float(t), 0.0f, 1e-4f, 7u}});
  gpu::Buffer accel(ctx(), n * 16, gpu::MemoryUse::Device, "accel");
  accel.upload(acc);
  gpu::Buffer heldBuffer(ctx(), n * 16, gpu::MemoryUse::Device, "held");
  heldBuffer.upload(held);
  gpu::Buffer dtCounts(ctx(), 16, gpu::MemoryUse::Device, "dt counts");
  dtCounts.upload(std::vector<std::uint32_t>{0, 0, 0, 0});
  gpu::Buffer wallInfo(ctx(), wallPoints * 16, gpu::MemoryUse::Device, "wall info");
  wallInfo.upload(info);
  const double psiPerScale = double(s.soundSpeed) * s.soundSpeed / (2.0 * h);
  sim::ToolContact contact(ctx(), store,
                           {&accel, &paramsBuffer, &clock, &dtCounts, &wallInfo, wallPoints, &heldBuffer, float(timeStepFactor)},
                           tools, float(psiPerScale), s.spacing, 4);
  contact.grips().upload(gripIn);
  gpu::CommandRecorder rec(ctx());
  rec.begin();
  contact.record(rec, n, 1u, true);
  rec.end();
  rec.submitAndWait();

  const reference::RefToolContact ref =
      reference::toolContact(tools, double(float(t)), x, mass, psiPerScale, h, period, &refGrips);
  // the grip records: the same holder, the anchor where it was or where the point is now
  const auto gripOut = contact.grips().readback<glm::vec4>(wallPoints);
  std::uint32_t gripped = 0, taken = 0, released = 0;
  for (std::uint32_t i = 0; i < n; ++i) {
    if (!refGrips.grippable[i]) continue;
    const glm::dvec4& want = refGrips.record[i];
    const glm::vec4& got = gripOut[ids[i]];
    EXPECT_EQ(double(got.w), want.w) << "particle " << i;
    EXPECT_NEAR(got.x, want.x, 1e-7) << "particle " << i;
    EXPECT_NEAR(got.y, want.y, 1e-7) << "particle " << i;
    gripped += want.w == 4.0;
    taken += want.w == 4.0 && gripIn[ids[i]].w != 4.0f;
    released += want.w == 0.0 && gripIn[ids[i]].w != 0.0f;
  }
  EXPECT_GT(gripped, 30u);
  EXPECT_GT(taken, 5u);
  EXPECT_GT(released, 100u);
  // (ids past the network's and anchored points keep their records)
  for (std::uint32_t id = 0; id < wallPoints; ++id) {
    if (info[id].y != 0.0f) {
      EXPECT_EQ(gripOut[id], gripIn[id]) << "anchored id " << id;
    }
  }
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
    if (refGrips.limit[i] > 0.0) minLimit = std::min(minLimit, refGrips.limit[i]);
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

// The stiffness of a pre-tensioned square sheet of springs (11 x 11 points, edges anchored,
// rest length 0.9 of the spacing) under a push on its centre point, from the linearised
// statics: each spring of tension T and length s resists a sideways offset of its ends with
// T / s, so the out-of-plane displacements solve a weighted graph Laplacian; K = 1 / C_cc.
double sheetCentreStiffness(int n, double tension, double spacing) {
  // unknowns: the interior points, row-major
  const int m = n - 2, count = m * m;
  std::vector<double> a(std::size_t(count) * count, 0.0), b(count, 0.0);
  const double w = tension / spacing;
  auto at = [&](int i, int j) { return (j - 1) * m + (i - 1); };
  for (int j = 1; j <= m; ++j) {
    for (int i = 1; i <= m; ++i) {
      const int r = at(i, j);
      const int di[4] = {1, -1, 0, 0}, dj[4] = {0, 0, 1, -1};
      for (int e = 0; e < 4; ++e) {
        a[std::size_t(r) * count + r] += w;
        const int ni = i + di[e], nj = j + dj[e];
        if (ni >= 1 && ni <= m && nj >= 1 && nj <= m) a[std::size_t(r) * count + at(ni, nj)] -= w;
      }
    }
  }
  const int c = at(n / 2, n / 2);
  b[c] = 1.0;
  // Gaussian elimination (symmetric positive definite: no pivoting needed)
  for (int k = 0; k < count; ++k) {
    for (int r = k + 1; r < count; ++r) {
      const double f = a[std::size_t(r) * count + k] / a[std::size_t(k) * count + k];
      if (f == 0.0) continue;
      for (int q = k; q < count; ++q) a[std::size_t(r) * count + q] -= f * a[std::size_t(k) * count + q];
      b[r] -= f * b[k];
    }
  }
  std::vector<double> x(count, 0.0);
  for (int r = count - 1; r >= 0; --r) {
    double sum = b[r];
    for (int q = r + 1; q < count; ++q) sum -= a[std::size_t(r) * count + q] * x[q];
    x[r] = sum / a[std::size_t(r) * count + r];
  }
  return 1.0 / x[c];
}

// That sheet (dp 10 mm, spacing 40 mm at z0 = 50 mm, springs of 10 N/m with mass 1e-4 kg
// points, pre-tensioned to a tenth of k times the spacing) on a solver with one tool; the wall
// points' transverse modes settle under velocity damping (the springs damp along themselves
// only).
struct SpringSheet {
  static constexpr int n = 11;
  static constexpr float dp = 0.01f, spacing = 4.0f * dp, z0 = 0.05f, k = 10.0f, mass = 1e-4f;
  static constexpr float mid = 5.0f * spacing;  // the centre point's x and y
  static constexpr double tension = double(k) * 0.1 * spacing;
  static constexpr std::uint32_t centre = std::uint32_t((n / 2) * n + n / 2);

  SpringSheet(gpu::Context& context, const sim::ToolSpec& tool) : store(context, n * n), rec(context) {
    sim::SphSettings s;
    s.spacing = dp;
    s.soundSpeed = 1.0f;
    s.gravity = glm::vec3(0.0f);
    s.maxTimeStep = 1.0f;
    s.dampingRate = 60.0f;
    s.dampingUntil = 1e6f;
    std::vector<glm::vec4> pos, vel;
    for (int j = 0; j < n; ++j) {
      for (int i = 0; i < n; ++i) {
        pos.emplace_back(float(i) * spacing, float(j) * spacing, z0, s.particleMass());
        vel.emplace_back(0.0f, 0.0f, 0.0f, float(HEMO_KIND_WALL));
        net.points.push_back({mass, i == 0 || j == 0 || i == n - 1 || j == n - 1});
      }
    }
    for (int j = 0; j < n; ++j) {
      for (int i = 0; i < n; ++i) {
        const std::uint32_t id = std::uint32_t(j * n + i);
        if (i + 1 < n) net.springs.push_back({id, id + 1, 0.9f * spacing, k, 0.0f, 3e38f});
        if (j + 1 < n) net.springs.push_back({id, id + std::uint32_t(n), 0.9f * spacing, k, 0.0f, 3e38f});
      }
    }
    store.upload(pos, vel);
    solver = std::make_unique<sim::SphSolver>(context, store, glm::vec3(-0.05f), glm::vec3(0.45f), s, 256);
    solver->attachWall(net);
    solver->attachTools({tool});
    rec.begin();
    solver->recordReset(rec);
    rec.end();
    rec.submitAndWait();
  }

  // Runs to `until` (s); over its last `window` s, the mean z force on the tool (N) and the
  // centre point's mean height above z0 (m).
  void runTo(double until, double window, double& force, double& height) {
    double fSum = 0.0, zSum = 0.0;
    int fCount = 0, zCount = 0;
    while (solver->readClock().time < float(until)) {  // (the clock stops at float(until))
      const double t0 = solver->readClock().time;
      const std::uint32_t batch = t0 < until - window ? 256u : 16u;
      rec.begin();
      for (std::uint32_t b = 0; b < batch; ++b) solver->recordStep(rec, step++, b, float(until));
      rec.end();
      rec.submitAndWait();
      if (t0 >= until - window) {
        for (const sim::ToolSample& sample : solver->tools()->readLog(batch)) {
          if (sample.force.w >= until - window && sample.force.w < until) fSum += sample.force.z, ++fCount;
        }
        const auto p = store.readPositions();
        const auto ids = store.readIds();
        for (std::size_t slot = 0; slot < ids.size(); ++slot) {
          if (ids[slot] == centre) zSum += double(p[slot].z) - z0, ++zCount;
        }
      }
    }
    ASSERT_GT(fCount, 10);
    force = fSum / fCount;
    height = zSum / zCount;
  }

  sim::SpringNetwork net;
  sim::ParticleStore store;
  std::unique_ptr<sim::SphSolver> solver;
  gpu::CommandRecorder rec;
  std::uint32_t step = 0;
};

// A sphere pressed onto the centre of that sheet, held at two depths (the wall points' own
// dynamics, damped, with the contact's push): the force the tool log reports over the centre
// point's displacement is the sheet's stiffness from the linearised statics within 5% at both
// depths (Hooke: the same K at twice the displacement). Only the centre point is within the
// contact distance, so the force is the sheet's reaction at that point alone.
TEST_F(ToolTest, ProbePressedIntoASpringSheetMeetsItsStiffness) {
  using S = SpringSheet;
  // The sheet's spacing is 4 dp: the contact's reach (2 dp) then takes in the centre point
  // alone, and the push's whole range (from its weakest at the reach to its strongest) holds
  // the sheet at both depths.
  // The sphere's bottom held where the centre point settles about 0.2 and 0.45 mm down (the
  // point sits 11-17 mm below the sphere, where the push balances the sheet's reaction)
  const float radius = 0.004f, mid = S::mid, z0 = S::z0;
  const float hold1 = z0 + 0.0170f + radius, hold2 = z0 + 0.0112f + radius;
  sim::ToolSpec probe;
  probe.name = "probe";
  probe.radius = radius;
  probe.contactDistance = 2.0f * S::dp;
  probe.contactScale = 0.26f;  // Psi = 10 m/s^2
  probe.keys = {{0.0, {mid, mid, z0 + 0.03f + radius}, glm::quat(1, 0, 0, 0)},
                {0.15, {mid, mid, hold1}, glm::quat(1, 0, 0, 0)},
                {0.5, {mid, mid, hold1}, glm::quat(1, 0, 0, 0)},
                {0.65, {mid, mid, hold2}, glm::quat(1, 0, 0, 0)}};
  SpringSheet sheet(ctx(), probe);
  const double expected = sheetCentreStiffness(S::n, S::tension, S::spacing);
  double f1 = 0, h1 = 0, f2 = 0, h2 = 0;
  sheet.runTo(0.5, 0.05, f1, h1);
  sheet.runTo(1.0, 0.05, f2, h2);
  const double w1 = -h1, w2 = -h2;  // pressed down
  std::printf("[tools] sheet K from the statics %.5g N/m; pressed %.3g mm: %.4g N, K %.5g; %.3g mm: %.4g N, K %.5g\n",
              expected, w1 * 1e3, f1, f1 / w1, w2 * 1e3, f2, f2 / w2);
  EXPECT_GT(w2, 1.5 * w1);
  EXPECT_NEAR(f1 / w1, expected, 0.05 * expected);
  EXPECT_NEAR(f2 / w2, expected, 0.05 * expected);
}

// A grasper closed on the centre point of the pre-tensioned sheet above grips it (the point
// lies within the contact distance of both capsule jaws, standing upright either side of it)
// and lifts it: the grip's spring k_g in series with the sheet's stiffness K sets the lift,
// u = w k_g / (k_g + K) for a jaw raised by w, and the force the tool feels, K u (both within
// 5%). Opened, the jaws let go: the record clears and the sheet springs back.
TEST_F(ToolTest, GrasperLiftsASpringSheetAgainstItsStiffnessAndLetsGo) {
  using S = SpringSheet;
  // Upright capsule jaws (the tool's default frame: shaft +z, jaws either side along x), the
  // tip 10 mm below the sheet. Closed to 4 mm, the centre point lies 2 mm from each (within
  // D = 3 mm of both), its neighbours 40 mm away out of reach. Raised by w1 = 0.5 mm, then
  // by w2 = 1 mm, then opened.
  const float mid = S::mid, tip = S::z0 - 0.01f, w1 = 0.0005f, w2 = 0.001f;
  const float kGrip = 2.0f;
  sim::ToolSpec grasper;
  grasper.name = "grasper";
  grasper.kind = sim::ToolKind::Grasper;
  grasper.radius = 0.004f;
  grasper.length = 0.02f;
  grasper.contactDistance = 0.003f;
  grasper.contactScale = 0.26f;
  grasper.gripStiffness = kGrip;
  const glm::quat upright(1, 0, 0, 0);
  grasper.keys = {{0.0, {mid, mid, tip}, upright, false, 0.03f},   {0.1, {mid, mid, tip}, upright, false, 0.004f},
                  {0.15, {mid, mid, tip}, upright, false, 0.004f}, {0.25, {mid, mid, tip + w1}, upright, false, 0.004f},
                  {0.5, {mid, mid, tip + w1}, upright, false, 0.004f}, {0.6, {mid, mid, tip + w2}, upright, false, 0.004f},
                  {1.0, {mid, mid, tip + w2}, upright, false, 0.004f}, {1.05, {mid, mid, tip + w2}, upright, false, 0.03f}};
  SpringSheet sheet(ctx(), grasper);
  const double K = sheetCentreStiffness(S::n, S::tension, S::spacing);
  const double share = kGrip / (kGrip + K);
  const std::size_t points = sheet.net.points.size();
  double f1 = 0, u1 = 0, f2 = 0, u2 = 0, f3 = 0, u3 = 0;
  sheet.runTo(0.5, 0.05, f1, u1);
  const auto grips = sheet.solver->tools()->grips().readback<glm::vec4>(points);
  for (std::uint32_t id = 0; id < grips.size(); ++id) {
    EXPECT_EQ(grips[id].w, id == S::centre ? 1.0f : 0.0f) << "id " << id << ": only the centre point is gripped";
  }
  sheet.runTo(1.0, 0.05, f2, u2);
  sheet.runTo(1.4, 0.05, f3, u3);
  std::printf("[tools] grip k %.3g N/m, sheet K %.5g N/m: lifted %.4g mm by %.3g (share %.4f, expected %.4f), F %.4g N "
              "(K u %.4g); %.4g mm by %.3g (share %.4f), F %.4g N (K u %.4g); let go: %.3g mm, F %.3g N\n",
              kGrip, K, u1 * 1e3, w1 * 1e3, u1 / w1, share, f1, K * u1, u2 * 1e3, w2 * 1e3, u2 / w2, f2, K * u2,
              u3 * 1e3, f3);
  EXPECT_NEAR(u1 / w1, share, 0.05 * share);
  EXPECT_NEAR(u2 / w2, share, 0.05 * share);
  // the sheet pulls the tool down (force z < 0)
  EXPECT_NEAR(-f1, K * u1, 0.05 * K * u1);
  EXPECT_NEAR(-f2, K * u2, 0.05 * K * u2);
  for (const glm::vec4& g : sheet.solver->tools()->grips().readback<glm::vec4>(points)) EXPECT_EQ(g.w, 0.0f);
  EXPECT_LT(std::abs(u3), 0.02 * u2);
  EXPECT_LT(std::abs(f3), 1e-3 * std::abs(f2));
}

// A blade's cut against the twin: 4,000 random springs (some broken already) in a box periodic
// along x; a blade whose edge moves and turns between two keys, cutting, and a probe that does
// not cut. Every spring the edge swept through between the clock's last two times breaks
// (except those the float test may decide either way: within 1e-4 of a boundary of the test's
// parameters), no other does, and the wall's counter counts exactly the new breaks.
TEST_F(ToolTest, BladeCutsExactlyTheSpringsItsEdgeSweeps) {
  auto rng = rngFor();
  std::uniform_real_distribution<double> u(0.0, 1.0);
  sim::SphSettings s;
  s.spacing = 0.002f;
  s.soundSpeed = 5.0f;
  const glm::dvec3 period(0.04, 0.0, 0.0);
  std::vector<sim::ToolSpec> tools(2);
  tools[0].name = "probe";
  tools[0].radius = 0.003f;
  tools[0].keys = {{0.0, {0.02f, 0.02f, 0.02f}, glm::quat(1, 0, 0, 0)}};
  tools[1].name = "blade";
  tools[1].kind = sim::ToolKind::Blade;
  tools[1].radius = 0.0005f;
  tools[1].length = 0.025f;
  tools[1].keys = {{0.0, {0.005f, 0.01f, 0.005f}, axisAngle({1, 0, 0}, -0.2f), true},
                   {1.0, {0.035f, 0.03f, 0.01f}, axisAngle({1, 1, 0}, 0.8f), false}};
  const float t1 = 0.6f, lastDt = 0.35f;

  const std::uint32_t points = 2000, springs = 4000;
  std::vector<glm::vec4> pos(points), vel(points, glm::vec4(0.0f, 0.0f, 0.0f, float(HEMO_KIND_WALL)));
  std::vector<std::uint32_t> slotOfId(points);
  for (std::uint32_t i = 0; i < points; ++i) {
    pos[i] = glm::vec4(glm::vec3(u(rng) * 0.04, u(rng) * 0.04, u(rng) * 0.04), 1e-5f);
    slotOfId[i] = i;
  }
  std::vector<sim::GpuSpring> records(springs);
  for (std::uint32_t k = 0; k < springs; ++k) {
    const std::uint32_t a = std::uint32_t(u(rng) * points) % points;
    const std::uint32_t b = (a + 1 + std::uint32_t(u(rng) * (points - 1))) % points;
    records[k] = {std::min(a, b), std::max(a, b), 0.005f, 1.0f, 0.0f, 1.0f, u(rng) < 0.05 ? 1u : 0u, 0u};
  }
  sim::ParticleStore store(ctx(), points);
  store.upload(pos, vel);
  gpu::Buffer paramsBuffer = periodicParams(ctx(), s, float(period.x));
  gpu::Buffer clock = clockAt(ctx(), {{t1, 0.0f, lastDt, 9u}, {0.9f, 0.0f, 0.0f, 0u}});
  gpu::Buffer accel(ctx(), points * 16, gpu::MemoryUse::Device, "accel");
  gpu::Buffer dtCounts(ctx(), 16, gpu::MemoryUse::Device, "dt counts");
  gpu::Buffer springBuffer(ctx(), springs * sizeof(sim::GpuSpring), gpu::MemoryUse::Device, "springs");
  springBuffer.upload(records);
  gpu::Buffer counters(ctx(), 16, gpu::MemoryUse::Device, "wall counters");
  counters.upload(std::vector<std::uint32_t>{7, 0, 0, 0});
  gpu::Buffer slots(ctx(), points * 4, gpu::MemoryUse::Device, "slot of id");
  slots.upload(slotOfId);
  sim::ToolBuffers buffers{&accel, &paramsBuffer, &clock, &dtCounts, nullptr, 0, nullptr};
  buffers.springs = &springBuffer;
  buffers.wallCounters = &counters;
  buffers.slotOfId = &slots;
  buffers.springCount = springs;
  sim::ToolContact contact(ctx(), store, buffers, tools, 1.0f, s.spacing, 4);
  ASSERT_TRUE(contact.cuts());
  gpu::CommandRecorder rec(ctx());
  rec.begin();
  contact.recordCut(rec, 0u);
  rec.end();
  rec.submitAndWait();

  const double t0d = double(t1 - lastDt), t1d = double(t1);
  const reference::RefToolPose before = reference::toolPose(tools[1], t0d), after = reference::toolPose(tools[1], t1d);
  ASSERT_TRUE(before.cutting);
  const glm::dvec3 a0 = before.position, b0 = a0 + double(tools[1].length) * before.axis;
  const glm::dvec3 a1 = after.position, b1 = a1 + double(tools[1].length) * after.axis;
  auto image = [&](glm::dvec3 d) {
    d.x -= period.x * std::round(d.x / period.x);
    return d;
  };
  const auto out = springBuffer.readback<sim::GpuSpring>(springs);
  std::uint32_t cut = 0, expectedCuts = 0, skipped = 0;
  for (std::uint32_t k = 0; k < springs; ++k) {
    const glm::dvec3 xa(pos[records[k].a]), xb(pos[records[k].b]);
    const glm::dvec3 p = a0 + image(xa - a0);
    double margin = 0.0;
    const bool crosses = reference::sweptEdgeCrosses(a0, b0, a1, b1, p, p + image(xb - xa), &margin);
    if (records[k].broken) {
      EXPECT_EQ(out[k].broken, 1u) << "spring " << k << " stays broken";
      continue;
    }
    if (out[k].broken) ++cut;
    if (std::abs(margin) < 1e-4) {
      ++skipped;
      continue;
    }
    if (crosses) ++expectedCuts;
    EXPECT_EQ(out[k].broken != 0u, crosses) << "spring " << k << " (margin " << margin << ")";
  }
  EXPECT_GT(expectedCuts, 50u);
  EXPECT_LT(skipped, 10u);
  EXPECT_EQ(counters.readback<std::uint32_t>(1)[0], 7u + cut) << "the counter adds the cuts";
}

// A blade drawn along the top of a pressurised tube, its edge through the wall: every spring
// whose segment crosses the edge's path (from the wall as built; the wall moves a few
// micrometres before the cut) breaks, and blood leaves through the slit.
TEST_F(ToolTest, BladeDrawnAcrossATubeCutsItsPathAndTheBloodLeaves) {
  const nlohmann::json j = nlohmann::json::parse(R"({
    "scene": "tube_cut",
    "particles": { "spacing_m": 5e-4 },
    "fluid": { "density_kg_m3": 1060.0, "viscosity_pa_s": 0.0035, "expected_max_speed_m_s": 0.5,
               "background_pressure_Pa": 1500.0, "background_pressure_ramp_s": 0.002 },
    "vessel": { "shape": "tube", "length_m": 0.008, "radius_m": 0.002, "point_mass_kg": 2e-5,
                "stiffness_N_m": 50.0, "damping_N_s_m": 0.005 },
    "tools": [ { "name": "blade", "kind": "blade", "radius_m": 1e-4, "length_m": 0.0025,
                 "path": [ { "time_s": 0.0, "position_m": [0.0005, 0.0, 0.0015] },
                           { "time_s": 0.003, "position_m": [0.0005, 0.0, 0.0015], "cutting": true },
                           { "time_s": 0.008, "position_m": [0.0075, 0.0, 0.0015] } ] } ],
    "forces": { "gravity_m_s2": [0, 0, 0] },
    "time": { "steps_per_batch": 32, "end_time_s": 0.025 },
    "domain": { "min_m": [0.0, -0.008, -0.008], "max_m": [0.008, 0.008, 0.012], "periodic": ["x"] }
  })");
  const scene::Scene sc = scene::parseScene(j.dump(), "tube_cut.json");
  sim::Simulation sim(ctx(), sc);
  ASSERT_NE(sim.solver().wall(), nullptr);
  // the wall as built, by id
  const auto pos0 = sim.store().readPositions();
  const auto ids0 = sim.store().readIds();
  std::vector<glm::dvec3> byId(pos0.size());
  for (std::size_t slot = 0; slot < pos0.size(); ++slot) byId[ids0[slot]] = glm::dvec3(pos0[slot]);
  const auto springs = sim.solver().wall()->readSprings();
  // the edge's path: from x = 0.5 to 7.5 mm at y = 0, z from 1.5 to 4 mm
  const glm::dvec3 a0(0.0005, 0.0, 0.0015), b0(0.0005, 0.0, 0.004), a1(0.0075, 0.0, 0.0015), b1(0.0075, 0.0, 0.004);
  std::vector<std::uint32_t> onPath;
  for (std::uint32_t k = 0; k < springs.size(); ++k) {
    double margin = 0.0;
    // (the spring is the minimum image across the periodic seam at x = 0)
    const glm::dvec3 p = byId[springs[k].a];
    glm::dvec3 d = byId[springs[k].b] - p;
    d.x -= 0.008 * std::round(d.x / 0.008);
    if (reference::sweptEdgeCrosses(a0, b0, a1, b1, p, p + d, &margin) && margin > 0.05) {
      onPath.push_back(k);
    }
  }
  ASSERT_GT(onPath.size(), 20u);
  sim.run({});
  const auto after = sim.solver().wall()->readSprings();
  std::uint32_t cut = 0;
  for (std::uint32_t k : onPath) cut += after[k].broken;
  EXPECT_EQ(cut, onPath.size()) << "springs on the blade's path left whole";
  // blood leaves through the slit: fluid beyond the wall's outer layer, all of it on top
  const sim::Snapshot snap = sim.snapshot();
  std::uint32_t out = 0, below = 0;
  for (std::size_t i = 0; i < snap.positions.size(); ++i) {
    if (std::uint32_t(snap.velocities[i].w) != HEMO_KIND_FLUID) continue;
    const glm::vec3 x(snap.positions[i]);
    if (std::hypot(x.y, x.z) > 0.002 + 3 * 5e-4) {
      ++out;
      if (x.z < 0.0f) ++below;
    }
  }
  std::printf("[tools] tube cut: %zu springs on the path, %u broken in all; %u fluid particles outside the wall by %.3f s "
              "(%u escaped)\n",
              onPath.size(), sim.brokenSprings(), out, sim.time(), sim.escapedParticles());
  EXPECT_GE(out, 5u) << "blood leaves through the cut";
  EXPECT_EQ(below, 0u) << "only through the cut";
}

// The clamp tests' tube and grasper (the periodic, body-force-driven form).
nlohmann::json clampTube() {
  return nlohmann::json::parse(R"({
    "scene": "tube_clamp",
    "particles": { "spacing_m": 5e-4, "neighbour_capacity": 256 },
    "fluid": { "density_kg_m3": 1060.0, "viscosity_pa_s": 0.106, "expected_max_speed_m_s": 0.5,
               "background_pressure_Pa": 300.0, "background_pressure_ramp_s": 0.002 },
    "vessel": { "shape": "tube", "length_m": 0.032, "radius_m": 0.0015, "point_mass_kg": 2e-5,
                "stiffness_N_m": 50.0, "damping_N_s_m": 0.005 },
    "tools": [ { "name": "clamp", "kind": "grasper", "radius_m": 5e-4, "length_m": 0.008, "jaw_width_m": 0.001,
                 "contact_scale": 0.1,
                 "path": [ { "time_s": 0.0, "position_m": [0.016, 0.0, -0.004], "orientation_wxyz": [0.70710678, 0, 0, 0.70710678],
                             "jaw_opening_m": 0.007 },
                           { "time_s": 0.03, "position_m": [0.016, 0.0, -0.004], "orientation_wxyz": [0.70710678, 0, 0, 0.70710678],
                             "jaw_opening_m": 0.007 },
                           { "time_s": 0.05, "position_m": [0.016, 0.0, -0.004], "orientation_wxyz": [0.70710678, 0, 0, 0.70710678],
                             "jaw_opening_m": 0.0005 } ] } ],
    "forces": { "gravity_m_s2": [0, 0, 0], "body_force_m_s2": [20.0, 0, 0] },
    "time": { "steps_per_batch": 64, "end_time_s": 0.12 },
    "domain": { "min_m": [0.0, -0.008, -0.008], "max_m": [0.032, 0.008, 0.008], "periodic": ["x"] }
  })");
}

// A clamp on a tube with flow: a periodic tube (32 mm, radius 1.5 mm) whose blood a body force
// drives (a pressure gradient the clamp can hold, where the inflow's pump would set the flow
// rate whatever the pressure). A grasper with flat jaws across it, open, lets the flow develop;
// closed between 0.03 and 0.05 s, it squeezes the tube shut and grips its wall. The flux, the
// blood's mean axial speed in the loop (the rate of its mean displacement, which on a closed
// loop is every cross-section's flux averaged in time: a local rise or fall of the lumen's
// volume near one section does not count), falls from its open value to under 5% of it.
TEST_F(ToolTest, ClampClosedOnATubeStopsTheFlow) {
  const nlohmann::json j = clampTube();
  const scene::Scene sc = scene::parseScene(j.dump(), "tube_clamp.json");
  ASSERT_FLOAT_EQ(sc.tools[0].gripStiffness, 50.0f) << "a grasper grips with the vessel's spring stiffness by default";
  sim::Simulation sim(ctx(), sc);
  // the blood's mean axial displacement (each batch's steps, minimum image) and the net
  // crossings of the lumen's section 8 mm past the jaws, against time
  const float period = 0.032f, section = 0.024f;
  std::vector<glm::vec4> last;
  std::vector<double> times, shift, crossed;
  std::uint32_t grippedMax = 0;
  sim::RunOptions options;
  options.onBatch = [&](const sim::Progress&) {
    const sim::Snapshot snap = sim.snapshot();
    if (!last.empty()) {
      double sum = 0.0;
      int count = 0, net = 0;
      for (std::size_t i = 0; i < snap.positions.size(); ++i) {
        if (std::uint32_t(snap.velocities[i].w) != HEMO_KIND_FLUID) continue;
        const glm::vec4 a = last[i], b = snap.positions[i];
        if (std::hypot(a.y, a.z) > 0.0035f || std::hypot(b.y, b.z) > 0.0035f) continue;  // (blood that left the tube)
        const float dx = (b.x - a.x) - period * std::round((b.x - a.x) / period);
        sum += dx;
        ++count;
        if (std::abs(b.x - a.x) < 0.5f * period && std::hypot(b.y, b.z) < 0.002f) {
          net += (a.x < section && b.x >= section) ? 1 : (a.x >= section && b.x < section) ? -1 : 0;
        }
      }
      times.push_back(sim.time());
      shift.push_back((shift.empty() ? 0.0 : shift.back()) + sum / std::max(count, 1));
      crossed.push_back((crossed.empty() ? 0.0 : crossed.back()) + net);
    }
    last = snap.positions;
    if (sim.time() > 0.05) {
      std::uint32_t gripped = 0;
      for (const glm::vec4& g : sim.solver().tools()->grips().readback<glm::vec4>(sim.solver().wall()->pointCount())) {
        gripped += g.w == 1.0f;
      }
      grippedMax = std::max(grippedMax, gripped);
    }
  };
  sim.run(options);
  // least-squares slopes over [from, to]
  auto slope = [&](const std::vector<double>& y, double from, double to) {
    double st = 0.0, sy = 0.0, stt = 0.0, sty = 0.0;
    int n = 0;
    for (std::size_t i = 0; i < times.size(); ++i) {
      if (times[i] < from || times[i] > to) continue;
      st += times[i], sy += y[i], stt += times[i] * times[i], sty += times[i] * y[i], ++n;
    }
    return n > 2 ? (n * sty - st * sy) / (n * stt - st * st) : 0.0;
  };
  const double openSpeed = slope(shift, 0.015, 0.03), closedSpeed = slope(shift, 0.06, 0.12);
  const double openCross = slope(crossed, 0.015, 0.03), closedCross = slope(crossed, 0.06, 0.12);
  std::printf("[tools] clamp: the blood's mean speed open %.4g m/s, closed %.3g m/s (ratio %.4f); net crossings of the section "
              "8 mm downstream open %.4g /s, closed %.3g /s (ratio %.3f); %u wall points gripped; %u escaped, %u broken "
              "springs\n",
              openSpeed, closedSpeed, closedSpeed / openSpeed, openCross, closedCross, closedCross / openCross, grippedMax,
              sim.escapedParticles(), sim.brokenSprings());
  EXPECT_GT(openSpeed, 0.04) << "the open tube carries the flow (Poiseuille: G R^2 / 8 nu = 0.056 m/s)";
  EXPECT_LT(std::abs(closedSpeed), 0.05 * openSpeed);
  EXPECT_GT(grippedMax, 20u) << "the jaws hold the wall they squeeze";
}
// The same clamp on a tube with open ends, its flow driven by a pressure drop from a
// pressure inlet to a pressure outlet (hemo/sim/inflow.hpp; the drop is the body force's
// above over the lumen's length): the outflow the GPU counts at the outlet plane, closed,
// falls under 5% of what it was open.
TEST_F(ToolTest, ClampClosedOnAnOpenTubeStopsTheOutflow) {
  nlohmann::json j = clampTube();
  j["scene"] = "open_tube_clamp";
  j["vessel"]["inflow"] = {{"profile", "parabolic"}, {"driven_by", "pressure"}, {"pressure_Pa", 594.0},
                           {"zone_length_m", 0.002}, {"ramp_s", 0.005}};
  j["vessel"]["outlet"] = {{"condition", "pressure"}};
  j["forces"].erase("body_force_m_s2");
  j["domain"].erase("periodic");
  const scene::Scene sc = scene::parseScene(j.dump(), "open_tube_clamp.json");
  sim::Simulation sim(ctx(), sc);
  // the net outflow (particles across the outlet plane) against time
  std::vector<double> times, out;
  sim::RunOptions options;
  options.onBatch = [&](const sim::Progress&) {
    const auto o = sim.openCounts();
    times.push_back(sim.time());
    out.push_back(double(o.out) - double(o.outBack));
  };
  sim.run(options);
  auto slope = [&](double from, double to) {
    double st = 0.0, sy = 0.0, stt = 0.0, sty = 0.0;
    int n = 0;
    for (std::size_t i = 0; i < times.size(); ++i) {
      if (times[i] < from || times[i] > to) continue;
      st += times[i], sy += out[i], stt += times[i] * times[i], sty += times[i] * out[i], ++n;
    }
    return n > 2 ? (n * sty - st * sy) / (n * stt - st * st) : 0.0;
  };
  const double open = slope(0.015, 0.03), closed = slope(0.08, 0.12);
  std::printf("[tools] clamp on an open tube: outflow open %.4g /s, closed %.3g /s (ratio %.4f); %u escaped, %u broken springs\n",
              open, closed, closed / open, sim.escapedParticles(), sim.brokenSprings());
  EXPECT_GT(open, 1000.0) << "the open tube carries the pressure-driven flow";
  EXPECT_LT(std::abs(closed), 0.05 * open);
}

// RunOptions::pipelined: a second batch recorded and submitted while the first runs gives
// the same particles, the same clock and the same tool log, row for row, as one batch at a
// time, both for a number of steps and to an end time inside a batch (the batch in flight
// then changes nothing). Synchronization validation watches the two command buffers in
// flight.
TEST_F(ToolTest, PipelinedRunsMatchOneBatchAtATime) {
  const scene::Scene scene = scene::loadScene(std::string(HEMO_SOURCE_DIR) + "/tests/cli/tiny_tank_probe.json");
  for (const bool toEndTime : {false, true}) {
    std::vector<sim::ToolLogRow> rows[2];
    sim::Snapshot states[2];
    std::uint64_t steps[2];
    double times[2];
    for (int pipelined = 0; pipelined < 2; ++pipelined) {
      sim::Simulation sim(ctx(), scene);
      sim::RunOptions run;
      run.pipelined = pipelined == 1;
      if (toEndTime) {
        run.until = 0.0437;  // inside a batch
      } else {
        run.steps = 16 * 7 + 5;  // a short last batch
      }
      std::uint64_t batches = 0;
      run.onBatch = [&](const sim::Progress&) { ++batches; };
      run.onToolLog = [&](const std::vector<sim::ToolLogRow>& batch) {
        rows[pipelined].insert(rows[pipelined].end(), batch.begin(), batch.end());
      };
      const sim::RunResult result = sim.run(run);
      steps[pipelined] = result.steps;
      times[pipelined] = sim.time();
      states[pipelined] = sim.snapshot();
      EXPECT_GT(batches, 5u);
      EXPECT_EQ(sim.toolFeedback().samples, result.steps);
    }
    const char* what = toEndTime ? "to an end time" : "a number of steps";
    EXPECT_EQ(steps[0], steps[1]) << what;
    EXPECT_EQ(times[0], times[1]) << what;
    if (toEndTime) {
      EXPECT_GE(times[0], double(float(0.0437)));  // (the clock stops at the end time as a float)
    } else {
      EXPECT_EQ(steps[0], 16u * 7 + 5);
    }
    EXPECT_EQ(states[0].positions, states[1].positions) << what;
    EXPECT_EQ(states[0].velocities, states[1].velocities) << what;
    ASSERT_EQ(rows[0].size(), rows[1].size()) << what;
    ASSERT_EQ(rows[0].size(), steps[0]) << what;  // one tool
    for (std::size_t k = 0; k < rows[0].size(); ++k) {
      ASSERT_EQ(rows[0][k].step, rows[1][k].step);
      ASSERT_EQ(rows[0][k].step, k);
      ASSERT_EQ(std::memcmp(&rows[0][k].sample, &rows[1][k].sample, sizeof(sim::ToolSample)), 0) << what << ", row " << k;
    }
    std::printf("pipelined, %s: %llu steps to t = %.6f s, %zu tool rows, the same\n", what,
                static_cast<unsigned long long>(steps[0]), times[0], rows[0].size());
  }
}

}  // namespace
}  // namespace hemo::test
