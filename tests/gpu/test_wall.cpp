// The vessel wall's mass-spring stages: against the double-precision reference on random
// networks, and against analytic spring dynamics (period, hanging chain, rupture).
#include "gpu_test.hpp"
#include "sph_model.hpp"
#include "hemo/reference/sph.hpp"
#include "hemo/reference/springs.hpp"
#include "hemo/scene/fusiform.hpp"
#include "hemo/scene/statics.hpp"
#include "hemo/scene/tube.hpp"
#include "hemo/sim/sph.hpp"
#include "interface/sph.h"

#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
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
  // Uploads the particles (ids = index), builds the solver on [lo, hi], attaches the network
  // and resets.
  void setUp(const std::vector<glm::vec4>& pos, const std::vector<glm::vec4>& vel, const std::vector<glm::vec4>& normals,
             const sim::SpringNetwork& net, const sim::SphSettings& s, glm::vec3 lo, glm::vec3 hi) {
    store_ = std::make_unique<sim::ParticleStore>(ctx(), static_cast<std::uint32_t>(pos.size()));
    store_->upload(pos, vel, {}, normals);
    solver_ = std::make_unique<sim::SphSolver>(ctx(), *store_, lo, hi, s);
    solver_->attachWall(net);
    rec_ = std::make_unique<gpu::CommandRecorder>(ctx());
    rec_->begin();
    solver_->recordReset(*rec_);
    rec_->end();
    rec_->submitAndWait();
  }
  // Wall particles only, at `x` with velocities `v`.
  void setUp(const std::vector<glm::vec3>& x, const std::vector<glm::vec3>& v, const sim::SpringNetwork& net,
             const sim::SphSettings& s, glm::vec3 lo, glm::vec3 hi) {
    std::vector<glm::vec4> pos(x.size()), vel(x.size());
    for (std::size_t i = 0; i < x.size(); ++i) {
      pos[i] = glm::vec4(x[i], s.particleMass());
      vel[i] = glm::vec4(v[i], float(HEMO_KIND_WALL));
    }
    setUp(pos, vel, {}, net, s, lo, hi);
  }
  // One force evaluation from scratch (grid, list, density, forces with the wall stages).
  void evaluate() {
    rec_->begin();
    solver_->recordNeighbours(*rec_);
    solver_->recordDensity(*rec_);
    solver_->recordForces(*rec_);
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
// accelerations and time-step limits match the reference. The domain is periodic in x, and
// the points fill its whole period, so many springs span the seam (minimum image).
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
      glm::dvec3 sep = dx[i] - dx[j];
      sep.x -= 0.1 * std::round(sep.x / 0.1);  // the spring's length across the periodic x
      sim::Spring s{i, j, float(glm::length(sep) * (0.8 + 0.4 * u(rng))), float(10 + 90 * u(rng)),
                    float(0.5 * u(rng)), 3.0e38f};
      reference::RefSpring r{std::min(i, j), std::max(i, j), s.restLength, s.stiffness, s.damping, 0.0, false};
      const double tension = reference::springTension(r, dx, dv, nullptr, glm::dvec3(0.1, 0.0, 0.0));
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
  sim::SphSettings s = wallSettings({0.0f, -1.0f, -9.81f});
  s.periodic = {true, false, false};
  setUp(x, v, net, s, glm::vec3(0.0f, -0.05f, -0.05f), glm::vec3(0.1f, 0.15f, 0.15f));
  const glm::dvec3 period(0.1, 0.0, 0.0);
  std::size_t acrossSeam = 0;
  for (const auto& r : ref) acrossSeam += std::abs(dx[r.a].x - dx[r.b].x) > 0.05;
  EXPECT_GT(acrossSeam, 100u);
  evaluate();

  const std::uint32_t broke = reference::rupture(ref, dx, dv, period);
  EXPECT_EQ(broke, weak);
  EXPECT_EQ(solver_->wall()->readBrokenCount(), broke);
  const auto springs = solver_->wall()->readSprings();
  ASSERT_EQ(springs.size(), ref.size());
  for (std::size_t k = 0; k < ref.size(); ++k) EXPECT_EQ(springs[k].broken != 0, ref[k].broken) << "spring " << k;

  std::vector<double> mass(n);
  std::vector<bool> anchored(n);
  for (std::uint32_t i = 0; i < n; ++i) mass[i] = net.points[i].mass, anchored[i] = net.points[i].anchored;
  const auto acc = reference::springAccelerations(ref, dx, dv, mass, anchored, glm::dvec3(s.gravity), period);
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
  // The time step's reduction, begun by the fluid's force pass and completed by the wall
  // stage: the smallest limit is a wall particle's.
  EXPECT_EQ(solver_->stepLimits().readback<float>(1)[0], *std::min_element(limits.begin(), limits.end()));

  // The renderer's wall shade (wall/point_shade.comp): per point, the largest strain of its
  // unbroken springs (0 if none is stretched) and the fraction of its springs broken.
  rec_->begin();
  solver_->wall()->recordShade(*rec_, n);
  rec_->end();
  rec_->submitAndWait();
  const auto shade = solver_->wall()->shade().readback<glm::vec2>(n);
  std::vector<double> strain(n, 0.0), total(n, 0.0), broken(n, 0.0);
  for (const auto& r : ref) {
    total[r.a] += 1, total[r.b] += 1;
    if (r.broken) {
      broken[r.a] += 1, broken[r.b] += 1;
      continue;
    }
    glm::dvec3 d = dx[r.b] - dx[r.a];
    d.x -= 0.1 * std::round(d.x / 0.1);
    const double e = glm::length(d) / r.restLength - 1.0;
    strain[r.a] = std::max(strain[r.a], e), strain[r.b] = std::max(strain[r.b], e);
  }
  std::size_t stretched = 0, partlyBroken = 0;
  for (std::uint32_t slot = 0; slot < n; ++slot) {
    const std::uint32_t i = ids[slot];
    EXPECT_NEAR(shade[slot].x, strain[i], 1e-5 * std::max(1.0, strain[i])) << "strain of point " << i;
    EXPECT_NEAR(shade[slot].y, total[i] > 0 ? broken[i] / total[i] : 0.0, 1e-6) << "broken fraction of point " << i;
    stretched += strain[i] > 0.05;
    partlyBroken += broken[i] > 0;
  }
  EXPECT_GT(stretched, 50u);
  EXPECT_GT(partlyBroken, 20u);
}

// A sheet of wall particles (two layers, springs to the lattice and diagonal neighbours and
// across the layers, random masses, a few anchored) under a jittered, compressed block of fluid with random velocities.
struct CoupledCase {
  std::vector<glm::vec4> pos, vel, normals;  // ids = index: wall particles first
  std::uint32_t wall = 0;
  sim::SpringNetwork net;
};

