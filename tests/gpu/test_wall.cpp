// The vessel wall's mass-spring stages: against the double-precision reference on random
// networks, and against analytic spring dynamics (period, hanging chain, rupture).
#include "gpu_test.hpp"
#include "hemo/reference/springs.hpp"
#include "hemo/sim/sph.hpp"
#include "interface/sph.h"

#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>
#include <memory>
#include <numbers>
#include <set>

namespace hemo::test {
namespace {

// Settings for scenes of wall particles only: c0 = 1 m/s, so the acoustic limit
// (0.3 h / c0 = 3.9 ms) stays above the springs' limits in these tests.
sim::SphSettings wallSettings(glm::vec3 gravity) {
  sim::SphSettings s;
  s.spacing = 0.01f;
  s.soundSpeed = 1.0f;
  s.gravity = gravity;
  s.maxTimeStep = 1.0f;
  return s;
}

struct WallRun {
  std::unique_ptr<sim::ParticleStore> store;
  std::unique_ptr<sim::SphSolver> solver;
  gpu::CommandRecorder* rec = nullptr;
  std::uint32_t step = 0;
};

class WallTest : public GpuTest {
 protected:
  // Wall particles at `x` (ids = index) with velocities `v`, the network attached.
  void setUp(const std::vector<glm::vec3>& x, const std::vector<glm::vec3>& v, const sim::SpringNetwork& net,
             const sim::SphSettings& s, glm::vec3 lo, glm::vec3 hi) {
    const auto n = static_cast<std::uint32_t>(x.size());
    store_ = std::make_unique<sim::ParticleStore>(ctx(), n);
    std::vector<glm::vec4> pos(n), vel(n);
    for (std::uint32_t i = 0; i < n; ++i) {
      pos[i] = glm::vec4(x[i], s.particleMass());
      vel[i] = glm::vec4(v[i], float(HEMO_KIND_WALL));
    }
    store_->upload(pos, vel);
    solver_ = std::make_unique<sim::SphSolver>(ctx(), *store_, lo, hi, s);
    solver_->attachWall(net);
    rec_ = std::make_unique<gpu::CommandRecorder>(ctx());
    rec_->begin();
    solver_->recordReset(*rec_);
    rec_->end();
    rec_->submitAndWait();
  }
  void steps(int count) {
    for (int done = 0; done < count;) {
      const int batch = std::min(count - done, 200);
      rec_->begin();
      for (int k = 0; k < batch; ++k) solver_->recordStep(*rec_, step_++, std::uint32_t(k));
      rec_->end();
      rec_->submitAndWait();
      done += batch;
    }
  }
  // Positions by id.
  std::vector<glm::vec4> positionsById() const {
    const auto pos = store_->readPositions();
    const auto ids = store_->readIds();
    std::vector<glm::vec4> out(pos.size());
    for (std::size_t s = 0; s < pos.size(); ++s) out[ids[s]] = pos[s];
    return out;
  }
  double time() const { return solver_->readClock().time; }