CoupledCase coupledCase(std::mt19937_64& rng, const sim::SphSettings& s, int nx, int ny, int nz, float speed,
                        float wallSpeed = 0.1f, float restJitter = 0.1f, float squeeze = 0.95f) {
  CoupledCase c;
  const float dp = s.spacing, m = s.particleMass();
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  auto index = [&](int i, int j, int layer) { return std::uint32_t((layer * (ny + 4) + (j + 2)) * (nx + 4) + (i + 2)); };
  for (int layer = 0; layer < 2; ++layer)
    for (int j = -2; j < ny + 2; ++j)
      for (int i = -2; i < nx + 2; ++i) {
        c.pos.emplace_back((i + 0.5f) * dp, (j + 0.5f) * dp, -(layer + 0.5f) * dp, m);
        c.vel.emplace_back(glm::vec3(u(rng) - 0.5f, u(rng) - 0.5f, u(rng) - 0.5f) * wallSpeed, float(HEMO_KIND_WALL));
        c.normals.emplace_back(0.0f, 0.0f, 1.0f, 0.0f);
        c.net.points.push_back({0.5f * m + m * u(rng), u(rng) < 0.05f});
      }
  c.wall = static_cast<std::uint32_t>(c.pos.size());
  for (int layer = 0; layer < 2; ++layer)
    for (int j = -2; j < ny + 2; ++j)
      for (int i = -2; i < nx + 2; ++i) {
        const std::uint32_t a = index(i, j, layer);
        auto link = [&](std::uint32_t b) {
          const float rest = glm::length(glm::vec3(c.pos[a]) - glm::vec3(c.pos[b])) * (1.0f + restJitter * (2.0f * u(rng) - 1.0f));
          c.net.springs.push_back({a, b, rest, 50.0f + 50.0f * u(rng), 0.01f * u(rng), 3.0e38f});
        };
        if (i + 1 < nx + 2) link(index(i + 1, j, layer));
        if (j + 1 < ny + 2) link(index(i, j + 1, layer));
        if (i + 1 < nx + 2 && j + 1 < ny + 2) link(index(i + 1, j + 1, layer));  // shear
        if (i + 1 < nx + 2 && j > -2) link(index(i + 1, j - 1, layer));
        if (layer == 0) {
          link(index(i, j, 1));
          if (i + 1 < nx + 2) link(index(i + 1, j, 1));  // bending: diagonals between the layers
          if (i > -2) link(index(i - 1, j, 1));
          if (j + 1 < ny + 2) link(index(i, j + 1, 1));
          if (j > -2) link(index(i, j - 1, 1));
        }
      }
  std::uniform_real_distribution<float> jitter(-0.15f * dp, 0.15f * dp);
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i) {
        const glm::vec3 x = glm::vec3((i + 0.5f) * dp, (j + 0.5f) * dp, (k + 0.45f) * dp) * squeeze +
                            glm::vec3(jitter(rng), jitter(rng), jitter(rng));
        c.pos.emplace_back(x, m);
        c.vel.emplace_back(glm::vec3(u(rng) - 0.5f, u(rng) - 0.5f, u(rng) - 0.5f) * speed, float(HEMO_KIND_FLUID));
        c.normals.emplace_back(0.0f);
      }
  return c;
}

// Fluid over a wall sheet: the fluid's accelerations (wall particles act as boundary
// particles) and the wall's (springs + the reaction of every force the fluid felt from it,
// over its mass, + gravity) match the double-precision references.
TEST_F(WallTest, FluidAndWallAccelerationsMatchReference) {
  auto rng = rngFor();
  sim::SphSettings s = wallSettings({0.0f, -1.0f, -9.81f});
  s.soundSpeed = 20.0f;
  s.viscosity = 0.05f;  // large, so the viscous reaction is visible
  CoupledCase c = coupledCase(rng, s, 8, 7, 6, 0.6f);
  // The lumen area each wall point carries the shear of.
  for (std::size_t i = 0; i < c.net.points.size(); ++i) c.net.points[i].shearArea = (0.4f + 0.2f * float(i % 4)) * s.spacing * s.spacing;
  const auto n = static_cast<std::uint32_t>(c.pos.size());
  // the fluid's list read four entries per texel (capacity 128) and one (capacity 130), the
  // fluid's clusters (interface/sph.h), and no list (the passes walking cells); and
  // non-Newtonian blood (each fluid particle's viscosity from its shear rate: the reaction
  // and the wall shear take the fluid particle's), with the list and walking cells
  struct Variant {
    sim::ListLayout layout;
    std::uint32_t capacity;
    sim::NeighbourSearch search = sim::NeighbourSearch::List;
    bool carreau = false;
  };
  for (const Variant variant : {Variant{sim::ListLayout::Contiguous, 128u}, Variant{sim::ListLayout::Contiguous, 130u},
                                Variant{sim::ListLayout::Clusters, 128u},
                                Variant{sim::ListLayout::Contiguous, 128u, sim::NeighbourSearch::Cells},
                                Variant{sim::ListLayout::Contiguous, 128u, sim::NeighbourSearch::List, true},
                                Variant{sim::ListLayout::Contiguous, 130u, sim::NeighbourSearch::Cells, true}}) {
    const std::uint32_t capacity = variant.capacity;
    const bool cells = variant.search == sim::NeighbourSearch::Cells;
    SCOPED_TRACE(testing::Message() << "capacity " << capacity
                                    << (variant.layout == sim::ListLayout::Clusters ? ", clusters" : "")
                                    << (cells ? ", walking cells" : "") << (variant.carreau ? ", Carreau-Yasuda" : ""));
    // (viscosities from 0.1 at rest to 0.01 Pa s, thinning from shear rates of about 2 1/s;
    // the case's random velocities shear the fluid at tens)
    s.rheology = variant.carreau ? sim::Rheology::CarreauYasuda : sim::Rheology::Newtonian;
    s.carreau = {0.1f, 0.01f, 0.5f, 0.4f, 1.5f};
    s.listLayout = variant.layout;
    s.neighbourCapacity = capacity;
    s.neighbourSearch = variant.search;
    setUp(c.pos, c.vel, c.normals, c.net, s, glm::vec3(-0.05f), glm::vec3(0.15f));
    solver_->wall()->setWallShear(true);
    ASSERT_EQ(solver_->walksCells(), cells);
    ASSERT_EQ(solver_->listReadWidth(), cells || capacity % 4u != 0u ? 1u : 4u);
    evaluate();
    ASSERT_EQ(solver_->usesClusters(), variant.layout == sim::ListLayout::Clusters);

    // References: the fluid model (all wall particles as boundary particles), then the springs.
    const reference::SphModel model = modelOf(solver_->params());
    ASSERT_EQ(model.carreauYasuda, variant.carreau);
    std::vector<reference::SphParticle> ref(n);
    for (std::uint32_t i = 0; i < n; ++i) {
      ref[i] = {glm::dvec3(c.pos[i]), glm::dvec3(c.vel[i]), glm::dvec3(c.normals[i]), c.pos[i].w, i < c.wall ? 1 : 0};
    }
    const auto rp = reference::densityPressure(ref, model);
    if (variant.carreau) {  // the law must matter: the fluid's viscosities spread widely
      const auto mu = reference::viscosities(ref, rp, model);
      double lo = 1e30, hi = 0.0;
      for (std::uint32_t i = c.wall; i < n; ++i) lo = std::min(lo, mu[i]), hi = std::max(hi, mu[i]);
      EXPECT_GT(hi, 2.0 * lo) << "viscosities " << lo << " to " << hi << " Pa s";
    }
    std::vector<glm::dvec3> reactions;
    const auto fluidAcc = reference::accelerations(ref, rp, model, &reactions);
    std::vector<reference::RefSpring> springs;
    for (const auto& sp : c.net.springs) {
      springs.push_back({std::min(sp.a, sp.b), std::max(sp.a, sp.b), sp.restLength, sp.stiffness, sp.damping, sp.maxForce, false});
    }
    std::vector<glm::dvec3> wx(c.wall), wv(c.wall);
    std::vector<double> mass(c.wall);
    std::vector<bool> anchored(c.wall);
    for (std::uint32_t i = 0; i < c.wall; ++i) {
      wx[i] = ref[i].x, wv[i] = ref[i].v, mass[i] = c.net.points[i].mass, anchored[i] = c.net.points[i].anchored;
    }
    const auto wallAcc = reference::springAccelerations(springs, wx, wv, mass, anchored, glm::dvec3(s.gravity));

    const auto ids = store_->readIds();
    const auto accel = solver_->accel().readback<glm::vec4>(n);
    double fluidScale = 0.0, wallScale = 0.0, reactionScale = 0.0;
    for (std::uint32_t i = 0; i < n; ++i) {
      if (i < c.wall) {
        wallScale = std::max(wallScale, glm::length(wallAcc[i]));
        if (!anchored[i]) reactionScale = std::max(reactionScale, glm::length(reactions[i] / mass[i]));
      } else {
        fluidScale = std::max(fluidScale, glm::length(fluidAcc[i]));
      }
    }
    ASSERT_GT(reactionScale, 10.0) << "the fluid must push the wall noticeably";
    std::size_t pushed = 0;
    for (std::uint32_t slot = 0; slot < n; ++slot) {
      const std::uint32_t i = ids[slot];
      if (i >= c.wall) {
        EXPECT_LT(glm::length(glm::dvec3(accel[slot]) - fluidAcc[i]), 2e-4 * fluidScale) << "fluid particle " << i;
        continue;
      }
      const glm::dvec3 want = anchored[i] ? glm::dvec3(0.0) : wallAcc[i] + reactions[i] / mass[i];
      pushed += glm::length(reactions[i]) > 0.0;
      EXPECT_LT(glm::length(glm::dvec3(accel[slot]) - want), 2e-4 * (wallScale + reactionScale)) << "wall particle " << i;
    }
    EXPECT_GT(pushed, 100u);

    // The wall shear stress, anchored particles included, against its twin.
    const auto wss = solver_->wall()->wallShearStress().readback<glm::vec4>(n);
    std::vector<glm::dvec3> wssRef(c.wall);
    double wssScale = 0.0;
    for (std::uint32_t i = 0; i < c.wall; ++i) {
      wssRef[i] = reference::wallShearStress(ref, rp, model, i, c.net.points[i].shearArea);
      wssScale = std::max(wssScale, glm::length(wssRef[i]));
    }
    ASSERT_GT(wssScale, 0.0);
    std::size_t wetted = 0;
    double worst = 0.0;
    for (std::uint32_t slot = 0; slot < n; ++slot) {
      const std::uint32_t i = ids[slot];
      if (i >= c.wall) continue;
      const double error = glm::length(glm::dvec3(glm::vec3(wss[slot])) - wssRef[i]);
      worst = std::max(worst, error);
      EXPECT_LT(error, 2e-3 * wssScale) << "wall shear at wall particle " << i;
      wetted += wss[slot].w == 1.0f;
    }
    EXPECT_GT(wetted, 100u);
    // What the renderer colours the wall by, in the wall shear's mode: |tau| per wall slot.
    rec_->begin();
    solver_->wall()->recordShade(*rec_, n, sim::MassSpring::ShadeBy::WallShear);
    rec_->end();
    rec_->submitAndWait();
    const auto shade = solver_->wall()->shade().readback<glm::vec2>(n);
    for (std::uint32_t slot = 0; slot < n; ++slot) {
      if (ids[slot] < c.wall) {
        const float magnitude = glm::length(glm::vec3(wss[slot]));
        EXPECT_NEAR(shade[slot].x, magnitude, 1e-6f * magnitude + 1e-30f) << "wall particle " << ids[slot];
      }
    }
    std::printf("wall shear: %zu wall particles wetted, largest %.4g Pa, worst difference from the twin %.3g of it\n", wetted, wssScale,
                worst / wssScale);
  }
}

// A wall particle under the fluid whose springs all break detaches: it is counted once, its
// SPH mass is zero after that step, the fluid's forces from then on are those of a wall
// without it (the reference with the particle removed), and it only falls.
TEST_F(WallTest, ParticleWithAllSpringsBrokenDetachesFromTheWall) {
  auto rng = rngFor();
  sim::SphSettings s = wallSettings({0.0f, 0.0f, -9.81f});
  s.soundSpeed = 20.0f;
  CoupledCase c = coupledCase(rng, s, 8, 7, 6, 0.3f, 0.0f, 0.0f, 0.97f);
  for (auto& point : c.net.points) point.anchored = false;
  // The top-layer particle under the middle of the block: its springs start stretched to twice
  // their rest length and break at the first force evaluation.
  const std::uint32_t victim = std::uint32_t((0 * (7 + 4) + (3 + 2)) * (8 + 4) + (4 + 2));
  std::size_t cut = 0;
  for (auto& sp : c.net.springs) {
    if (sp.a == victim || sp.b == victim) sp.restLength *= 0.5f, sp.maxForce = 0.1f, ++cut;
  }
  ASSERT_GE(cut, 5u);
  const auto n = static_cast<std::uint32_t>(c.pos.size());
  setUp(c.pos, c.vel, c.normals, c.net, s, glm::vec3(-0.05f), glm::vec3(0.15f));
  rec_->begin();
  solver_->recordNeighbours(*rec_);
  solver_->recordDensity(*rec_);
  solver_->recordForces(*rec_);  // breaks the springs and marks the particle
  solver_->recordIntegrate(*rec_, 0, 0);  // detaches it (SPH mass 0)
  solver_->recordDensity(*rec_);
  solver_->recordForces(*rec_);  // the fluid without it
  rec_->end();
  rec_->submitAndWait();

  const reference::SphModel model = modelOf(solver_->params());
  // The reference at the state of the second evaluation (after the integration step).
  const auto ids = store_->readIds();
  const auto pos = store_->readPositions();
  const auto vel = store_->readVelocities();
  const auto normals = store_->readNormals();
  std::vector<std::uint32_t> slotOf(n);
  for (std::uint32_t slot = 0; slot < n; ++slot) slotOf[ids[slot]] = slot;
  std::vector<reference::SphParticle> ref;
  for (std::uint32_t i = 0; i < n; ++i) {
    if (i == victim) continue;
    const std::uint32_t k = slotOf[i];
    ref.push_back({glm::dvec3(pos[k]), glm::dvec3(vel[k]), glm::dvec3(normals[k]), pos[k].w, i < c.wall ? 1 : 0});
  }
  const auto rp = reference::densityPressure(ref, model);
  const auto acc = reference::accelerations(ref, rp, model);
  double scale = 0.0;
  for (const auto& a : acc) scale = std::max(scale, glm::length(a));
  const auto accel = solver_->accel().readback<glm::vec4>(n);
  bool sawVictim = false;
  for (std::uint32_t slot = 0; slot < n; ++slot) {
    const std::uint32_t i = ids[slot];
    if (i == victim) {
      sawVictim = true;
      EXPECT_EQ(pos[slot].w, 0.0f) << "SPH mass of the detached particle";
      EXPECT_EQ(accel[slot], glm::vec4(s.gravity, 0.0f)) << "a detached particle only falls (and is not marked again)";
      continue;
    }
    if (i < c.wall) continue;
    const std::size_t r = i - 1;  // the reference lacks the victim (a wall particle, id < i)
    EXPECT_LT(glm::length(glm::dvec3(accel[slot]) - acc[r]), 2e-4 * scale) << "fluid particle " << i;
  }
  EXPECT_TRUE(sawVictim);
  EXPECT_EQ(solver_->wall()->readBrokenCount(), cut);
  EXPECT_EQ(solver_->wall()->readDetachedCount(), 1u);
}