  std::unique_ptr<sim::ParticleStore> store_;
  std::unique_ptr<sim::SphSolver> solver_;
  std::unique_ptr<gpu::CommandRecorder> rec_;
  std::uint32_t step_ = 0;
};

// Random network (3 springs per point to random others, a fifth of them weak enough to break
// now, a tenth of the points anchored, random velocities and damping): rupture flags, spring
// accelerations and time-step limits match the reference.
TEST_F(WallTest, RandomNetworkMatchesReference) {
  auto rng = rngFor();
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const std::uint32_t n = 300;
  std::vector<glm::vec3> x(n), v(n);
  sim::SpringNetwork net;
  net.points.resize(n);
  for (std::uint32_t i = 0; i < n; ++i) {
    x[i] = glm::vec3(u(rng), u(rng), u(rng)) * 0.1f;
    v[i] = glm::vec3(u(rng) - 0.5, u(rng) - 0.5, u(rng) - 0.5) * 0.2f;
    net.points[i] = {float(0.001 + 0.01 * u(rng)), u(rng) < 0.1};
  }
  std::vector<glm::dvec3> dx(n), dv(n);
  for (std::uint32_t i = 0; i < n; ++i) dx[i] = glm::dvec3(x[i]), dv[i] = glm::dvec3(v[i]);
  std::set<std::pair<std::uint32_t, std::uint32_t>> used;
  std::vector<reference::RefSpring> ref;
  std::size_t weak = 0;
  for (std::uint32_t i = 0; i < n; ++i) {
    for (int e = 0; e < 3; ++e) {
      const auto j = static_cast<std::uint32_t>(u(rng) * n) % n;
      if (j == i || !used.insert({std::min(i, j), std::max(i, j)}).second) continue;
      sim::Spring s{i, j, float(glm::length(dx[i] - dx[j]) * (0.8 + 0.4 * u(rng))), float(10 + 90 * u(rng)),
                    float(0.5 * u(rng)), 3.0e38f};
      reference::RefSpring r{std::min(i, j), std::max(i, j), s.restLength, s.stiffness, s.damping, 0.0, false};
      const double tension = reference::springTension(r, dx, dv);
      if (u(rng) < 0.2 && tension > 0.1) {
        s.maxForce = float(0.5 * tension);  // breaks now
        ++weak;
      } else {
        s.maxForce = float(2.0 * std::abs(tension) + 1.0);  // holds
      }
      r.maxForce = s.maxForce;
      net.springs.push_back(s);
      ref.push_back(r);
    }
  }
  ASSERT_GT(weak, 20u);
  const sim::SphSettings s = wallSettings({0.0f, -1.0f, -9.81f});
  setUp(x, v, net, s, glm::vec3(-0.05f), glm::vec3(0.15f));
  rec_->begin();
  solver_->recordNeighbours(*rec_);
  solver_->recordDensity(*rec_);
  solver_->recordForces(*rec_);
  rec_->end();
  rec_->submitAndWait();

  const std::uint32_t broke = reference::rupture(ref, dx, dv);
  EXPECT_EQ(broke, weak);
  EXPECT_EQ(solver_->wall()->readBrokenCount(), broke);
  const auto springs = solver_->wall()->readSprings();
  ASSERT_EQ(springs.size(), ref.size());
  for (std::size_t k = 0; k < ref.size(); ++k) EXPECT_EQ(springs[k].broken != 0, ref[k].broken) << "spring " << k;

  std::vector<double> mass(n);
  std::vector<bool> anchored(n);
  for (std::uint32_t i = 0; i < n; ++i) mass[i] = net.points[i].mass, anchored[i] = net.points[i].anchored;
  const auto acc = reference::springAccelerations(ref, dx, dv, mass, anchored, glm::dvec3(s.gravity));
  double scale = 0.0;
  for (const auto& a : acc) scale = std::max(scale, glm::length(a));
  ASSERT_GT(scale, 100.0);
  const auto ids = store_->readIds();
  const auto accel = solver_->accel().readback<glm::vec4>(n);
  const auto limits = solver_->dtLimits().readback<float>(n);
  std::vector<double> stiffness(n, 0.0);
  for (const auto& r : ref) {
    if (!r.broken) stiffness[r.a] += r.stiffness, stiffness[r.b] += r.stiffness;
  }
  for (std::uint32_t slot = 0; slot < n; ++slot) {
    const std::uint32_t i = ids[slot];
    EXPECT_LT(glm::length(glm::dvec3(accel[slot]) - acc[i]), 1e-5 * scale) << "point " << i;
    const double acoustic = s.cflAcoustic * s.h() / (s.soundSpeed + glm::length(dv[i]));
    const double want = anchored[i] ? 3.0e38 : stiffness[i] > 0 ? std::min(acoustic, 0.1 * std::sqrt(mass[i] / stiffness[i])) : acoustic;
    EXPECT_NEAR(limits[slot], want, 1e-5 * want) << "time-step limit of point " << i;
  }
}

// One spring from an anchored point: a mass oscillates with period 2 pi sqrt(m/k) (0.5%).
TEST_F(WallTest, SpringOscillatesWithTheAnalyticPeriod) {
  const float m = 0.01f, k = 100.0f, rest = 0.05f, amplitude = 0.01f;
  sim::SpringNetwork net;
  net.points = {{m, true}, {m, false}};
  net.springs = {{0, 1, rest, k, 0.0f, 3.0e38f}};
  setUp({glm::vec3(0.0f), glm::vec3(rest + amplitude, 0.0f, 0.0f)}, {glm::vec3(0.0f), glm::vec3(0.0f)}, net,
        wallSettings(glm::vec3(0.0f)), glm::vec3(-0.1f), glm::vec3(0.1f));
  const double period = 2.0 * std::numbers::pi * std::sqrt(double(m) / k);
  // Two steps per submit (~30 samples per period), recording x(t); upward zero crossings of
  // x - rest, interpolated linearly (x is nearly linear in t there).
  std::vector<double> crossings;
  double prevT = 0.0, prevX = amplitude;
  while (crossings.size() < 6) {
    steps(2);
    const double t = time();
    const double xr = positionsById()[1].x - rest;
    if (prevX < 0.0 && xr >= 0.0) crossings.push_back(prevT + (t - prevT) * (-prevX) / (xr - prevX));
    prevT = t;
    prevX = xr;
    ASSERT_LT(t, 10.0 * period) << "no oscillation";
  }
  const double measured = (crossings.back() - crossings.front()) / double(crossings.size() - 1);
  RecordProperty("period_ratio", std::to_string(measured / period));
  EXPECT_NEAR(measured, period, 0.005 * period) << "steps per period ~" << period / solver_->readClock().lastDt;
}

// A chain of 10 points hanging from an anchored top point settles (global damping phase) to
// the static stretch: the spring above point i carries the weight of the points below it.
TEST_F(WallTest, HangingChainSettlesToTheStaticStretch) {
  const int count = 10;
  const float m = 0.002f, k = 50.0f, rest = 0.02f, g = 9.81f;
  sim::SpringNetwork net;
  std::vector<glm::vec3> x, v(count, glm::vec3(0.0f));
  for (int i = 0; i < count; ++i) {
    net.points.push_back({m, i == 0});
    x.emplace_back(0.0f, 0.0f, -rest * float(i));
    if (i > 0) net.springs.push_back({std::uint32_t(i - 1), std::uint32_t(i), rest, k, 0.0f, 3.0e38f});
  }
  sim::SphSettings s = wallSettings({0.0f, 0.0f, -g});
  s.dampingRate = 20.0f;  // 1/s, above the lowest mode's angular frequency (~7/s)
  s.dampingUntil = 100.0f;
  setUp(x, v, net, s, glm::vec3(-0.1f, -0.1f, -0.4f), glm::vec3(0.1f, 0.1f, 0.1f));
  steps(6000);  // dt ~ 0.1 sqrt(m / 2k) = 0.45 ms: ~2.7 s
  ASSERT_GT(time(), 2.0);
  const auto p = positionsById();
  for (int i = 1; i < count; ++i) {
    const double stretch = double(p[i - 1].z - p[i].z) - rest;
    const double expect = double(count - i) * m * g / k;
    EXPECT_NEAR(stretch, expect, 0.01 * expect) << "spring above point " << i;
  }
}

// A spring weaker than the weight it holds breaks on the first step, stays broken (counted
// once) and the point falls freely from then on.
TEST_F(WallTest, OverloadedSpringBreaksForGoodAndReleasesItsPoint) {
  const float m = 0.01f, g = 9.81f;
  sim::SpringNetwork net;
  net.points = {{m, true}, {m, false}};
  const float k = 10.0f, rest = 0.05f;
  net.springs = {{0, 1, rest, k, 0.0f, 0.5f * m * g}};
  sim::SphSettings s = wallSettings({0.0f, 0.0f, -g});
  s.maxTimeStep = 1e-3f;
  // Start stretched so the tension (0.55 m g) exceeds the limit at once.
  setUp({glm::vec3(0.0f), glm::vec3(0.0f, 0.0f, -rest - 0.55f * m * g / k)},
        {glm::vec3(0.0f), glm::vec3(0.0f)}, net, s, glm::vec3(-0.1f, -0.1f, -1.0f), glm::vec3(0.1f));
  const double z0 = positionsById()[1].z;
  steps(100);
  EXPECT_EQ(solver_->wall()->readBrokenCount(), 1u);
  EXPECT_EQ(solver_->wall()->readSprings()[0].broken, 1u);
  const double t = time();
  const double fall = z0 - positionsById()[1].z;
  // Symplectic Euler with constant dt falls g t (t + dt) / 2.
  const double dt = solver_->readClock().lastDt;
  EXPECT_NEAR(fall, 0.5 * g * t * (t + dt), 1e-3 * fall);
  EXPECT_EQ(positionsById()[0], glm::vec4(0.0f, 0.0f, 0.0f, s.particleMass())) << "the anchor moved";
}

}  // namespace
}  // namespace hemo::test