// DFSPH's share for the wall (wall/dfsph_reaction.comp): after the density solve each free
// wall particle adds F_w = sum_f m_f m_w (p_f / rho_f^2) gradW_fw over its spring mass, the
// exact opposite of what the solves' mirrored boundary term gave the fluid, with p_f the
// solves' pressure. Checked against a double-precision sum over the solver's own pressures,
// densities and positions, with the list read four entries per texel (capacity 128) and one
// (130); the solver's reported pressure is that plus the background pressure.
TEST_F(WallTest, DfsphWallTakesTheReactionOfTheSolvedPressure) {
  auto rng = rngFor();
  sim::SphSettings s = wallSettings({0.0f, 0.0f, -9.81f});
  s.soundSpeed = 20.0f;
  s.pressureSolver = sim::PressureSolver::Dfsph;
  s.solverTolerance = 1.0e-7f;
  s.solverMaxIterations = 3;
  s.backgroundPressure = 40.0f;
  s.listLayout = sim::ListLayout::Contiguous;
  const CoupledCase c = coupledCase(rng, s, 8, 7, 6, 0.6f, 0.1f, 0.1f, 0.9f);  // squeezed onto the sheet
  const auto n = static_cast<std::uint32_t>(c.pos.size());
  for (const std::uint32_t capacity : {128u, 130u}) {
    SCOPED_TRACE(testing::Message() << "capacity " << capacity);
    s.neighbourCapacity = capacity;
    setUp(c.pos, c.vel, c.normals, c.net, s, glm::vec3(-0.05f), glm::vec3(0.15f));
    ASSERT_EQ(solver_->listReadWidth(), capacity % 4u == 0u ? 4u : 1u);
    evaluate();  // with the divergence solve, and the springs and the wall's other reactions
    const auto before = solver_->accel().readback<glm::vec4>(n);
    rec_->begin();
    solver_->recordPressureSolve(*rec_);
    rec_->end();
    rec_->submitAndWait();
    const auto after = solver_->accel().readback<glm::vec4>(n);
    const auto kappa = solver_->solveStiffness().readback<glm::vec4>(n);
    const auto state = solver_->state().readback<glm::vec4>(n);
    const auto pos = store_->readPositions();
    const auto ids = store_->readIds();
    const double h = solver_->params().h;
    std::vector<glm::dvec3> want(n, glm::dvec3(0.0));
    double scale = 0.0, pressureScale = 0.0;
    for (std::uint32_t w = 0; w < n; ++w) {
      const std::uint32_t id = ids[w];
      if (id >= c.wall) {
        pressureScale = std::max(pressureScale, double(kappa[w].y));
        // the solve's pressure and the density pass's: the expansion side of the Tait law
        const double rho0 = solver_->params().rho0, rho = state[w].x;
        const double own = std::max(solver_->params().taitB * (std::pow(std::min(rho, rho0) / rho0, 7.0) - 1.0) + s.backgroundPressure, 0.0);
        EXPECT_NEAR(state[w].y, kappa[w].y + own, 1e-5 * (std::abs(kappa[w].y) + s.backgroundPressure))
            << "reported pressure of particle " << id;
        continue;
      }
      if (c.net.points[id].anchored) continue;
      glm::dvec3 f(0.0);
      for (std::uint32_t k = 0; k < n; ++k) {
        if (ids[k] < c.wall) continue;
        const glm::dvec3 d = glm::dvec3(glm::vec3(pos[k])) - glm::dvec3(glm::vec3(pos[w]));
        const double r = glm::length(d);
        if (r == 0.0 || r >= 2.0 * h) continue;
        const double rho = state[k].x;
        f += (double(pos[k].w) * double(pos[w].w) * double(kappa[k].y) / (rho * rho) * reference::kernelDwdr(r, h) / r) * d;
      }
      want[w] = f / double(c.net.points[id].mass);
      scale = std::max(scale, glm::length(want[w]));
    }
    ASSERT_GT(pressureScale, 10.0 * s.backgroundPressure) << "the solve must find a pressure in this squeezed case";
    ASSERT_GT(scale, 1.0) << "the solved pressure must push the wall noticeably";
    std::size_t pushed = 0;
    for (std::uint32_t w = 0; w < n; ++w) {
      const std::uint32_t id = ids[w];
      if (id >= c.wall) continue;
      const glm::dvec3 change = glm::dvec3(glm::vec3(after[w])) - glm::dvec3(glm::vec3(before[w]));
      EXPECT_LT(glm::length(change - want[w]), 2e-4 * scale) << "wall particle " << id;
      EXPECT_EQ(after[w].w, before[w].w) << "wall particle " << id;
      pushed += glm::length(want[w]) > 1e-3 * scale;
    }
    EXPECT_GT(pushed, 50u);
  }
}

// Fluid thrown at a free wall sheet (no anchors, no gravity): fluid and wall exchange momentum
// through exactly opposite pair forces and the springs are internal, so the total momentum
// (SPH masses for the fluid, spring masses for the wall) stays put over 1,000 steps; under
// DFSPH (300 steps), the wall takes the exact opposite of the solves' boundary term too.
TEST_F(WallTest, FluidAndFreeWallConserveMomentum) {
  for (const sim::PressureSolver solver : {sim::PressureSolver::Wcsph, sim::PressureSolver::Dfsph}) {
    const bool dfsph = solver == sim::PressureSolver::Dfsph;
    SCOPED_TRACE(dfsph ? "dfsph" : "wcsph");
    auto rng = rngFor();
    sim::SphSettings s = wallSettings(glm::vec3(0.0f));
    s.soundSpeed = 20.0f;
    s.viscosity = 0.01f;
    s.clampNegativePressure = false;
    s.neighbourCapacity = 256;  // the free sheet bends where the fluid hits it and crowds together
    s.pressureSolver = solver;
    s.solverMaxIterations = 10;
    if (dfsph) s.listLayout = sim::ListLayout::Contiguous;
    CoupledCase c = coupledCase(rng, s, 8, 7, 6, 0.1f, 0.01f, 0.0f, 1.0f);  // relaxed sheet, fluid at rest density
    for (auto& point : c.net.points) point.anchored = false;
    for (std::uint32_t i = c.wall; i < c.pos.size(); ++i) c.vel[i].z -= 0.3f;  // towards the sheet
    const auto n = static_cast<std::uint32_t>(c.pos.size());
    setUp(c.pos, c.vel, c.normals, c.net, s, glm::vec3(-0.2f), glm::vec3(0.3f));
    auto momentum = [&]() {
      const auto vel = store_->readVelocities();
      const auto pos = store_->readPositions();
      const auto ids = store_->readIds();
      glm::dvec3 fluid(0.0), wall(0.0);
      for (std::uint32_t slot = 0; slot < n; ++slot) {
        const std::uint32_t i = ids[slot];
        if (i < c.wall) wall += double(c.net.points[i].mass) * glm::dvec3(vel[slot]);
        else fluid += double(pos[slot].w) * glm::dvec3(vel[slot]);
      }
      return std::pair{fluid, wall};
    };
    const auto [fluid0, wall0] = momentum();
    const glm::dvec3 p0 = fluid0 + wall0;
    steps(dfsph ? 300 : 1000);
    EXPECT_EQ(solver_->readStatus().neighbourOverflow, 0u) << "the case must stay within the list capacity";
    const auto [fluid1, wall1] = momentum();
    const double moved = glm::length(wall1 - wall0);
    EXPECT_GT(moved, 0.1 * glm::length(p0)) << "the fluid must hand the wall a good share of its momentum";
    EXPECT_LT(glm::length(fluid1 + wall1 - p0), 1e-5 * glm::length(p0))
        << "total momentum drifted; fluid gave " << glm::length(fluid1 - fluid0) << ", wall got " << moved;
    EXPECT_EQ(solver_->readStatus().nonFinite, 0u);
    if (dfsph) {
      const sim::PressureSolveStats st = solver_->readPressureSolveStats();
      EXPECT_GT(st.totalIterations, 0u) << "the solve must act in this case";
      std::printf("dfsph: %.1f ms of simulated time in 300 steps, %u density and %u divergence corrections, wall got %.3g of %.3g kg m/s\n",
                  1e3 * time(), st.totalIterations, solver_->readPressureSolveStats(true).totalIterations, moved, glm::length(p0));
    }
  }
}

// Normals follow the deformed wall: a 6 x 5 sheet (frame points along +x and +y, so the
// normals start as +z), rotated rigidly and one corner anchored: after one force evaluation
// every framed normal is the rotated +z; the point without a frame keeps its normal.
TEST_F(WallTest, NormalsFollowTheDeformedWall) {
  const int nx = 6, ny = 5;
  const float dp = 0.01f;
  sim::SpringNetwork net;
  std::vector<glm::vec3> x, v;
  const glm::vec3 axis = glm::normalize(glm::vec3(1.0f, 2.0f, 0.5f));
  const float angle = 0.7f;
  auto rotate = [&](glm::vec3 p) {  // Rodrigues
    return p * std::cos(angle) + glm::cross(axis, p) * std::sin(angle) + axis * glm::dot(axis, p) * (1.0f - std::cos(angle));
  };
  auto id = [&](int i, int j) { return std::uint32_t(j * nx + i); };
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      sim::WallPoint p{0.001f, i == 0 && j == 0};
      // A then B with (x_A - x) x (x_B - x) along +z: right-handed pairs of lattice directions.
      const int di = i + 1 < nx ? 1 : -1, dj = j + 1 < ny ? 1 : -1;
      p.frameA = di * dj > 0 ? id(i + di, j) : id(i, j + dj);
      p.frameB = di * dj > 0 ? id(i, j + dj) : id(i + di, j);
      if (i == 3 && j == 2) p.frameA = p.frameB = sim::WallPoint::kNoFrame;
      net.points.push_back(p);
      x.push_back(rotate(glm::vec3(i * dp, j * dp, 0.0f)));
      v.emplace_back(0.0f);
      if (i + 1 < nx) net.springs.push_back({id(i, j), id(i + 1, j), dp, 10.0f, 0.0f, 3.0e38f});
      if (j + 1 < ny) net.springs.push_back({id(i, j), id(i, j + 1), dp, 10.0f, 0.0f, 3.0e38f});
    }
  setUp(x, v, net, wallSettings(glm::vec3(0.0f)), glm::vec3(-0.1f), glm::vec3(0.1f));
  // Start every normal at +x, so only the update can produce the rotated +z.
  store_->live().normals.upload(std::vector<glm::vec4>(x.size(), glm::vec4(1.0f, 0.0f, 0.0f, 0.0f)));
  evaluate();
  const auto ids = store_->readIds();
  const auto normals = store_->readNormals();
  const glm::vec3 want = rotate(glm::vec3(0.0f, 0.0f, 1.0f));
  for (std::size_t slot = 0; slot < ids.size(); ++slot) {
    const glm::vec3 n(normals[slot]);
    if (ids[slot] == id(3, 2)) {
      EXPECT_EQ(n, glm::vec3(1.0f, 0.0f, 0.0f)) << "a point without a frame keeps its normal";
    } else {
      EXPECT_LT(glm::length(n - want), 1e-5f) << "normal of point " << ids[slot];
    }
  }
}

// A tube of two wall layers, periodic along its axis, filled with agitated fluid (random
// velocity components of 0.1 m/s, |v| about c0 / 12, the design limit c0 >= 10 v_max): for 2,000 steps no fluid particle crosses the wall's
// inner layer, no spring breaks (none may: no maximum force) and the state stays finite.
TEST_F(WallTest, TubeKeepsItsFluidInside) {
  auto rng = rngFor();
  std::normal_distribution<float> agitation(0.0f, 0.1f);
  sim::SphSettings s = wallSettings(glm::vec3(0.0f));
  s.spacing = 0.001f;
  s.soundSpeed = 2.0f;
  s.viscosity = 1e-3f;
  s.periodic = {true, false, false};
  scene::TubeSpec t;
  t.length = 9 * s.spacing;  // three neighbour-list radii
  t.radius = 5 * s.spacing;
  t.spacing = s.spacing;
  t.pointMass = 1e-3f;       // a heavy wall (a thousand fluid particles)
  t.stiffness = 100.0f;
  t.damping = 0.01f;
  t.periodic = true;
  t.fluidMass = s.particleMass();
  scene::TubeBuild tube = scene::buildTube(t);
  ASSERT_GT(tube.particles.fluid, 500u);
  for (std::uint32_t i = tube.wall; i < tube.particles.size(); ++i) {
    tube.particles.velocities[i] = glm::vec4(agitation(rng), agitation(rng), agitation(rng), float(HEMO_KIND_FLUID));
  }
  const float outer = t.radius + 4.0f * s.spacing;
  setUp(tube.particles.positions, tube.particles.velocities, tube.particles.normals, tube.network, s,
        glm::vec3(0.0f, -outer, -outer), glm::vec3(t.length, outer, outer));
  steps(2000);
  const auto status = solver_->readStatus();
  EXPECT_EQ(status.nonFinite, 0u);
  EXPECT_EQ(status.neighbourOverflow, 0u);
  EXPECT_EQ(solver_->wall()->readBrokenCount(), 0u);
  // Inside the wall as it is now (the fluid at rest density pushes it out a little): no fluid
  // particle lies more than 0.1 dp beyond the local inner layer, the mean radius of the four
  // inner-layer points nearest to it. The layer is a lattice of points a spacing apart and
  // the repulsion starts only within D of a point, so a particle pressed into a gap between
  // points can sit a little past that mean radius without crossing: over four random
  // agitations each, the closest approach was -0.017 to +0.090 dp with cells of the list
  // radius and -0.004 to +0.183 dp with the present half cells (the particle order, and with
  // it the rounding, differ). A particle through the wall would be a whole spacing out.
  const auto pos = positionsById();
  const std::uint32_t inner = tube.along * tube.around;  // layer 0 comes first
  double worst = -1e30, widest = 0.0;
  std::size_t fluid = 0;
  for (std::uint32_t k = tube.wall; k < pos.size(); ++k) {
    ++fluid;
    const double r = std::hypot(pos[k].y, pos[k].z);
    std::vector<std::pair<double, double>> near;  // (distance, radius) of inner-layer points
    for (std::uint32_t w = 0; w < inner; ++w) {
      glm::dvec3 d = glm::dvec3(pos[w]) - glm::dvec3(pos[k]);
      d.x -= t.length * std::round(d.x / t.length);
      near.emplace_back(glm::length(d), std::hypot(pos[w].y, pos[w].z));
    }
    std::partial_sort(near.begin(), near.begin() + 4, near.end());
    const double wallR = 0.25 * (near[0].second + near[1].second + near[2].second + near[3].second);
    worst = std::max(worst, r - wallR);
    widest = std::max(widest, r);
  }
  EXPECT_EQ(fluid, tube.particles.fluid);
  EXPECT_LT(worst, 0.1 * s.spacing) << "a fluid particle is outside the wall's inner layer";
  RecordProperty("largest_fluid_radius_over_inner_radius", std::to_string(widest / t.radius));
  std::printf("tube: %.4f s, largest fluid radius %.3f R, closest approach to the inner layer %.3f dp, %u rebuilds\n", time(),
              widest / t.radius, -worst / s.spacing, solver_->readRebuilds());
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

// The wall's substeps (wall/substep.comp) against a double-precision twin: a fluid block on a
// random free-ish network, one step with 4 substeps; the twin starts from the same wall state,
// holds the force the GPU's last force evaluation gave each particle (the fluid's reaction and
// gravity, tested against its own twin in FluidAndWallAccelerationsMatchReference) and takes
// 4 symplectic Euler substeps of dt / 4 with the springs re-evaluated at each.
TEST_F(WallTest, SubstepsMatchReference) {
  auto rng = rngFor();
  sim::SphSettings s = wallSettings({0.0f, -1.0f, -9.81f});
  s.soundSpeed = 5.0f;  // a step long enough that substeps matter
  s.viscosity = 0.05f;
  CoupledCase c = coupledCase(rng, s, 8, 7, 6, 0.6f, 0.5f);
  c.net.substeps = 4;
  const auto n = static_cast<std::uint32_t>(c.pos.size());
  setUp(c.pos, c.vel, c.normals, c.net, s, glm::vec3(-0.05f), glm::vec3(0.15f));
  ASSERT_EQ(solver_->wall()->substeps(), 4u);
  steps(1);
  const double dt = solver_->readClock().lastDt;
  const auto ids = store_->readIds();
  const auto pos = store_->readPositions();
  const auto vel = store_->readVelocities();
  const auto held = solver_->wall()->held().readback<glm::vec4>(n);
  std::vector<reference::RefSpring> springs;
  for (const auto& sp : c.net.springs) {
    springs.push_back({std::min(sp.a, sp.b), std::max(sp.a, sp.b), sp.restLength, sp.stiffness, sp.damping, sp.maxForce, false});
  }
  std::vector<glm::dvec3> x(c.wall), v(c.wall), outside(c.wall);
  std::vector<double> mass(c.wall);
  std::vector<bool> anchored(c.wall);
  for (std::uint32_t i = 0; i < c.wall; ++i) {
    x[i] = glm::dvec3(glm::vec3(c.pos[i])), v[i] = glm::dvec3(glm::vec3(c.vel[i]));
    mass[i] = c.net.points[i].mass, anchored[i] = c.net.points[i].anchored;
  }
  for (std::uint32_t slot = 0; slot < n; ++slot) {
    if (ids[slot] < c.wall) outside[ids[slot]] = glm::dvec3(glm::vec3(held[slot]));
  }
  // h: the substep; returns the state after `count` substeps
  auto advance = [&](int count) {
    std::vector<glm::dvec3> xs = x, vs = v;
    const double h = dt / count;
    for (int k = 0; k < count; ++k) {
      const auto a = reference::springAccelerations(springs, xs, vs, mass, anchored, glm::dvec3(0.0));
      for (std::uint32_t i = 0; i < c.wall; ++i) {
        if (anchored[i]) continue;
        vs[i] += (a[i] + outside[i]) * h;
        xs[i] += vs[i] * h;
      }
    }
    return std::pair{xs, vs};
  };
  const auto [xRef, vRef] = advance(4);
  const auto [xOne, vOne] = advance(1);
  double dvScale = 0.0, dxScale = 0.0, oneStep = 0.0;
  for (std::uint32_t i = 0; i < c.wall; ++i) {
    dvScale = std::max(dvScale, glm::length(vRef[i] - v[i]));
    dxScale = std::max(dxScale, glm::length(xRef[i] - x[i]));
    oneStep = std::max(oneStep, glm::length(vOne[i] - vRef[i]));
  }
  ASSERT_GT(dvScale, 0.0);
  EXPECT_GT(oneStep, 0.01 * dvScale) << "one step of dt must differ from four substeps here (dt " << dt << " s)";
  std::printf("dt %.3g s: one step of dt differs from four substeps by %.3g of the largest velocity change\n", dt,
              oneStep / dvScale);
  for (std::uint32_t slot = 0; slot < n; ++slot) {
    const std::uint32_t i = ids[slot];
    if (i >= c.wall) continue;
    EXPECT_LT(glm::length(glm::dvec3(glm::vec3(vel[slot])) - vRef[i]), 1e-3 * dvScale) << "velocity of wall particle " << i;
    EXPECT_LT(glm::length(glm::dvec3(glm::vec3(pos[slot])) - xRef[i]), 2e-3 * dxScale + 1e-7) << "position of wall particle " << i;
  }
}

// With 8 substeps a spring oscillates at its analytic frequency at a step 7.5 times its own
// explicit limit: sampled once per (constant) step, a linear oscillator's samples obey
// x_{k+1} + x_{k-1} = 2 cos(omega dt) x_k, and the least-squares cos(omega dt) gives omega
// within 0.1% (one symplectic Euler step of this dt would be 2.3% off).
TEST_F(WallTest, SubstepsKeepTheSpringsFrequencyAtALargerStep) {
  const float m = 0.01f, k = 100.0f, rest = 0.05f, amplitude = 0.01f;
  sim::SpringNetwork net;
  net.points = {{m, true}, {m, false}};
  net.springs = {{0, 1, rest, k, 0.0f, 3.0e38f}};
  net.substeps = 8;
  sim::SphSettings s = wallSettings(glm::vec3(0.0f));
  s.spacing = 0.04f;         // C_a h / (c0 + |v|) above 7.8 ms at up to 1 m/s
  s.maxTimeStep = 7.5e-3f;   // the step, under the substeps' 8 ms
  setUp({glm::vec3(0.0f), glm::vec3(rest + amplitude, 0.0f, 0.0f)}, {glm::vec3(0.0f), glm::vec3(0.0f)}, net, s,
        glm::vec3(-0.1f), glm::vec3(0.1f));
  const double omega = std::sqrt(double(k) / m);
  std::vector<double> xs{amplitude};
  for (int step = 0; step < 60; ++step) {
    steps(1);
    xs.push_back(positionsById()[1].x - rest);
  }
  const double dt = solver_->readClock().lastDt;
  EXPECT_FLOAT_EQ(float(dt), s.maxTimeStep);
  EXPECT_NEAR(time(), 60.0 * dt, 1e-5 * time()) << "the step must be constant";
  double num = 0.0, den = 0.0;
  for (std::size_t j = 1; j + 1 < xs.size(); ++j) {
    num += xs[j] * (xs[j - 1] + xs[j + 1]);
    den += 2.0 * xs[j] * xs[j];
  }
  const double measured = std::acos(num / den) / dt;
  EXPECT_NEAR(measured, omega, 1e-3 * omega) << "dt " << dt << " s, omega dt " << omega * dt;
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


// Laplace's law (issue 4, test 4). A periodic tube (R = 5 mm, two layers, dx = 1 mm) full
// of blood is pressurised by raising the lumen (background) pressure; the wall's hoop
// springs must break when the measured mean fluid pressure reaches the rupture pressure
// P* that the spring layout predicts (scene::hoopRupturePressure), not much before and not
// much after, and must hold below it.
class LaplaceTest : public WallTest {
 protected:
  struct Sample {
    double time, pressure, minWallRadius;
    std::uint32_t broken;
  };
  // Builds the tube; the lumen pressure rises linearly to `target` x P* over `ramp` s.
  // Blood-like fluid at dp = 1 mm with a slow sound speed (c0 = 2 m/s), periodic along x.
  static sim::SphSettings fluid() {
    sim::SphSettings s = wallSettings(glm::vec3(0.0f));
    s.spacing = 0.001f;
    s.soundSpeed = 2.0f;
    s.viscosity = 3.5e-3f;
    s.restDensity = 1060.0f;
    s.periodic = {true, false, false};
    return s;
  }
  // A periodic two-layer tube of that fluid, `length` and `radius` in spacings, with heavy
  // points and stiff springs whose hoop springs break at 5% strain.
  static scene::TubeSpec tube(const sim::SphSettings& s, int length, int radius) {
    scene::TubeSpec t;
    t.length = float(length) * s.spacing;
    t.radius = float(radius) * s.spacing;
    t.spacing = s.spacing;
    t.layers = 2;
    t.pointMass = 1e-3f;
    t.stiffness = 100.0f;
    t.damping = 0.02f;
    t.periodic = true;
    t.fluidMass = s.particleMass();
    const double around = std::round(2.0 * std::numbers::pi * t.radius / s.spacing);
    const double hoop = 2.0 * (t.radius + 0.5 * s.spacing) * std::sin(std::numbers::pi / around);
    t.maxForce = float(t.stiffness * 0.05 * hoop);
    return t;
  }
  double build(double target, float ramp, sim::PressureSolver solver = sim::PressureSolver::Wcsph,
               std::uint32_t substeps = 1) {
    sim::SphSettings s = fluid();
    s.pressureSolver = solver;
    if (solver == sim::PressureSolver::Dfsph) {
      s.listLayout = sim::ListLayout::Contiguous;
      s.solverMaxIterations = 5;  // every step records the cap's worth (lavapipe's time)
    }
    t_ = tube(s, 10, 5);
    tube_ = scene::buildTube(t_);
    tube_.network.substeps = substeps;
    const double pStar = scene::hoopRupturePressure(t_, tube_);
    s.backgroundPressure = float(target * pStar);
    s.backgroundPressureRamp = ramp;
    const float outer = t_.radius + 8.0f * s.spacing;
    setUp(tube_.particles.positions, tube_.particles.velocities, tube_.particles.normals, tube_.network, s,
          glm::vec3(0.0f, -outer, -outer), glm::vec3(t_.length, outer, outer));
    return pStar;
  }
  void ruptureAtTheHoopLimit(sim::PressureSolver solver, std::uint32_t substeps = 1);
  // Runs `count` steps and measures the mean fluid pressure and the wall's smallest radius.
  Sample advance(int count) {
    steps(count);
    const auto n = static_cast<std::uint32_t>(tube_.particles.size());
    const auto state = solver_->state().readback<glm::vec4>(n);
    const auto vel = store_->readVelocities();
    const auto pos = store_->readPositions();
    double sumP = 0.0, rMin = 1.0;
    std::size_t fluid = 0;
    for (std::uint32_t k = 0; k < n; ++k) {
      if (vel[k].w == float(HEMO_KIND_FLUID)) sumP += state[k].y, ++fluid;
      else rMin = std::min(rMin, double(std::hypot(pos[k].y, pos[k].z)));
    }
    return {time(), sumP / double(fluid), rMin, solver_->wall()->readBrokenCount()};
  }
  scene::TubeSpec t_;
  scene::TubeBuild tube_;
};

TEST_F(LaplaceTest, RupturePressureOfTheLayoutIsTheHoopEstimate) {
  build(0.0, 0.0f);
  const double pStar = scene::hoopRupturePressure(t_, tube_);
  // 5 f_max / (R dx): the layout's exact value differs by the layers' radii and the
  // diagonals' angles (11% here).
  const double estimate = 5.0 * t_.maxForce / (t_.radius * t_.spacing);
  EXPECT_NEAR(pStar / estimate, 1.0, 0.15) << pStar << " Pa vs " << estimate << " Pa";
}

// The lumen pressure rises to 1.3 P* in 0.39 s (about 0.015 P* per 50 steps) until a spring
// breaks; checks the mean fluid pressure just before.
void LaplaceTest::ruptureAtTheHoopLimit(sim::PressureSolver solver, std::uint32_t substeps) {
  const double pStar = build(1.3, 0.39f, solver, substeps);
  Sample last{}, now{};
  for (int batch = 0; batch < 200; ++batch) {
    now = advance(50);
    ASSERT_TRUE(std::isfinite(now.pressure)) << "t " << now.time;
    if (now.broken > 0) break;
    EXPECT_GT(now.minWallRadius, t_.radius) << "the wall was pushed inwards at t " << now.time;
    last = now;
  }
  ASSERT_GT(now.broken, 0u) << "no spring broke up to " << now.pressure / pStar << " P*";
  // The mean fluid pressure just before the first break (it lags the lumen pressure by the
  // expansion into the gap between the fluid lattice and the wall).
  EXPECT_NEAR(last.pressure / pStar, 1.0, 0.2) << "first break at t " << now.time << " s, P* " << pStar << " Pa";
  // The static solution of the network (scene/statics.hpp): the inner layer carries more
  // than a uniform widening gives it, so it predicts the break lower, closer to the GPU's.
  const double staticP = scene::staticResponse(tube_.network, tube_.particles.positions, t_.length,
                                               scene::lumenLoads(scene::AneurysmSpec{t_}, tube_.particles.positions,
                                                                 tube_.particles.normals, tube_.wall))
                             .rupturePressure;
  EXPECT_NEAR(last.pressure / staticP, 1.0, 0.2);
  std::printf("%s: first break at t = %.4f s: mean fluid pressure %.0f Pa = %.3f P* (P* = %.0f Pa) = %.3f of the static estimate "
              "(%.0f Pa), %u springs\n",
              solver == sim::PressureSolver::Dfsph ? "dfsph" : "wcsph", now.time, last.pressure, last.pressure / pStar, pStar,
              last.pressure / staticP, staticP, now.broken);
  if (solver == sim::PressureSolver::Dfsph) {
    const sim::PressureSolveStats st = solver_->readPressureSolveStats();
    std::printf("dfsph, %u wall substeps: %u density and %u divergence corrections in %u steps, %u and %u solves at the cap\n",
                substeps, st.totalIterations, solver_->readPressureSolveStats(true).totalIterations, st.solves, st.capHits,
                solver_->readPressureSolveStats(true).capHits);
  }
}

TEST_F(LaplaceTest, TubeRupturesWhenTheLumenPressureReachesTheHoopLimit) { ruptureAtTheHoopLimit(sim::PressureSolver::Wcsph); }

// The same under DFSPH with the wall in 8 substeps per step: the background (lumen) pressure
// loads the wall through the force pass, the wall takes the reaction of the solved pressure,
// its springs no longer limit the step, and the first break comes within the same tolerances.
TEST_F(LaplaceTest, TubeRupturesAtTheHoopLimitUnderDfsph) { ruptureAtTheHoopLimit(sim::PressureSolver::Dfsph, 8); }

TEST_F(LaplaceTest, TubeHoldsBelowTheHoopLimit) {
  // Lumen pressure raised to 0.77 P* in 0.25 s, then held to 0.35 s. (With the ring fill the
  // fluid's pressure follows the lumen pressure closely; 0.8 P* reached in 0.15 s broke
  // springs at a mean fluid pressure of 0.74 P*, in the wall's overshoot after the ramp.)
  const double pStar = build(0.77, 0.25f);
  Sample now{};
  while (now.time < 0.35) {
    now = advance(200);
    ASSERT_TRUE(std::isfinite(now.pressure)) << "t " << now.time;
    ASSERT_EQ(now.broken, 0u) << "at t " << now.time << " s, " << now.pressure / pStar << " P*";
  }
  EXPECT_GT(now.pressure / pStar, 0.7) << "the fluid is held below 70% of P*";
  std::printf("held at t = %.3f s: mean fluid pressure %.0f Pa = %.3f P*, no spring broken\n", now.time, now.pressure,
              now.pressure / pStar);
}

// A fusiform aneurysm (R = 4 dp bulging to 6 dp over 10 dp, 20 dp of periodic tube, the
// Laplace tube's springs and fluid) under a rising lumen pressure: the first spring breaks
// when the mean fluid pressure reaches the static estimate of the built network
// (scene::staticResponse, which has no closed form here) within 20%, where the static solution
// puts the most loaded spring (at the bulge's ends, where the profile turns concave).
TEST_F(LaplaceTest, FusiformRupturesAtTheStaticEstimate) {
  sim::SphSettings s = fluid();
  scene::AneurysmSpec a;
  a.tube = tube(s, 20, 4);
  const scene::TubeSpec& t = a.tube;
  a.bulgeRadius = 6 * s.spacing;
  a.bulgeLength = 10 * s.spacing;
  const scene::FusiformBuild b = scene::buildFusiformAneurysm(a);
  const scene::StaticResponse statics = scene::staticResponse(
      b.network, b.particles.positions, t.length, scene::lumenLoads(a, b.particles.positions, b.particles.normals, b.wall));
  const double pStar = statics.rupturePressure;
  s.backgroundPressure = float(1.3 * pStar);
  s.backgroundPressureRamp = 0.39f;
  const float outer = a.bulgeRadius + 8.0f * s.spacing;
  setUp(b.particles.positions, b.particles.velocities, b.particles.normals, b.network, s, glm::vec3(0.0f, -outer, -outer),
        glm::vec3(t.length, outer, outer));
  const auto n = static_cast<std::uint32_t>(b.particles.size());
  double last = 0.0, now = 0.0;
  std::uint32_t broken = 0;
  for (int batch = 0; batch < 200 && broken == 0; ++batch) {
    steps(50);
    const auto state = solver_->state().readback<glm::vec4>(n);
    const auto vel = store_->readVelocities();
    double sumP = 0.0;
    std::size_t fluid = 0;
    for (std::uint32_t k = 0; k < n; ++k) {
      if (vel[k].w == float(HEMO_KIND_FLUID)) sumP += state[k].y, ++fluid;
    }
    last = now;
    now = sumP / double(fluid);
    ASSERT_TRUE(std::isfinite(now)) << "t " << time();
    broken = solver_->wall()->readBrokenCount();
  }
  ASSERT_GT(broken, 0u) << "no spring broke up to " << now / pStar << " P*";
  const auto springs = solver_->wall()->readSprings();
  // Where along the axis (from the bulge's middle, in dp) a spring sits.
  auto offset = [&](const sim::Spring& sp) {
    const double x = 0.5 * (b.particles.positions[sp.a].x + b.particles.positions[sp.b].x);
    return (x - 0.5 * t.length) / t.spacing;
  };
  const double predicted = std::abs(offset(b.network.springs[statics.firstSpring]));
  std::uint32_t onBulge = 0;
  for (std::size_t k = 0; k < springs.size(); ++k) {
    if (!springs[k].broken) continue;
    onBulge += b.inBulge[b.network.springs[k].a] || b.inBulge[b.network.springs[k].b];
    // Where the static solution puts the most loaded spring (either end of the bulge).
    EXPECT_NEAR(std::abs(offset(b.network.springs[k])), predicted, 1.0) << "spring " << k;
  }
  std::printf("static first spring %.2f dp from the bulge's middle (its half-length %.1f dp)\n", predicted,
              0.5 * a.bulgeLength / t.spacing);
  std::printf("fusiform: static P* %.0f Pa (tube's hoop estimate %.0f Pa); first break at t = %.4f s at a mean fluid pressure of "
              "%.0f Pa = %.3f P*, %u springs (%u on the bulge)\n",
              pStar, scene::hoopRupturePressure(t, scene::buildTube(t)), time(), last, last / pStar, broken, onBulge);
  EXPECT_NEAR(last / pStar, 1.0, 0.2);
}

}  // namespace
}  // namespace hemo::test
