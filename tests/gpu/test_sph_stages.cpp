// SPH stages on the GPU against the double-precision reference on random inputs.
#include "gpu_test.hpp"
#include "sph_model.hpp"
#include "hemo/reference/sph.hpp"
#include "hemo/sim/sph.hpp"
#include "interface/sph.h"

#include <glm/geometric.hpp>

#include <algorithm>
#include <numeric>
#include <map>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <memory>
#include <utility>

namespace hemo::test {
namespace {

struct Case {
  std::vector<glm::vec4> pos, vel, normals;
  std::vector<reference::SphParticle> ref;
};

// A jittered, slightly compressed block of fluid over two layers of a boundary plane, with
// random velocities, so every term (pressure, viscosity, repulsion) is exercised. With
// `periodicXY` the block and the plane fill exactly [0, nx dp) x [0, ny dp) (compressed in z
// only) and positions are wrapped into that period.
Case makeCase(std::mt19937_64& rng, const sim::SphSettings& s, int nx, int ny, int nz, float speedSigma = 0.3f,
              bool periodicXY = false) {
  Case c;
  const float dp = s.spacing;
  std::uniform_real_distribution<float> jitter(-0.15f * dp, 0.15f * dp);
  std::normal_distribution<float> speed(0.0f, speedSigma);
  const float m = s.particleMass();
  const int margin = periodicXY ? 0 : 2;
  for (int layer = 0; layer < 2; ++layer)
    for (int j = -margin; j < ny + margin; ++j)
      for (int i = -margin; i < nx + margin; ++i) {
        c.pos.emplace_back((i + 0.5f) * dp, (j + 0.5f) * dp, -(layer + 0.5f) * dp, m);
        c.vel.emplace_back(0.0f, 0.0f, 0.0f, float(sim::ParticleKind::Boundary));
        c.normals.emplace_back(0.0f, 0.0f, 1.0f, 0.0f);
      }
  const glm::vec3 squeeze = periodicXY ? glm::vec3(1.0f, 1.0f, 0.95f) : glm::vec3(0.95f);
  const glm::vec3 period(float(nx) * dp, float(ny) * dp, 0.0f);
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i) {
        glm::vec3 x = glm::vec3((i + 0.5f) * dp, (j + 0.5f) * dp, (k + 0.45f) * dp) * squeeze +
                      glm::vec3(jitter(rng), jitter(rng), jitter(rng));
        for (int a = 0; periodicXY && a < 2; ++a) x[a] -= period[a] * std::floor(x[a] / period[a]);
        c.pos.emplace_back(x, m);
        c.vel.emplace_back(speed(rng), speed(rng), speed(rng), float(sim::ParticleKind::Fluid));
        c.normals.emplace_back(0.0f);
      }
  for (std::size_t i = 0; i < c.pos.size(); ++i) {
    reference::SphParticle p;
    p.x = glm::dvec3(c.pos[i]);
    p.v = glm::dvec3(c.vel[i]);
    p.normal = glm::dvec3(c.normals[i]);
    p.mass = c.pos[i].w;
    p.kind = int(c.vel[i].w);
    c.ref.push_back(p);
  }
  return c;
}

// 2,000 particles at random over x in [0, period) (the grid's periodic axis) and y, z in
// [-0.03, 0.07) x [-0.03, 0.06), some beyond the grid's bounded sides: fluid (with chance 0.6)
// in the slab 0 < y < 0.05, boundary particles elsewhere. Positions only (no reference).
Case randomCase(std::mt19937_64& rng, const sim::SphSettings& s, float period) {
  std::uniform_real_distribution<float> ux(0.0f, period), uy(-0.03f, 0.07f), uz(-0.03f, 0.06f), unit(0.0f, 1.0f);
  Case c;
  for (int k = 0; k < 2000; ++k) {
    const glm::vec3 x(ux(rng), uy(rng), uz(rng));
    const bool fluid = x.y > 0.0f && x.y < 0.05f && unit(rng) < 0.6f;
    c.pos.emplace_back(x, s.particleMass());
    c.vel.emplace_back(0.0f, 0.0f, 0.0f, float(fluid ? sim::ParticleKind::Fluid : sim::ParticleKind::Boundary));
    c.normals.emplace_back(0.0f, 0.0f, 1.0f, 0.0f);
  }
  return c;
}

// The tile test's largest box separation (common/tiles.glsl), in double precision: each
// particle's displacement since the build goes into the box of the tile its build position
// lies in (the solver's grid decides which); neighbouring tiles (and each tile with itself)
// give max(hi_A - lo_B, hi_B - lo_A) per axis.
double tileBoundReference(const sim::TileGrid& g, const std::vector<glm::vec4>& pos, const std::vector<glm::vec4>& build) {
  std::map<std::uint32_t, std::pair<glm::dvec3, glm::dvec3>> boxes;
  for (std::size_t i = 0; i < pos.size(); ++i) {
    const glm::dvec3 d = glm::dvec3(pos[i]) - glm::dvec3(build[i]);
    const std::uint32_t t = g.indexOf(g.cellOf(glm::vec3(build[i])));
    auto [it, fresh] = boxes.try_emplace(t, d, d);
    if (!fresh) it->second = {glm::min(it->second.first, d), glm::max(it->second.second, d)};
  }
  double worst = 0.0;
  for (const auto& [t, a] : boxes) {
    const int c[3] = {int(t % g.count[0]), int(t / g.count[0] % g.count[1]), int(t / (g.count[0] * g.count[1]))};
    for (int dz = -1; dz <= 1; ++dz)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
          int o[3] = {c[0] + dx, c[1] + dy, c[2] + dz};
          bool inside = true;
          for (int ax = 0; ax < 3; ++ax) {
            const int cnt = int(g.count[ax]);
            if (g.count[3] & (1u << ax)) o[ax] = (o[ax] + cnt) % cnt;
            else inside = inside && o[ax] >= 0 && o[ax] < cnt;
          }
          if (!inside) continue;
          const auto it = boxes.find(g.indexOf(glm::uvec3(o[0], o[1], o[2])));
          if (it == boxes.end()) continue;
          const auto& b = it->second;
          worst = std::max(worst, glm::length(glm::max(a.second - b.first, b.second - a.first)));
        }
  }
  return worst;
}

class SphStageTest : public GpuTest {
 protected:
  // Uploads the case (ids = input index) and runs neighbours, density and forces once (only
  // the neighbour list with `listOnly`).
  struct Stages {
    std::unique_ptr<sim::ParticleStore> store;
    std::unique_ptr<sim::SphSolver> solver;
  };
  Stages runStages(const Case& c, const sim::SphSettings& s, glm::vec3 domainMax, glm::vec3 domainMin = glm::vec3(-0.05f),
                   bool listOnly = false, float lastDt = 0.0f) {
    const auto n = static_cast<std::uint32_t>(c.pos.size());
    Stages st;
    st.store = std::make_unique<sim::ParticleStore>(ctx(), n);
    std::vector<std::uint32_t> ids(n);
    for (std::uint32_t i = 0; i < n; ++i) ids[i] = i;
    st.store->upload(c.pos, c.vel, ids, c.normals);
    st.solver = std::make_unique<sim::SphSolver>(ctx(), *st.store, domainMin, domainMax, s);
    gpu::CommandRecorder rec(ctx());
    rec.begin();
    st.solver->recordReset(rec);
    if (lastDt > 0.0f) {  // as if a step of lastDt had just been taken (the clock's record 0)
      std::uint32_t bits;
      std::memcpy(&bits, &lastDt, 4);
      rec.computeToTransfer();
      rec.fill(st.solver->clockBuffer(), bits, 8, 4);
      rec.transferToCompute();
    }
    st.solver->recordNeighbours(rec);
    if (!listOnly) {
      st.solver->recordDensity(rec);
      st.solver->recordForces(rec);
    }
    rec.end();
    rec.submitAndWait();
    return st;
  }

  void checkRebuildAgainstReference(sim::Integrator integrator);
  static sim::SphSettings settings() {
    sim::SphSettings s;
    s.spacing = 0.01f;
    s.soundSpeed = 20.0f;
    s.viscosity = 0.05f;  // large, so the viscous term is visible next to pressure
    s.gravity = {0.0f, -1.0f, -9.81f};
    // D = dp: the fluid's first layer (0.78-1.08 dp in front of the plane's top layer) is
    // partly within the repulsion's reach (with the default D = dp / 2 none of it would be)
    s.repulsionCutoffRatio = 1.0f;
    return s;
  }
};

TEST_F(SphStageTest, DensityPressureAndAccelerationMatchReference) {
  auto rng = rngFor();
  // Clamped, unclamped, and clamped with a background pressure (a vessel's lumen pressure) of
  // about 5% of B, so the clamp cuts at a negative Tait pressure.
  // The list is read four entries per texel (contiguous layout, capacity a multiple of 4) or
  // one (a capacity that is not, or the interleaved layout): each read, each variant.
  struct Variant {
    bool clamp;
    float background;
    sim::ListLayout layout;
    std::uint32_t capacity;
    std::uint32_t readWidth;
    sim::NeighbourSearch search = sim::NeighbourSearch::List;
  };
  // (and without a list: the passes walking cells, clamped and not)
  for (const Variant variant : {Variant{true, 0.0f, sim::ListLayout::Contiguous, 128, 1, sim::NeighbourSearch::Cells},
                                Variant{false, 3000.0f, sim::ListLayout::Contiguous, 128, 1, sim::NeighbourSearch::Cells},
                                Variant{true, 0.0f, sim::ListLayout::Contiguous, 128, 4},
                                Variant{false, 0.0f, sim::ListLayout::Contiguous, 128, 4},
                                Variant{true, 3000.0f, sim::ListLayout::Contiguous, 128, 4},
                                Variant{false, 3000.0f, sim::ListLayout::Contiguous, 130, 1},
                                Variant{false, 3000.0f, sim::ListLayout::Interleaved, 128, 1},
                                Variant{true, 0.0f, sim::ListLayout::Clusters, 128, 4},
                                Variant{false, 3000.0f, sim::ListLayout::Clusters, 128, 4}}) {
    const bool clamp = variant.clamp;
    sim::SphSettings s = settings();
    s.clampNegativePressure = clamp;
    s.backgroundPressure = variant.background;
    s.listLayout = variant.layout;
    s.neighbourCapacity = variant.capacity;
    s.neighbourSearch = variant.search;
    const bool cells = variant.search == sim::NeighbourSearch::Cells;
    SCOPED_TRACE(testing::Message() << "clamp " << clamp << ", background " << variant.background << " Pa, list read "
                                    << variant.readWidth << " per texel" << (cells ? ", walking cells" : ""));
    const Case c = makeCase(rng, s, 9, 8, 7);
    const auto n = static_cast<std::uint32_t>(c.pos.size());
    const Stages st = runStages(c, s, glm::vec3(0.15f));
    const sim::ParticleStore& store = *st.store;
    const sim::SphSolver& solver = *st.solver;
    ASSERT_EQ(solver.listReadWidth(), variant.readWidth);
    ASSERT_EQ(solver.walksCells(), cells);
    ASSERT_EQ(solver.usesClusters(), variant.layout == sim::ListLayout::Clusters);
    // (no wall particles: the boundary particles' slots are in clusters too)
    ASSERT_EQ(solver.usesBoundaryClusters(), variant.layout == sim::ListLayout::Clusters);

    const auto slotIds = store.readIds();
    const auto state = solver.state().readback<glm::vec4>(n);
    const auto accel = solver.accel().readback<glm::vec4>(n);
    const auto model = modelOf(solver.params());
    const auto rp = reference::densityPressure(c.ref, model);
    const auto acc = reference::accelerations(c.ref, rp, model);
    double accelScale = 0.0;
    for (const auto& a : acc) accelScale = std::max(accelScale, glm::length(a));
    ASSERT_GT(accelScale, 10.0);
    std::size_t fluid = 0, positive = 0, negative = 0, boundaryWithPressure = 0, repelled = 0;
    for (std::uint32_t slot = 0; slot < n; ++slot) {
      const std::uint32_t i = slotIds[slot];
      if (c.ref[i].kind != 0) {
        // Extrapolated boundary pressure (Adami et al. 2012) and its Tait density.
        EXPECT_NEAR(state[slot].y, rp[i].y, 7.0 * model.taitB * 4e-6 + 1e-5 * std::abs(rp[i].y)) << "boundary pressure " << i;
        EXPECT_NEAR(state[slot].x, rp[i].x, 2e-6 * rp[i].x) << "boundary density " << i;
        boundaryWithPressure += rp[i].y > 0.0;
        EXPECT_EQ(glm::vec3(accel[slot]), glm::vec3(0.0f));
        continue;
      }
      ++fluid;
      // within D of the plane's top layer (at z = -dp/2, normal +z)
      repelled += c.ref[i].x.z + 0.5 * s.spacing < double(solver.params().repulsionCutoff);
      positive += rp[i].y > 0.0;
      negative += rp[i].y < 0.0;
      EXPECT_NEAR(state[slot].x, rp[i].x, 2e-6 * rp[i].x) << "density of particle " << i;
      // p = B((rho/rho0)^7 - 1): a relative density error e gives about 7 B e in pressure.
      EXPECT_NEAR(state[slot].y, rp[i].y, 7.0 * model.taitB * 4e-6 + 1e-5 * std::abs(rp[i].y)) << "pressure " << i;
      const double err = glm::length(glm::dvec3(accel[slot]) - acc[i]);
      EXPECT_LT(err, 2e-4 * accelScale) << "acceleration of particle " << i << " (|a| = " << glm::length(acc[i]) << ")";
    }
    EXPECT_GT(fluid, 400u);
    EXPECT_GT(boundaryWithPressure, 50u);
    EXPECT_GT(repelled, 20u) << "the case must exercise the repulsion";
    EXPECT_GT(positive, 50u) << "the case must exercise positive pressure";
    if (!clamp) {
      EXPECT_GT(negative, 10u) << "the free surface must give negative pressure without clamping";
    }
    if (variant.background > 0.0f) {
      EXPECT_EQ(model.backgroundPressure, variant.background);
    }
    const auto status = solver.readStatus();
    EXPECT_EQ(status.neighbourOverflow, 0u);
    if (!cells) {
      EXPECT_GT(status.maxNeighbours, 30u);  // (a walk counts no list)
    }
  }
}

// Continuity density: each fluid particle carries a density (random, 0.97-1.05 rho0, in
// normals.w). With symplectic Euler the density pass advances it over the last step (dt =
// 2e-4 s) with the continuity equation and the delta-SPH diffusion less its hydrostatic part;
// with RK2 it keeps it and gives the rate (state.z) to the integrator's stages. The increment
// or the rate, the pressure and the accelerations match the reference.
TEST_F(SphStageTest, ContinuityDensityMatchesReference) {
  for (const sim::Integrator integrator : {sim::Integrator::SymplecticEuler, sim::Integrator::Rk2Midpoint}) {
    const bool rk2 = integrator == sim::Integrator::Rk2Midpoint;
    SCOPED_TRACE(rk2 ? "rk2_midpoint" : "symplectic_euler");
    auto rng = rngFor();
    sim::SphSettings s = settings();
    // symplectic Euler reads the list four entries per texel, RK2 one (a capacity not a
    // multiple of 4)
    s.listLayout = sim::ListLayout::Contiguous;
    s.neighbourCapacity = rk2 ? 130u : 128u;
    s.densityMethod = sim::DensityMethod::Continuity;
    s.deltaSph = 0.1f;
    s.integrator = integrator;
    Case c = makeCase(rng, s, 9, 8, 7);
    std::uniform_real_distribution<double> spread(0.97, 1.05);
    for (std::size_t i = 0; i < c.pos.size(); ++i) {
      if (c.ref[i].kind != 0) continue;
      c.normals[i].w = float(spread(rng) * s.restDensity);
      c.ref[i].density = c.normals[i].w;
    }
    const auto n = static_cast<std::uint32_t>(c.pos.size());
    const float dt = 2e-4f;
    const Stages st = runStages(c, s, glm::vec3(0.15f), glm::vec3(-0.05f), false, dt);
    ASSERT_EQ(st.solver->listReadWidth(), rk2 ? 1u : 4u);
    const auto slotIds = st.store->readIds();
    const auto state = st.solver->state().readback<glm::vec4>(n);
    const auto accel = st.solver->accel().readback<glm::vec4>(n);
    auto model = modelOf(st.solver->params());
    model.continuity = true;
    ASSERT_NEAR(model.deltaSph, 0.1, 1e-7);
    // The reference over one second gives the rate (kg/m^3/s); over dt, the advanced density.
    model.lastDt = 1.0;
    const auto perSecond = reference::densityPressure(c.ref, model);
    model.lastDt = rk2 ? 0.0 : dt;
    const auto rp = reference::densityPressure(c.ref, model);
    const auto acc = reference::accelerations(c.ref, rp, model);
    double rateScale = 0.0, accelScale = 0.0;
    for (std::uint32_t i = 0; i < n; ++i) {
      if (c.ref[i].kind == 0) rateScale = std::max(rateScale, std::abs(perSecond[i].x - c.ref[i].density));
      accelScale = std::max(accelScale, glm::length(acc[i]));
    }
    ASSERT_GT(rateScale * dt, 1.0) << "kg/m^3: a step must change the densities visibly";
    // Without the diffusion term the rates differ: the test sees it.
    reference::SphModel plain = model;
    plain.deltaSph = 0.0;
    plain.lastDt = 1.0;
    const auto plainPerSecond = reference::densityPressure(c.ref, plain);
    double diffusionScale = 0.0;
    for (std::uint32_t i = 0; i < n; ++i) diffusionScale = std::max(diffusionScale, std::abs(perSecond[i].x - plainPerSecond[i].x));
    ASSERT_GT(diffusionScale, 0.05 * rateScale);
    std::size_t fluid = 0;
    for (std::uint32_t slot = 0; slot < n; ++slot) {
      const std::uint32_t i = slotIds[slot];
      if (c.ref[i].kind != 0) continue;
      ++fluid;
      const double rateRef = perSecond[i].x - c.ref[i].density;
      if (rk2) {
        EXPECT_EQ(state[slot].x, c.normals[i].w) << "the carried density of particle " << i;
        EXPECT_NEAR(state[slot].z, rateRef, 1e-3 * rateScale) << "density rate of particle " << i;
      } else {
        EXPECT_NEAR(double(state[slot].x) - double(c.normals[i].w), rateRef * dt, 2e-4 + 1e-3 * rateScale * dt)
            << "density increment of particle " << i;
        EXPECT_EQ(state[slot].z, 0.0f);
      }
      EXPECT_NEAR(state[slot].y, rp[i].y, 7.0 * model.taitB * 4e-6 + 1e-5 * std::abs(rp[i].y)) << "pressure " << i;
      EXPECT_LT(glm::length(glm::dvec3(accel[slot]) - acc[i]), 2e-4 * accelScale) << "acceleration of particle " << i;
    }
    EXPECT_GT(fluid, 400u);
  }
}

// Periodic in x and y: every pair term across the seams (found through wrapped neighbour
// cells, with minimum-image separations) matches the reference, which compares every pair
// by the minimum image.
TEST_F(SphStageTest, PeriodicAxesMatchReferenceAcrossTheSeams) {
  auto rng = rngFor();
  sim::SphSettings s = settings();
  s.periodic = {true, true, false};
  // Periods of 9 and 10 spacings (3.1 and 3.5 list radii of 2.86 dp), then of 9 and 8 (2.8 list
  // radii): the list grid's cells along y are then R / 2, as five of 2R/3 do not fit.
  for (const sim::ListLayout layout : {sim::ListLayout::Contiguous, sim::ListLayout::Clusters})
  for (const int ny : {10, 8}) {
  SCOPED_TRACE("period along y of " + std::to_string(ny) + " spacings, " +
               (layout == sim::ListLayout::Clusters ? "clusters" : "contiguous lists"));
  s.listLayout = layout;
  const int nx = 9;
  Case c = makeCase(rng, s, nx, ny, 6, 0.3f, true);
  // A spray of 80 particles over the block (0.03 of its density): clusters of consecutive slots
  // there span rows of cells far apart, and the cluster passes take those images per member.
  std::uniform_real_distribution<float> sx(0.0f, float(nx) * s.spacing), sy(0.0f, float(ny) * s.spacing),
      sz(7.0f * s.spacing, 14.0f * s.spacing);
  std::normal_distribution<float> sprayV(0.0f, 0.3f);
  for (int k = 0; k < 80; ++k) {
    c.pos.emplace_back(sx(rng), sy(rng), sz(rng), s.particleMass());
    c.vel.emplace_back(sprayV(rng), sprayV(rng), sprayV(rng), float(sim::ParticleKind::Fluid));
    c.normals.emplace_back(0.0f);
    reference::SphParticle p;
    p.x = glm::dvec3(c.pos.back());
    p.v = glm::dvec3(c.vel.back());
    p.mass = c.pos.back().w;
    p.kind = 0;
    c.ref.push_back(p);
  }
  const auto n = static_cast<std::uint32_t>(c.pos.size());
  const glm::vec3 lo(0.0f, 0.0f, -0.05f), hi(float(nx) * s.spacing, float(ny) * s.spacing, 0.15f);
  const Stages st = runStages(c, s, hi, lo);
  ASSERT_EQ(st.solver->usesClusters(), layout == sim::ListLayout::Clusters);
  const auto model = modelOf(st.solver->params());
  ASSERT_NEAR(model.period.x, nx * s.spacing, 1e-7);
  ASSERT_NEAR(model.period.y, ny * s.spacing, 1e-7);
  ASSERT_EQ(model.period.z, 0.0);
  EXPECT_FLOAT_EQ(st.solver->grid().spec().cellScale.y, ny == 10 ? 8.0f / 3.0f : 2.0f);
  // The case must have pairs that interact only across a seam.
  std::size_t seamPairs = 0;
  for (std::size_t i = 0; i < c.ref.size(); ++i)
    for (std::size_t j = 0; j < c.ref.size(); ++j) {
      const double direct = glm::length(c.ref[i].x - c.ref[j].x);
      seamPairs += direct >= 2.0 * model.h && glm::length(reference::separation(model, c.ref[i].x, c.ref[j].x)) < 2.0 * model.h;
    }
  EXPECT_GT(seamPairs, 1000u);

  const auto slotIds = st.store->readIds();
  if (layout == sim::ListLayout::Clusters) {
    // The cluster passes take a compact cluster's images once per entry and a wide one's per
    // member and entry (common/cluster_frame.glsl): the case must have both kinds.
    std::uint32_t fluid = 0;
    while (fluid < n && c.ref[slotIds[fluid]].kind == 0) ++fluid;
    int compact = 0, wide = 0;
    for (std::uint32_t first = 0; first < fluid; first += HEMO_CLUSTER_SIZE) {
      const glm::dvec3 x0 = c.ref[slotIds[first]].x;
      glm::dvec3 boxLo = x0, boxHi = x0;
      for (std::uint32_t slot = first + 1; slot < std::min(first + HEMO_CLUSTER_SIZE, fluid); ++slot) {
        const glm::dvec3 u = x0 + reference::separation(model, c.ref[slotIds[slot]].x, x0);
        boxLo = glm::min(boxLo, u);
        boxHi = glm::max(boxHi, u);
      }
      const glm::dvec3 extent = boxHi - boxLo;
      const bool isCompact = extent.x < model.period.x - 4.0 * model.h && extent.y < model.period.y - 4.0 * model.h;
      ++(isCompact ? compact : wide);
    }
    EXPECT_GT(compact, 50);
    EXPECT_GT(wide, 5);
    std::printf("  clusters: %d compact, %d wide\n", compact, wide);
  }
  const auto state = st.solver->state().readback<glm::vec4>(n);
  const auto accel = st.solver->accel().readback<glm::vec4>(n);
  const auto rp = reference::densityPressure(c.ref, model);
  const auto acc = reference::accelerations(c.ref, rp, model);
  double accelScale = 0.0;
  for (const auto& a : acc) accelScale = std::max(accelScale, glm::length(a));
  for (std::uint32_t slot = 0; slot < n; ++slot) {
    const std::uint32_t i = slotIds[slot];
    EXPECT_NEAR(state[slot].x, rp[i].x, 2e-6 * rp[i].x) << "density of particle " << i << " kind " << c.ref[i].kind;
    EXPECT_NEAR(state[slot].y, rp[i].y, 7.0 * model.taitB * 4e-6 + 1e-5 * std::abs(rp[i].y)) << "pressure " << i;
    if (c.ref[i].kind != 0) continue;
    EXPECT_LT(glm::length(glm::dvec3(accel[slot]) - acc[i]), 2e-4 * accelScale) << "acceleration of particle " << i;
  }
  }
}

// The neighbour list holds exactly the pairs closer than the list radius (by the minimum
// image on periodic axes): every other particle for a fluid particle, only fluid ones for a
// boundary particle. Random positions over a box periodic in x (7 cells of half the radius)
// and bounded in y and z, with particles outside the grid, in boundary-only regions and
// clustered, against a brute-force search in double precision. Pairs within 1e-5 of the
// radius are left out of the comparison (float rounding decides them).
// The lists of `c` hold exactly the pairs within the list radius
// (brute force; `period` > 0: x periodic with that period), in both memory layouts, in the
// same order.
// `run(settings)` runs the stages on them.
template <class Run>
void expectListsMatchBruteForce(const Case& c, sim::SphSettings s, float period, Run run) {
  const auto n = static_cast<std::uint32_t>(c.pos.size());
  const double R = s.listRadius();
  s.neighbourCapacity = 1024;
  // Both memory layouts of the list (interface/sph.h) must hold the same entries in the
  // same order.
  std::vector<std::uint32_t> firstLists;
  for (const sim::ListLayout layout : {sim::ListLayout::Interleaved, sim::ListLayout::Contiguous}) {
    s.listLayout = layout;
    const auto st = run(s);
    ASSERT_EQ(st.solver->readStatus().neighbourOverflow, 0u);
    const auto slotIds = st.store->readIds();
    const auto counts = st.solver->neighbourCounts().template readback<std::uint32_t>(n);
    const std::uint32_t entryStride = st.solver->params().listStride;
    const std::uint32_t particleStride = st.solver->params().listParticleStride;
    ASSERT_EQ(layout == sim::ListLayout::Interleaved ? particleStride : entryStride, 1u);
    const auto list = st.solver->neighbourList().template readback<std::uint32_t>(std::size_t(n) * s.neighbourCapacity);
    std::vector<std::uint32_t> flat;  // every list in slot order, as ids
    std::size_t pairs = 0, seam = 0, mismatches = 0, kindMismatches = 0, boundaryEntries = 0;
    for (std::uint32_t slot = 0; slot < n; ++slot) {
      const std::uint32_t i = slotIds[slot];
      const bool fluidI = c.vel[i].w == float(sim::ParticleKind::Fluid);
      std::vector<std::uint32_t> got;
      for (std::uint32_t k = 0; k < counts[slot]; ++k) {
        const std::uint32_t entry = list[std::size_t(slot) * particleStride + std::size_t(k) * entryStride];
        const std::uint32_t j = slotIds[entry & ~sim::SphSolver::kListBoundaryBit];
        got.push_back(j);
        // a boundary or wall neighbour's entry is marked
        kindMismatches += ((entry & sim::SphSolver::kListBoundaryBit) != 0) != (c.vel[j].w != float(sim::ParticleKind::Fluid));
        boundaryEntries += (entry & sim::SphSolver::kListBoundaryBit) != 0;
      }
      flat.insert(flat.end(), got.begin(), got.end());
      std::sort(got.begin(), got.end());
      ASSERT_TRUE(std::adjacent_find(got.begin(), got.end()) == got.end()) << "particle " << i << " lists a neighbour twice";
      std::vector<std::uint32_t> want;
      for (std::uint32_t j = 0; j < n; ++j) {
        if (j == i || (!fluidI && c.vel[j].w != float(sim::ParticleKind::Fluid))) continue;
        glm::dvec3 d = glm::dvec3(c.pos[i]) - glm::dvec3(c.pos[j]);
        if (period > 0.0f) d.x -= period * std::round(d.x / period);
        const double r = glm::length(d);
        if (std::abs(r - R) < 1e-5 * R) {  // undecided by float rounding: accept either
          got.erase(std::remove(got.begin(), got.end(), j), got.end());
          continue;
        }
        if (r < R) {
          want.push_back(j);
          seam += period > 0.0f && std::abs(double(c.pos[i].x) - c.pos[j].x) >= R;
        }
      }
      pairs += want.size();
      if (got != want && ++mismatches <= 5) {
        ADD_FAILURE() << "particle " << i << (fluidI ? " (fluid)" : " (boundary)") << " at (" << c.pos[i].x << ", "
                      << c.pos[i].y << ", " << c.pos[i].z << ") lists " << got.size() << " neighbours, brute force finds "
                      << want.size();
      }
    }
    EXPECT_EQ(mismatches, 0u);
    EXPECT_EQ(kindMismatches, 0u) << "entries whose boundary mark does not match the neighbour's kind";
    EXPECT_GT(boundaryEntries, 1000u);
    EXPECT_GT(pairs, 20000u);
    if (period > 0.0f) {
      EXPECT_GT(seam, 1000u) << "the case must have pairs across the periodic seam";
    }
    if (firstLists.empty()) {
      firstLists = flat;
    } else {
      EXPECT_TRUE(flat == firstLists) << "the two layouts list different neighbours or orders";
    }
  }
}

TEST_F(SphStageTest, NeighbourListHoldsExactlyThePairsWithinTheListRadius) {
  auto rng = rngFor();
  sim::SphSettings s = settings();
  s.periodic = {true, false, false};
  const double R = s.listRadius();
  const float period = float(3.6 * R);
  const glm::vec3 lo(0.0f, -0.02f, -0.02f), hi(period, 0.06f, 0.05f);
  std::uniform_real_distribution<float> ux(0.0f, period), uy(-0.03f, 0.07f), uz(-0.03f, 0.06f), unit(0.0f, 1.0f);
  std::normal_distribution<float> cluster(0.0f, 0.004f);
  Case c;
  const float m = s.particleMass();
  for (int k = 0; k < 3000; ++k) {
    glm::vec3 x(ux(rng), uy(rng), uz(rng));
    if (k % 5 == 0) x = glm::vec3(ux(rng), 0.02f + cluster(rng), 0.01f + cluster(rng));
    x.x -= period * std::floor(x.x / period);
    // Boundary particles everywhere, fluid only in the band 0.025 < y < 0.05, so some cells
    // hold none, and boundary particles on both sides of it have fluid in only some of the
    // rows they scan (build_list.comp skips a boundary particle's rows in blocks when they
    // hold no fluid; rows are 1.43 cm here, so below the band a row without fluid lies
    // between a particle and fluid within its reach).
    const bool fluid = x.y > 0.025f && x.y < 0.05f && unit(rng) < 0.6f;
    c.pos.emplace_back(x, m);
    c.vel.emplace_back(0.0f, 0.0f, 0.0f, float(fluid ? sim::ParticleKind::Fluid : sim::ParticleKind::Boundary));
    c.normals.emplace_back(0.0f, 0.0f, 1.0f, 0.0f);
  }
  expectListsMatchBruteForce(c, s, period, [&](const sim::SphSettings& ss) { return runStages(c, ss, hi, lo, true); });
}

// The same on bounded axes with particles outside the grid on every side, some many cells
// out: they are clamped into the edge cells, and each lists exactly its neighbours there, as
// they list it (a particle beyond an x face listed nothing in the edge cell, so a neighbour
// inside pushed it and felt no push back: momentum leaked where blood left the domain).
TEST_F(SphStageTest, ParticlesOutsideTheGridListExactlyTheirNeighbours) {
  auto rng = rngFor();
  sim::SphSettings s = settings();
  const double R = s.listRadius();
  const glm::vec3 lo(0.0f, -0.02f, -0.02f), hi(0.05f, 0.04f, 0.04f);
  std::uniform_real_distribution<float> ux(-0.03f, 0.08f), uy(-0.05f, 0.07f), uz(-0.05f, 0.07f), unit(0.0f, 1.0f);
  Case c;
  const float m = s.particleMass();
  std::size_t farOut = 0;
  for (int k = 0; k < 3000; ++k) {
    glm::vec3 x(ux(rng), uy(rng), uz(rng));
    if (k % 7 == 0) x.x = k % 2 == 0 ? hi.x + float(2.5 * R) + 0.2f * float(R) * unit(rng) : lo.x - float(2.5 * R) - 0.2f * float(R) * unit(rng);
    farOut += x.x > hi.x + 2.0 * R || x.x < lo.x - 2.0 * R;
    const bool fluid = unit(rng) < 0.7f;
    c.pos.emplace_back(x, m);
    c.vel.emplace_back(0.0f, 0.0f, 0.0f, float(fluid ? sim::ParticleKind::Fluid : sim::ParticleKind::Boundary));
    c.normals.emplace_back(0.0f, 0.0f, 1.0f, 0.0f);
  }
  ASSERT_GT(farOut, 300u);
  expectListsMatchBruteForce(c, s, 0.0f, [&](const sim::SphSettings& ss) { return runStages(c, ss, hi, lo, true); });
}

// A particle's list filled to exactly its capacity keeps every neighbour: the candidates the
// build walks after the last neighbour must not take its slot (where they do, a particle with
// exactly `capacity` neighbours silently loses one). One neighbour more is an
// overflow. The capacity is set to the largest count a first build finds.
TEST_F(SphStageTest, ListFilledToItsCapacityKeepsEveryNeighbour) {
  auto rng = rngFor();
  sim::SphSettings s = settings();
  s.listLayout = sim::ListLayout::Contiguous;
  const Case c = makeCase(rng, s, 8, 7, 6);
  const auto n = static_cast<std::uint32_t>(c.pos.size());
  auto lists = [&](std::uint32_t capacity, std::uint32_t& overflow, std::uint32_t& most) {
    s.neighbourCapacity = capacity;
    const Stages st = runStages(c, s, glm::vec3(0.15f), glm::vec3(-0.05f), true);
    const auto status = st.solver->readStatus();
    overflow = status.neighbourOverflow;
    most = status.maxNeighbours;
    const auto slotIds = st.store->readIds();
    const auto counts = st.solver->neighbourCounts().readback<std::uint32_t>(n);
    const auto list = st.solver->neighbourList().readback<std::uint32_t>(std::size_t(n) * capacity);
    std::vector<std::vector<std::uint32_t>> byId(n);
    for (std::uint32_t slot = 0; slot < n; ++slot) {
      auto& got = byId[slotIds[slot]];
      for (std::uint32_t k = 0; k < std::min(counts[slot], capacity); ++k) {
        got.push_back(slotIds[list[std::size_t(slot) * capacity + k] & ~sim::SphSolver::kListBoundaryBit]);
      }
      std::sort(got.begin(), got.end());
    }
    return byId;
  };
  std::uint32_t overflow = 0, most = 0;
  const auto roomy = lists(512, overflow, most);
  ASSERT_EQ(overflow, 0u);
  ASSERT_GT(most, 30u);
  std::size_t full = 0;
  for (const auto& l : roomy) full += l.size() == most;
  std::uint32_t mostAgain = 0;
  const auto exact = lists(most, overflow, mostAgain);
  EXPECT_EQ(overflow, 0u) << "a list of exactly its capacity is not an overflow";
  EXPECT_EQ(mostAgain, most);
  std::size_t differ = 0;
  for (std::uint32_t i = 0; i < n; ++i) differ += exact[i] != roomy[i];
  EXPECT_EQ(differ, 0u) << "particles whose list at capacity " << most << " differs (" << full << " fill it)";
  lists(most - 1, overflow, mostAgain);
  EXPECT_EQ(overflow, std::uint32_t(full)) << "every particle with one neighbour too many overflows";
}

// A build that sorts only the fluid's slots (the rigid boundary particles stay where the last
// whole build put them, sph.cpp recordStep) gives the grid, slots and lists a whole build
// gives, after the fluid has moved: bit for bit.
TEST_F(SphStageTest, PartialGridBuildMatchesAWholeBuild) {
  auto rng = rngFor();
  sim::SphSettings s = settings();
  s.periodic = {true, false, false};
  const float period = float(3.6 * s.listRadius());
  const glm::vec3 lo(0.0f, -0.02f, -0.02f), hi(period, 0.06f, 0.05f);
  std::normal_distribution<float> jitter(0.0f, 0.006f);
  const Case c = randomCase(rng, s, period);
  const auto n = static_cast<std::uint32_t>(c.pos.size());
  s.neighbourCapacity = 1024;
  s.listLayout = sim::ListLayout::Contiguous;  // every particle's own list (clusters: ClusterListsHoldEachPairOnce)
  const Stages st = runStages(c, s, hi, lo, true);  // a whole build: the slots now in grid order
  const std::uint32_t fluid = st.store->fluidCount();
  ASSERT_GT(fluid, 300u);
  ASSERT_LT(fluid, n - 300u);
  // Move the fluid (past the seam too, and out of the grid on the bounded axes) behind the
  // store's back, as the integrator does.
  auto pos = st.store->readPositions();
  for (std::uint32_t slot = 0; slot < fluid; ++slot) pos[slot] += glm::vec4(jitter(rng), jitter(rng), jitter(rng), 0.0f);
  st.store->live().positions.upload(pos);
  const auto idsBefore = st.store->readIds();
  struct Build {
    std::vector<std::uint32_t> cellStart, ids, counts, list;
    std::vector<glm::vec4> pos;
  };
  auto build = [&](std::uint32_t sorted) {
    gpu::CommandRecorder rec(ctx());
    rec.begin();
    st.solver->recordNeighbours(rec, sorted);
    rec.end();
    rec.submitAndWait();
    Build b;
    b.cellStart = st.solver->grid().cellStart().readback<std::uint32_t>(st.solver->grid().spec().keyCount() + 1);
    b.ids = st.store->readIds();
    b.pos = st.store->readPositions();
    b.counts = st.solver->neighbourCounts().readback<std::uint32_t>(n);
    b.list = st.solver->neighbourList().readback<std::uint32_t>(std::size_t(n) * s.neighbourCapacity);
    return b;
  };
  const Build partial = build(fluid);
  const Build whole = build(n);
  EXPECT_TRUE(partial.cellStart == whole.cellStart) << "cell ranges";
  EXPECT_TRUE(partial.ids == whole.ids) << "slot order";
  EXPECT_EQ(std::memcmp(partial.pos.data(), whole.pos.data(), n * sizeof(glm::vec4)), 0) << "positions";
  EXPECT_TRUE(partial.counts == whole.counts) << "list lengths";
  std::size_t entries = 0, mismatches = 0;
  for (std::uint32_t slot = 0; slot < n; ++slot) {
    for (std::uint32_t k = 0; k < whole.counts[slot]; ++k) {
      const std::size_t at = std::size_t(slot) * st.solver->params().listParticleStride +
                             std::size_t(k) * st.solver->params().listStride;
      ++entries;
      mismatches += partial.list[at] != whole.list[at];
    }
  }
  EXPECT_EQ(mismatches, 0u) << "list entries";
  EXPECT_GT(entries, 20000u);
  EXPECT_NE(partial.ids, idsBefore) << "the fluid's moves must change the slot order, or nothing is tested";
}

// The density pass's interacting pairs: of each fluid particle's list, exactly the entries
// within interaction range (the support, or the repulsion's reach where larger), the fluid
// ones from the first entry and the boundary ones from the last, each in list order, in both
// list layouts. The list's skin must leave entries out, or nothing is tested.
TEST_F(SphStageTest, InteractingPairsAreTheListEntriesWithinRange) {
  auto rng = rngFor();
  sim::SphSettings s = settings();
  const Case c = makeCase(rng, s, 8, 7, 6);
  const auto n = static_cast<std::uint32_t>(c.pos.size());
  for (const sim::ListLayout layout : {sim::ListLayout::Interleaved, sim::ListLayout::Contiguous}) {
    SCOPED_TRACE(layout == sim::ListLayout::Interleaved ? "interleaved" : "contiguous");
    s.listLayout = layout;
    const Stages st = runStages(c, s, glm::vec3(0.15f));
    const sim::SphParams& p = st.solver->params();
    const double reach = std::abs(double(p.repulsionCutoff)) + p.wallSpacing;
    const double keep2 = std::max(double(p.supportRadius) * p.supportRadius, reach * reach + double(p.wallSpacing) * p.wallSpacing);
    const auto positions = st.store->readPositions();
    const auto velocities = st.store->live().velocities.readback<glm::vec4>(n);
    const auto counts = st.solver->neighbourCounts().readback<std::uint32_t>(n);
    const auto list = st.solver->neighbourList().readback<std::uint32_t>(std::size_t(n) * s.neighbourCapacity);
    const auto pairCounts = st.solver->interactingPairCounts().readback<std::uint32_t>(n);
    const auto pairs = st.solver->interactingPairs().readback<std::uint32_t>(std::size_t(n) * s.neighbourCapacity);
    auto at = [&](std::uint32_t slot, std::uint32_t k) {
      return std::size_t(slot) * p.listParticleStride + std::size_t(k) * p.listStride;
    };
    std::size_t fluid = 0, listed = 0, kept = 0, keptBoundary = 0, mismatches = 0;
    for (std::uint32_t slot = 0; slot < n; ++slot) {
      if (velocities[slot].w != float(sim::ParticleKind::Fluid)) continue;
      ++fluid;
      // in range: the fluid neighbours in list order, then the boundary ones in list order
      std::vector<std::uint32_t> wantFluid, wantBoundary, got, undecided;
      for (std::uint32_t k = 0; k < counts[slot]; ++k) {
        const std::uint32_t entry = list[at(slot, k)];
        const std::uint32_t j = entry & ~sim::SphSolver::kListBoundaryBit;
        const double r2 = glm::dot(glm::dvec3(positions[slot]) - glm::dvec3(positions[j]),
                                   glm::dvec3(positions[slot]) - glm::dvec3(positions[j]));
        if (std::abs(r2 - keep2) < 1e-5 * keep2) {
          undecided.push_back(j);  // float rounding may decide either way
        } else if (r2 < keep2) {
          (velocities[j].w == float(sim::ParticleKind::Fluid) ? wantFluid : wantBoundary).push_back(j);
        }
      }
      std::vector<std::uint32_t> want = wantFluid;
      want.insert(want.end(), wantBoundary.begin(), wantBoundary.end());
      // the pair list: fluid pairs from entry 0 up, boundary pairs from the last entry down
      const std::uint32_t fluidPairs = pairCounts[slot] & 0xffffu, boundaryPairs = pairCounts[slot] >> 16;
      ASSERT_LE(fluidPairs + boundaryPairs, counts[slot]);
      std::vector<std::uint32_t> order;
      for (std::uint32_t k = 0; k < fluidPairs; ++k) order.push_back(k);
      for (std::uint32_t k = 0; k < boundaryPairs; ++k) order.push_back(s.neighbourCapacity - 1 - k);
      for (const std::uint32_t k : order) {
        const std::uint32_t j = pairs[at(slot, k)];
        if (std::find(undecided.begin(), undecided.end(), j) == undecided.end()) got.push_back(j);
      }
      listed += counts[slot];
      kept += fluidPairs + boundaryPairs;
      keptBoundary += boundaryPairs;
      if (got != want && ++mismatches <= 5) {
        ADD_FAILURE() << "slot " << slot << ": " << got.size() << " interacting pairs, " << want.size()
                      << " list entries within range (or another order)";
      }
    }
    EXPECT_EQ(mismatches, 0u);
    EXPECT_GT(fluid, 300u);
    EXPECT_GT(keptBoundary, 1000u) << "the case must have boundary pairs";
    EXPECT_LT(kept, listed * 9 / 10) << "the list's skin should hold entries beyond the interaction range";
    EXPECT_GT(kept, listed / 2);
  }
}

// recordStep rebuilds the grid and the neighbour list only when the two largest reaches
// (distance moved since the build relative to the middle of the x displacements, GPU-reduced
// in the integrator) sum to more than the list's skin.
TEST_F(SphStageTest, NeighbourListIsRebuiltOnlyWhenTwoParticlesMayHaveClosedInByTheSkin) {
  auto rng = rngFor();
  sim::SphSettings s = settings();
  s.maxTimeStep = 1.0e-6f;  // particles move ~1e-6 m per step: far below the threshold
  const Case c = makeCase(rng, s, 6, 5, 5, 0.1f);
  const auto n = static_cast<std::uint32_t>(c.pos.size());
  sim::ParticleStore store(ctx(), n);
  store.upload(c.pos, c.vel, {}, c.normals);
  sim::SphSolver solver(ctx(), store, glm::vec3(-0.05f), glm::vec3(0.12f), s);
  ASSERT_GT(solver.rebuildThreshold(), 0.0f);
  gpu::CommandRecorder rec(ctx());
  std::uint32_t step = 0;
  auto steps = [&](int count) {
    rec.begin();
    if (step == 0) solver.recordReset(rec);
    for (int k = 0; k < count; ++k, ++step) solver.recordStep(rec, step, std::uint32_t(k));
    rec.end();
    rec.submitAndWait();
    return solver.readRebuilds();
  };
  EXPECT_EQ(steps(1), 1u) << "the first step builds the list";
  EXPECT_EQ(steps(5), 1u) << "tiny motion keeps the list";
  // The test compares displacements since the build with the middle c of their x range at
  // the step before (sph/integrate.comp): it must rebuild once two
  // particles may have closed in by the skin (twice the threshold), and need not for a drift
  // they share. Each move below is measured by the step after it and acted on by the one
  // after that.
  const float threshold = solver.rebuildThreshold();
  const auto vel = store.readVelocities();
  std::uint32_t moved = n;
  for (std::uint32_t i = 0; i < n && moved == n; ++i) {
    if (vel[i].w == 0.0f) moved = i;
  }
  ASSERT_LT(moved, n);
  // Rigid boundary particles never move (the solver leaves them out of the integrator and
  // counts them at displacement 0): the moves below shift fluid particles only.
  auto move = [&](glm::vec3 all, glm::vec3 one) {
    auto pos = store.readPositions();
    for (std::size_t i = 0; i < pos.size(); ++i) {
      if (vel[i].w == 0.0f) pos[i] += glm::vec4(all, 0.0f);
    }
    pos[moved] += glm::vec4(one, 0.0f);
    store.live().positions.upload(pos);
  };
  // The fluid 1.5 thresholds along x, a tenth at a time as a flow drifts past a wall: the
  // fluid has closed in on the wall by less than the skin (2 thresholds), no rebuild (x range
  // 0 .. 1.5, reach 0.75 from the middle; the bare largest displacement, 1.5, would have
  // rebuilt).
  for (int k = 0; k < 10; ++k) {
    move(glm::vec3(0.15f * threshold, 0.0f, 0.0f), glm::vec3(0.0f));
    EXPECT_EQ(steps(1), 1u) << "a common drift keeps the list (move " << k << ")";
  }
  EXPECT_EQ(steps(1), 1u);
  // One fluid particle 0.3 thresholds further, a fifth at a time: x range 0 .. 1.8, reach 0.9
  // from the middle (a little more from the lagging prediction): the list still holds.
  for (int k = 0; k < 5; ++k) {
    move(glm::vec3(0.0f), glm::vec3(0.06f * threshold, 0.0f, 0.0f));
    EXPECT_EQ(steps(1), 1u) << "a relative move under the skin keeps the list (move " << k << ")";
  }
  // 0.3 further (2.1 thresholds from the wall, past the skin): reach 1.05 from the middle,
  // > 1: rebuild.
  move(glm::vec3(0.0f), glm::vec3(0.3f * threshold, 0.0f, 0.0f));
  EXPECT_EQ(steps(1), 1u);
  EXPECT_EQ(steps(1), 2u) << "a particle past the skin relative to the others forces a rebuild";
  EXPECT_EQ(steps(3), 2u) << "and the new list serves again";
  // Across the flow there is no common reference. One particle alone 1.05 thresholds along y,
  // every other still: two particles can have closed in by 1.05 at most, about half the skin
  // (the test's half-sum of the two largest reaches is 0.53): the list holds.
  move(glm::vec3(0.0f), glm::vec3(0.0f, 1.05f * threshold, 0.0f));
  EXPECT_EQ(steps(1), 2u);
  EXPECT_EQ(steps(1), 2u) << "one particle alone past half the skin keeps the list";
  // 1.05 further (2.1 thresholds, past the skin): rebuild.
  move(glm::vec3(0.0f), glm::vec3(0.0f, 1.05f * threshold, 0.0f));
  EXPECT_EQ(steps(1), 2u);
  EXPECT_EQ(steps(1), 3u) << "a move across x past the skin forces a rebuild";
  // A rebuild request (for profiling a rebuild step) opens the gate for the next step only.
  rec.begin();
  solver.recordRebuildRequest(rec);
  solver.recordStep(rec, step++, 0);
  solver.recordStep(rec, step++, 1);
  rec.end();
  rec.submitAndWait();
  EXPECT_EQ(solver.readRebuilds(), 4u) << "a requested rebuild happens once";
}

// Between list builds each force evaluation updates only the boundary particles with fluid
// in their list (the active list, sorted out after every build); the others keep the state of
// the build, and recordBoundaryRest brings them to the last force evaluation's background
// pressure without touching the active ones. With a background pressure ramping ~30 Pa per
// step, a stale state is visible. Per-particle lists, and the boundary particles' clusters,
// where a particle is active when its cluster lists fluid.
TEST_F(SphStageTest, BoundaryParticlesWithoutFluidAreSetAtTheBuildAndOnRequest) {
  auto rng = rngFor();
  sim::SphSettings s = settings();
  s.maxTimeStep = 1.0e-4f;
  s.backgroundPressure = 3000.0f;
  s.backgroundPressureRamp = 0.01f;
  Case c = makeCase(rng, s, 6, 5, 5, 0.01f);
  // and a patch of boundary particles beyond the list radius of any fluid (x >= 0.095 m
  // against the fluid's x < 0.06 m), which fills clusters of its own
  for (int layer = 0; layer < 2; ++layer)
    for (int j = -2; j < 7; ++j)
      for (int i = 0; i < 3; ++i) {
        c.pos.emplace_back(0.095f + 0.01f * float(i), (j + 0.5f) * s.spacing, -(layer + 0.5f) * s.spacing, s.particleMass());
        c.vel.emplace_back(0.0f, 0.0f, 0.0f, float(sim::ParticleKind::Boundary));
        c.normals.emplace_back(0.0f, 0.0f, 1.0f, 0.0f);
      }
  const auto n = static_cast<std::uint32_t>(c.pos.size());
  for (const sim::ListLayout layout : {sim::ListLayout::Contiguous, sim::ListLayout::Clusters}) {
    SCOPED_TRACE(layout == sim::ListLayout::Clusters ? "clusters" : "per-particle lists");
    s.listLayout = layout;
    sim::ParticleStore store(ctx(), n);
    store.upload(c.pos, c.vel, {}, c.normals);
    sim::SphSolver solver(ctx(), store, glm::vec3(-0.05f), glm::vec3(0.12f), s);
    gpu::CommandRecorder rec(ctx());
    rec.begin();
    solver.recordReset(rec);
    for (std::uint32_t k = 0; k < 6; ++k) solver.recordStep(rec, k, k);
    rec.end();
    rec.submitAndWait();
    ASSERT_EQ(solver.readRebuilds(), 1u) << "the case must keep its first list";
    ASSERT_EQ(solver.usesBoundaryClusters(), layout == sim::ListLayout::Clusters);
    const sim::SphClock clock = solver.readClock();
    ASSERT_GT(clock.lastDt, 0.0);
    const auto vel = store.readVelocities();
    const std::uint32_t fluid = store.fluidCount();
    std::vector<bool> listsFluid(n, false);
    if (solver.usesBoundaryClusters()) {
      const std::uint32_t first = (fluid + HEMO_CLUSTER_SIZE - 1) / HEMO_CLUSTER_SIZE;
      const auto counts = solver.clusterCounts().readback<std::uint32_t>(first + (n - fluid + 3) / 4);
      for (std::uint32_t slot = fluid; slot < n; ++slot) {
        listsFluid[slot] = (counts[first + (slot - fluid) / HEMO_CLUSTER_SIZE] & 0xffffu) > 0;
      }
    } else {
      const auto counts = solver.neighbourCounts().readback<std::uint32_t>(n);
      for (std::uint32_t slot = 0; slot < n; ++slot) listsFluid[slot] = counts[slot] > 0;
    }
    const auto before = solver.state().readback<glm::vec4>(n);
    rec.begin();
    solver.recordBoundaryRest(rec);
    rec.end();
    rec.submitAndWait();
    const auto after = solver.state().readback<glm::vec4>(n);
    // The last force evaluation ran at the clock before the last step.
    auto background = [&](double t) { return 3000.0 * std::clamp(t / 0.01, 0.0, 1.0); };
    const double pLast = background(clock.time - clock.lastDt);
    const double pBuild = background(0.0);
    std::size_t active = 0, rest = 0;
    for (std::uint32_t slot = 0; slot < n; ++slot) {
      if (vel[slot].w == float(sim::ParticleKind::Fluid)) continue;
      if (listsFluid[slot]) {
        ++active;
        EXPECT_EQ(after[slot], before[slot]) << "an active boundary particle was changed, slot " << slot;
        EXPECT_GT(before[slot].x, 0.0f);
        continue;
      }
      ++rest;
      EXPECT_NEAR(before[slot].y, pBuild, 1e-3) << "without fluid: the build's background pressure, slot " << slot;
      EXPECT_NEAR(after[slot].y, pLast, 1e-2) << "without fluid: the last evaluation's background pressure, slot " << slot;
      EXPECT_NEAR(after[slot].x, s.restDensity, 1e-3 * s.restDensity) << "slot " << slot;
    }
    EXPECT_GT(active, 30u);
    EXPECT_GT(rest, 15u);
    EXPECT_GT(pLast - pBuild, 100.0) << "the ramp must make a stale state visible";
  }
}

// With SPS turbulence on, the accelerations (SPS stress from the strain rate, then its
// divergence) match the reference, and the SPS term is far from negligible in this case.
TEST_F(SphStageTest, SpsTurbulenceMatchesReference) {
  auto rng = rngFor();
  sim::SphSettings s = settings();
  s.sps = true;
  s.smagorinsky = 0.5f;  // larger than the usual 0.12, and a violent flow (6 m/s random
  s.blinn = 0.05f;       // velocities), so the SPS term is comparable to the pressure term
  const Case c = makeCase(rng, s, 8, 7, 6, 6.0f);
  const auto n = static_cast<std::uint32_t>(c.pos.size());
  // the list read four entries per texel (capacity 128) and one (capacity 130)
  for (const std::uint32_t capacity : {128u, 130u}) {
    SCOPED_TRACE(testing::Message() << "capacity " << capacity);
    s.listLayout = sim::ListLayout::Contiguous;
    s.neighbourCapacity = capacity;
    const Stages st = runStages(c, s, glm::vec3(0.12f));
    ASSERT_EQ(st.solver->listReadWidth(), capacity % 4u == 0u ? 4u : 1u);
    const auto slotIds = st.store->readIds();
    const auto accel = st.solver->accel().readback<glm::vec4>(n);
    auto model = modelOf(st.solver->params());
    ASSERT_TRUE(model.sps);
    const auto rp = reference::densityPressure(c.ref, model);
    const auto withSps = reference::accelerations(c.ref, rp, model);
    model.sps = false;
    const auto without = reference::accelerations(c.ref, rp, model);
    double scale = 0.0, spsScale = 0.0;
    for (std::size_t i = 0; i < withSps.size(); ++i) {
      scale = std::max(scale, glm::length(withSps[i]));
      spsScale = std::max(spsScale, glm::length(withSps[i] - without[i]));
    }
    EXPECT_GT(spsScale, 0.05 * scale) << "the SPS term should matter in this case: " << spsScale << " of " << scale;
    for (std::uint32_t slot = 0; slot < n; ++slot) {
      const std::uint32_t i = slotIds[slot];
      if (c.ref[i].kind != 0) continue;
      EXPECT_LT(glm::length(glm::dvec3(accel[slot]) - withSps[i]), 2e-4 * scale) << "particle " << i;
    }
  }
}

// Non-Newtonian blood (interface/sph.h, "Viscosity"): each fluid particle's viscosity from its
// shear rate (the Carreau-Yasuda law), then the accelerations with mu_i + mu_j in the viscous
// pair terms, against the reference; the list read four entries per texel and one, and the
// passes walking cells. The law must matter here: the viscosities spread over a factor of
// two or more, and the viscous term differs from that of Newtonian blood at mu_0.
TEST_F(SphStageTest, CarreauYasudaViscosityMatchesReference) {
  auto rng = rngFor();
  sim::SphSettings s = settings();
  s.rheology = sim::Rheology::CarreauYasuda;
  // from 1 Pa s at rest to 0.05, thinning from about 50 1/s; the random velocities (3 m/s)
  // shear the fluid at hundreds. A softer fluid (c0 = 10 m/s) than the other cases', so the
  // viscous term is not lost next to the pressure of the jittered lattice.
  s.carreau = {1.0f, 0.05f, 0.02f, 0.3f, 1.5f};
  s.soundSpeed = 10.0f;
  const Case c = makeCase(rng, s, 8, 7, 6, 3.0f);
  const auto n = static_cast<std::uint32_t>(c.pos.size());
  struct Variant {
    std::uint32_t capacity;
    sim::NeighbourSearch search;
  };
  for (const Variant variant : {Variant{128u, sim::NeighbourSearch::List}, Variant{130u, sim::NeighbourSearch::List},
                                Variant{128u, sim::NeighbourSearch::Cells}}) {
    SCOPED_TRACE(testing::Message() << "capacity " << variant.capacity
                                    << (variant.search == sim::NeighbourSearch::Cells ? ", walking cells" : ""));
    s.listLayout = sim::ListLayout::Auto;  // (non-Newtonian blood never walks clusters)
    s.neighbourCapacity = variant.capacity;
    s.neighbourSearch = variant.search;
    const Stages st = runStages(c, s, glm::vec3(0.12f));
    ASSERT_FALSE(st.solver->usesClusters());
    const auto slotIds = st.store->readIds();
    const auto accel = st.solver->accel().readback<glm::vec4>(n);
    const auto mu = st.solver->viscosities().readback<float>(n);
    auto model = modelOf(st.solver->params());
    ASSERT_TRUE(model.carreauYasuda);
    EXPECT_NEAR(model.powerIndex, 0.3, 1e-6);
    const auto rp = reference::densityPressure(c.ref, model);
    const auto muRef = reference::viscosities(c.ref, rp, model);
    const auto want = reference::accelerations(c.ref, rp, model);
    double lo = 1e30, hi = 0.0, worstMu = 0.0;
    for (std::uint32_t slot = 0; slot < n; ++slot) {
      const std::uint32_t i = slotIds[slot];
      if (c.ref[i].kind != 0) continue;
      lo = std::min(lo, muRef[i]);
      hi = std::max(hi, muRef[i]);
      worstMu = std::max(worstMu, std::abs(mu[slot] - muRef[i]) / muRef[i]);
      EXPECT_NEAR(mu[slot], muRef[i], 1e-4 * muRef[i]) << "particle " << i;
    }
    EXPECT_GT(hi, 2.0 * lo) << "the viscosities should spread: " << lo << " to " << hi << " Pa s";
    // The viscous term against that of Newtonian blood at mu_0 and of inviscid fluid.
    reference::SphModel newtonian = model;
    newtonian.carreauYasuda = false;
    newtonian.mu = model.mu0;
    const auto atRest = reference::accelerations(c.ref, rp, newtonian);
    newtonian.mu = 0.0;
    const auto inviscid = reference::accelerations(c.ref, rp, newtonian);
    double scale = 0.0, lawScale = 0.0, viscousScale = 0.0, worst = 0.0;
    for (std::size_t i = 0; i < want.size(); ++i) {
      scale = std::max(scale, glm::length(want[i]));
      lawScale = std::max(lawScale, glm::length(want[i] - atRest[i]));
      viscousScale = std::max(viscousScale, glm::length(want[i] - inviscid[i]));
    }
    EXPECT_GT(viscousScale, 0.02 * scale) << "the viscous term should matter in this case: " << viscousScale << " of " << scale;
    EXPECT_GT(lawScale, 0.3 * viscousScale) << "the law should matter: " << lawScale << " of the viscous term's " << viscousScale;
    for (std::uint32_t slot = 0; slot < n; ++slot) {
      const std::uint32_t i = slotIds[slot];
      if (c.ref[i].kind != 0) continue;
      worst = std::max(worst, glm::length(glm::dvec3(accel[slot]) - want[i]) / scale);
      EXPECT_LT(glm::length(glm::dvec3(accel[slot]) - want[i]), 2e-4 * scale) << "particle " << i;
    }
    std::printf("viscosities %.4g to %.4g Pa s (worst relative difference %.2g); viscous term %.3g and the law's effect "
                "%.3g of the largest acceleration, worst difference %.2g of it\n",
                lo, hi, worstMu, viscousScale / scale, lawScale / scale, worst);
  }
}

// DFSPH (interface/sph.h, "The pressure solver"): the divergence solve in the density pass
// (after a last step of 2e-4 s) and the density solve after the force pass, three corrections
// each (a tolerance no prediction meets, so both stop at the cap), against the reference's
// solves: the velocities, the accelerations a_np + a_p, the pressures and each solve's last
// mean error. The list read four entries per texel and one.
TEST_F(SphStageTest, DfsphSolvesMatchReference) {
  auto rng = rngFor();
  // (the compressible solve, the default, with either list width; the incompressible one)
  for (const auto& [capacity, compressible] : {std::pair{128u, true}, std::pair{130u, true}, std::pair{128u, false}}) {
    SCOPED_TRACE(testing::Message() << "capacity " << capacity << (compressible ? ", compressible" : ", incompressible"));
    sim::SphSettings s = settings();
    s.pressureSolver = sim::PressureSolver::Dfsph;
    s.solverCompressible = compressible;
    s.solverTolerance = 1.0e-7f;
    s.solverMaxIterations = 3;
    s.neighbourCapacity = capacity;
    s.listLayout = sim::ListLayout::Contiguous;
    s.backgroundPressure = 25.0f;  // in the force pass's pair terms, and added to the reported pressure
    const Case c = makeCase(rng, s, 9, 8, 7);
    const auto n = static_cast<std::uint32_t>(c.pos.size());
    const float lastDt = 2.0e-4f;
    Stages st = runStages(c, s, glm::vec3(0.15f), glm::vec3(-0.05f), false, lastDt);
    sim::SphSolver& solver = *st.solver;
    ASSERT_TRUE(solver.solvesPressure());
    ASSERT_FALSE(solver.usesClusters());
    ASSERT_EQ(solver.listReadWidth(), capacity % 4u == 0u ? 4u : 1u);
    const auto slotIds = st.store->readIds();
    const auto velAfterDivergence = st.store->readVelocities();
    const auto stateBefore = solver.state().readback<glm::vec4>(n);  // the density pass's (rho, p)
    {
      gpu::CommandRecorder rec(ctx());
      rec.begin();
      solver.recordPressureSolve(rec);
      rec.end();
      rec.submitAndWait();
    }
    const auto accel = solver.accel().readback<glm::vec4>(n);
    const auto state = solver.state().readback<glm::vec4>(n);
    const glm::vec2 limits = solver.stepLimits().readback<glm::vec2>(1)[0];
    const double dt = std::min(limits.x, solver.params().dtMax);
    ASSERT_GT(dt, 0.0);
    const auto model = modelOf(solver.params());
    const double floor = solver.params().solveFloor;
    ASSERT_GT(floor, 0.0);

    // the divergence solve
    const auto div = reference::dfsphDivergenceSolve(c.ref, model, floor, lastDt, 3);
    double speedScale = 0.0, divergenceChange = 0.0;
    for (std::size_t i = 0; i < c.ref.size(); ++i) {
      speedScale = std::max(speedScale, glm::length(div.values[i]));
      divergenceChange = std::max(divergenceChange, glm::length(div.values[i] - c.ref[i].v));
    }
    EXPECT_GT(divergenceChange, 0.05 * speedScale) << "the divergence solve should matter in this case";
    std::vector<reference::SphParticle> moved = c.ref;
    for (std::uint32_t slot = 0; slot < n; ++slot) {
      const std::uint32_t i = slotIds[slot];
      if (c.ref[i].kind != 0) continue;
      EXPECT_LT(glm::length(glm::dvec3(glm::vec3(velAfterDivergence[slot])) - div.values[i]), 2e-4 * speedScale)
          << "velocity of particle " << i << " after the divergence solve";
      moved[i].v = div.values[i];
    }
    const sim::PressureSolveStats divStats = solver.readPressureSolveStats(true);
    EXPECT_EQ(divStats.solves, 1u);
    EXPECT_EQ(divStats.lastIterations, 3u);
    EXPECT_EQ(divStats.capHits, 1u);
    EXPECT_NEAR(divStats.lastError, div.errors.back(), 2e-6 + 1e-3 * div.errors.back());

    // the density solve, from the non-pressure accelerations of the reference's forces (the
    // expansion side of the Tait law, p_bg at rho0 and above; boundary particles at rho0 with
    // their fluid's mean pressure)
    ASSERT_TRUE(model.dfsph);
    const double background = s.backgroundPressure;
    const auto rp = reference::densityPressure(moved, model);
    std::vector<double> rho(n);
    int expanded = 0, compressed = 0;
    for (std::size_t i = 0; i < moved.size(); ++i) {
      rho[i] = rp[i].x;
      if (moved[i].kind != 0) continue;
      expanded += rho[i] < model.rho0 && rp[i].y < background;
      compressed += rho[i] > model.rho0 && rp[i].y == background;
    }
    for (std::uint32_t slot = 0; slot < n; ++slot) {
      const std::uint32_t i = slotIds[slot];
      if (moved[i].kind != 0) continue;
      EXPECT_NEAR(stateBefore[slot].y, rp[i].y, 7.0 * model.taitB * 4e-6 + 1e-5 * background)
          << "the density pass's pressure of particle " << i;
    }
    EXPECT_GT(expanded, 0) << "some fluid should be expanded, below p_bg";
    EXPECT_GT(compressed, 0) << "some fluid should be compressed, at p_bg";
    const auto aNp = reference::accelerations(moved, rp, model);
    const auto dens = reference::dfsphDensitySolve(moved, rho, aNp, dt, model, floor, 3);
    ASSERT_EQ(model.solveCompliance > 0.0, compressible);
    if (compressible) {
      // the compliance should matter here: the incompressible solve's pressure differs
      reference::SphModel stiff = model;
      stiff.solveCompliance = 0.0;
      const auto incompressible = reference::dfsphDensitySolve(moved, rho, aNp, dt, stiff, floor, 3);
      double largest = 0.0, change = 0.0;
      for (std::size_t i = 0; i < moved.size(); ++i) {
        largest = std::max(largest, std::abs(incompressible.pressure[i]));
        change = std::max(change, std::abs(incompressible.pressure[i] - dens.pressure[i]));
      }
      EXPECT_GT(change, 0.05 * largest) << "the compliance should change the solved pressure in this case";
    }
    double accelScale = 0.0, pressureScale = 0.0, pressureChange = 0.0;
    for (std::size_t i = 0; i < moved.size(); ++i) {
      if (moved[i].kind != 0) continue;
      accelScale = std::max(accelScale, glm::length(dens.values[i]));
      pressureScale = std::max(pressureScale, div.pressure[i] * rho[i] * rho[i] / dt + dens.pressure[i]);
      pressureChange = std::max(pressureChange, glm::length(dens.values[i] - aNp[i]));
    }
    EXPECT_GT(pressureChange, 0.5 * accelScale) << "the pressure should dominate in this compressed case";
    int partial = 0;  // boundary particles between 0 and p_bg: next to expanded fluid
    for (std::uint32_t slot = 0; slot < n; ++slot) {
      const std::uint32_t i = slotIds[slot];
      if (moved[i].kind != 0) {
        // the boundary pass: rho0 and the fluid neighbours' mean pressure, within [0, p_bg]
        EXPECT_EQ(state[slot].x, float(model.rho0)) << "density of boundary particle " << i;
        EXPECT_NEAR(state[slot].y, rp[i].y, 1e-4 * background) << "pressure of boundary particle " << i;
        partial += rp[i].y > 0.01 * background && rp[i].y < 0.99 * background;
        continue;
      }
      EXPECT_LT(glm::length(glm::dvec3(accel[slot]) - dens.values[i]), 5e-4 * accelScale) << "acceleration of particle " << i;
      // the divergence solve's impulse over dt, then the density solve's corrections
      const double pressure = div.pressure[i] * rho[i] * rho[i] / dt + dens.pressure[i];
      EXPECT_NEAR(state[slot].y, rp[i].y + pressure, 5e-4 * pressureScale) << "pressure of particle " << i;
    }
    EXPECT_GT(partial, 0) << "some boundary particle should see expanded fluid";
    const sim::PressureSolveStats st2 = solver.readPressureSolveStats();
    EXPECT_EQ(st2.solves, 1u);
    EXPECT_EQ(st2.lastIterations, 3u);
    EXPECT_EQ(st2.capHits, 1u);
    EXPECT_NEAR(st2.lastError, dens.errors.back(), 2e-6 + 1e-3 * dens.errors.back());
    EXPECT_LT(dens.errors.back(), 0.5 * dens.errors.front()) << "three corrections should reduce the compression";
  }
}

TEST_F(SphStageTest, TimeStepLimitIsTheMinimumOfTheConditions) {
  auto rng = rngFor();
  const sim::SphSettings s = settings();
  const Case c = makeCase(rng, s, 6, 6, 5);
  const auto n = static_cast<std::uint32_t>(c.pos.size());
  const Stages st = runStages(c, s, glm::vec3(0.1f));
  const sim::ParticleStore& store = *st.store;
  const sim::SphSolver& solver = *st.solver;
  const auto vel = store.readVelocities();
  const auto accel = solver.accel().readback<glm::vec4>(n);
  const auto limits = solver.dtLimits().readback<float>(n);
  const auto& p = solver.params();
  for (std::uint32_t i = 0; i < n; ++i) {
    if (vel[i].w != 0.0f) {
      EXPECT_GT(limits[i], 1e30f);
      continue;
    }
    const double v = glm::length(glm::dvec3(vel[i])), a = glm::length(glm::dvec3(accel[i]));
    double expect = std::min(p.cflAcoustic * p.h / (p.c0 + v), double(p.dtViscous));
    if (a > 0) expect = std::min(expect, p.cflForce * std::sqrt(p.h / a));
    EXPECT_NEAR(limits[i], expect, 1e-5 * expect);
  }
  // The reduction the force pass folds in for the integrator: exactly the extremes.
  const auto range = solver.stepLimits().readback<float>(2);
  EXPECT_EQ(range[0], *std::min_element(limits.begin(), limits.end()));
  EXPECT_EQ(range[1], *std::max_element(limits.begin(), limits.end()));
}

// The rebuild check against a double-precision twin on random particles: after each step the
// result holds the (min, max) of the x displacements since the build, the half-sum of the two
// largest reaches |d - (c, 0, 0)| with c = 2 m1 - m2 predicted from the two checks before
// (with RK2 plus each particle's look-ahead of half its next step), and m1 in w. The
// integrator reduces the reaches per SIMD group and sph/rebuild_decide.comp the partials,
// with the tile test after symplectic Euler and without it after RK2.
TEST_F(SphStageTest, RebuildCheckMatchesTheCpuReference) {
  for (const sim::Integrator integrator : {sim::Integrator::SymplecticEuler, sim::Integrator::Rk2Midpoint}) {
    SCOPED_TRACE(integrator == sim::Integrator::Rk2Midpoint ? "rk2_midpoint" : "symplectic_euler");
    checkRebuildAgainstReference(integrator);
  }
}

void SphStageTest::checkRebuildAgainstReference(sim::Integrator integrator) {
  const bool rk2 = integrator == sim::Integrator::Rk2Midpoint;
  auto rng = rngFor();
  sim::SphSettings s = settings();
  s.integrator = integrator;
  const Case c = makeCase(rng, s, 6, 5, 5, 0.1f);
  const auto n = static_cast<std::uint32_t>(c.pos.size());
  sim::ParticleStore store(ctx(), n);
  store.upload(c.pos, c.vel, {}, c.normals);
  sim::SphSolver solver(ctx(), store, glm::vec3(-0.05f), glm::vec3(0.12f), s);
  gpu::CommandRecorder rec(ctx());
  std::uniform_real_distribution<float> jitter(-1.0f, 1.0f);
  const float threshold = solver.rebuildThreshold();
  std::uint32_t step = 0;
  int checked = 0, tilesCompared = 0;
  for (int round = 0; round < 8; ++round) {
    const auto before = solver.rebuildCheck().readback<float>(4);
    rec.begin();
    if (step == 0) solver.recordReset(rec);
    solver.recordStep(rec, step, 0);
    rec.end();
    rec.submitAndWait();
    ++step;
    const auto pos = store.readPositions();
    const auto build = solver.grid().positionsAtBuild().readback<glm::vec4>(n);
    const auto got = solver.rebuildCheck().readback<float>(4);
    const bool rebuiltNext = got[0] == 0.0f && got[1] == 0.0f && got[3] == 0.0f && got[2] > threshold;
    // The tiles are collected where the last half-sum passed HEMO_TILE_COLLECT_FROM of the
    // threshold (and after the reset, which sets it to +inf); elsewhere the bound reads +inf.
    // (RK2 has no tile test.)
    const bool collected = !rk2 && (round == 0 || !(before[2] <= float(HEMO_TILE_COLLECT_FROM) * threshold));
    const double tileRef = collected ? tileBoundReference(solver.tileGrid(), pos, build) : INFINITY;
    const float tileGot = solver.tileCheck().readback<float>(1)[0];
    if (rk2) {
      // the tile result is not written
    } else if (collected) {
      EXPECT_NEAR(tileGot, tileRef, 1e-5 * tileRef + 1e-7) << "tile boxes' largest separation, step " << step;
      ++tilesCompared;
    } else {
      EXPECT_TRUE(std::isinf(tileGot)) << "step " << step << " did not collect the tiles";
    }
    double lo = 1e300, hi = -1e300;
    std::vector<double> reaches;
    const double cRef = round == 0 ? 0.0 : double(before[0]) + double(before[1]) - double(before[3]);
    const auto vel = store.readVelocities();
    for (std::uint32_t i = 0; i < n; ++i) {
      const glm::dvec3 d = glm::dvec3(pos[i]) - glm::dvec3(build[i]);
      lo = std::min(lo, d.x);
      hi = std::max(hi, d.x);
      double reach = glm::length(d - glm::dvec3(cRef, 0.0, 0.0));
      if (rk2) {  // the particle's next half step, at most (rigid particles: 0)
        const double speed = glm::length(glm::dvec3(vel[i]));
        reach += 0.5 * speed * std::min(double(s.maxTimeStep), double(s.cflAcoustic) * s.h() / (s.soundSpeed + speed));
      }
      reaches.push_back(reach);
    }
    // The two largest reaches' half-sum: the most two particles can have closed in, halved.
    std::partial_sort(reaches.begin(), reaches.begin() + 2, reaches.end(), std::greater<>());
    const double reach = 0.5 * (reaches[0] + reaches[1]);
    ASSERT_GT(reaches[0] - reaches[1], 1e-3 * threshold) << "the two largest must differ, or the half-sum is the largest";
    const double tol = 1e-6 * threshold + 1e-5 * reach;
    EXPECT_NEAR(got[2], reach, tol) << "half-sum of the two largest reaches, step " << step;
    // The gate opens when both tests fail: the reach test (the half-sum past half the skin)
    // and the tile test (boxes apart by more than the skin, or the reaches past the tiles).
    const bool tilesHold = !rk2 && tileRef <= 2.0 * threshold && reach <= solver.tileGrid().origin[3];
    EXPECT_EQ(rebuiltNext, reach > threshold && !tilesHold) << "step " << step << ": reach " << reach << ", tiles " << tileRef;
    if (!rebuiltNext) {
      EXPECT_NEAR(got[0], lo, 1e-6 * threshold) << "min d.x, step " << step;
      EXPECT_NEAR(got[1], hi, 1e-6 * threshold) << "max d.x, step " << step;
      EXPECT_FLOAT_EQ(got[3], round == 0 ? 0.0f : 0.5f * (before[0] + before[1])) << "previous middle";
      ++checked;
    }
    // Move every fluid particle randomly by up to 0.3 thresholds, with a common drift along x
    // that grows each round, so the prediction of c matters. Rigid boundary particles stay:
    // the solver leaves their slots out of the integrator and the check counts them at
    // displacement 0 (reach |c|), which the reference above computes from their positions.
    auto moved = pos;
    const auto kinds = store.readVelocities();
    for (std::uint32_t i = 0; i < n; ++i) {
      if (kinds[i].w != 0.0f) continue;
      moved[i] += glm::vec4(0.4f * threshold * float(round) + 0.3f * threshold * jitter(rng),
                            0.3f * threshold * jitter(rng), 0.3f * threshold * jitter(rng), 0.0f);
    }
    store.live().positions.upload(moved);
  }
  EXPECT_GE(checked, 4);
  EXPECT_GE(tilesCompared, rk2 ? 0 : 4);
}

// The tile test: the list's pairs must hold for fluid particles carried together far beyond
// the skin (the reach test alone rebuilds there), next to a rigid wall the fluid runs into. After every step, every pair within the support has to be in the list (of a fluid
// particle, or a boundary particle's list of fluid).
TEST_F(SphStageTest, ListHoldsEveryPairWithinTheSupportWhileTheGateStaysClosed) {
  auto rng = rngFor();
  sim::SphSettings s = settings();
  s.gravity = glm::vec3(0.0f);
  s.viscosity = 0.001f;
  const float dp = s.spacing, m = s.particleMass();
  std::uniform_real_distribution<float> jitter(-0.1f * dp, 0.1f * dp);
  std::normal_distribution<float> noise(0.0f, 0.05f);
  s.listLayout = sim::ListLayout::Contiguous;  // every particle's own list; clusters: ClusterListsHoldEachPairOnce
  std::vector<glm::vec4> pos, vel;
  // A rigid wall of two layers across y = 0.095 m ...
  for (int layer = 0; layer < 2; ++layer)
    for (int k = -2; k < 10; ++k)
      for (int i = -2; i < 10; ++i) {
        pos.emplace_back((i + 0.5f) * dp, 0.095f + layer * dp, (k + 0.5f) * dp, m);
        vel.emplace_back(0.0f, 0.0f, 0.0f, float(sim::ParticleKind::Boundary));
      }
  // ... and a block of fluid below it moving towards it at 1.2 m/s, turning slowly about x
  // (a fifth of the threshold a step, so the integrator collects the tiles before the reach
  // test fails).
  const glm::vec3 centre(0.04f, 0.04f, 0.04f);
  for (int k = 0; k < 8; ++k)
    for (int j = 0; j < 8; ++j)
      for (int i = 0; i < 8; ++i) {
        const glm::vec3 x = glm::vec3((i + 0.5f) * dp, (j + 0.5f) * dp, (k + 0.5f) * dp) + glm::vec3(jitter(rng), jitter(rng), jitter(rng));
        const glm::vec3 r = x - centre;
        const glm::vec3 v = glm::vec3(0.0f, 1.2f, 0.0f) + glm::cross(glm::vec3(5.0f, 0.0f, 0.0f), r) +
                            glm::vec3(noise(rng), noise(rng), noise(rng));
        pos.emplace_back(x, m);
        vel.emplace_back(v, float(sim::ParticleKind::Fluid));
      }
  const auto n = static_cast<std::uint32_t>(pos.size());
  sim::ParticleStore store(ctx(), n);
  store.upload(pos, vel);
  sim::SphSolver solver(ctx(), store, glm::vec3(-0.05f), glm::vec3(0.17f), s);
  ASSERT_GE(solver.tileGrid().count[1], 3u) << "the y axis needs tiles that are not neighbours";
  gpu::CommandRecorder rec(ctx());
  const double support = s.supportRadius(), threshold = solver.rebuildThreshold();
  const std::uint32_t capacity = s.neighbourCapacity;
  int saved = 0, wallPairs = 0;
  float lastReach = 0.0f;
  for (std::uint32_t step = 0; step < 90; ++step) {
    rec.begin();
    if (step == 0) solver.recordReset(rec);
    solver.recordStep(rec, step, 0);
    rec.end();
    rec.submitAndWait();
    ASSERT_EQ(solver.readStatus().neighbourOverflow, 0u);
    // The list the next step will use: this step's, unless the check just opened the gate.
    const auto check = solver.rebuildCheck().readback<float>(4);
    const bool rebuildsNext = check[0] == 0.0f && check[1] == 0.0f && check[3] == 0.0f && check[2] > threshold;
    const auto x = store.readPositions();
    const bool collected = step == 0 || !(lastReach <= float(HEMO_TILE_COLLECT_FROM) * float(threshold));
    lastReach = check[2];
    const double tileRef = collected ? tileBoundReference(solver.tileGrid(), x, solver.grid().positionsAtBuild().readback<glm::vec4>(n)) : INFINITY;
    const float tileGot = solver.tileCheck().readback<float>(1)[0];
    if (collected) {
      EXPECT_NEAR(tileGot, tileRef, 1e-5 * tileRef + 1e-7) << "step " << step;
    } else {
      EXPECT_TRUE(std::isinf(tileGot)) << "step " << step;
    }
    const bool tilesHold = tileRef <= 2.0 * threshold && check[2] <= solver.tileGrid().origin[3];
    EXPECT_EQ(rebuildsNext, check[2] > threshold && !tilesHold) << "step " << step;
    saved += !rebuildsNext && check[2] > threshold;
    if (rebuildsNext) continue;
    const auto kinds = store.readVelocities();
    const auto counts = solver.neighbourCounts().readback<std::uint32_t>(n);
    const auto list = solver.neighbourList().readback<std::uint32_t>(std::size_t(n) * capacity);
    const std::uint32_t entryStride = solver.params().listStride, particleStride = solver.params().listParticleStride;
    for (std::uint32_t i = 0; i < n; ++i) {
      const bool fluidI = kinds[i].w == float(sim::ParticleKind::Fluid);
      std::vector<std::uint32_t> listed;
      for (std::uint32_t k = 0; k < counts[i]; ++k) {
        listed.push_back(list[std::size_t(i) * particleStride + std::size_t(k) * entryStride] & ~sim::SphSolver::kListBoundaryBit);
      }
      std::sort(listed.begin(), listed.end());
      for (std::uint32_t j = 0; j < n; ++j) {
        const bool fluidJ = kinds[j].w == float(sim::ParticleKind::Fluid);
        if (j == i || (!fluidI && !fluidJ)) continue;
        if (glm::length(glm::dvec3(x[i]) - glm::dvec3(x[j])) >= support) continue;
        wallPairs += fluidI != fluidJ;
        ASSERT_TRUE(std::binary_search(listed.begin(), listed.end(), j))
            << "step " << step << ": slots " << i << " and " << j << " are within the support but not listed";
      }
    }
  }
  std::printf("tile test: %d of 90 steps kept the list past the reach test, %d fluid-wall pairs checked, %u rebuilds\n",
              saved, wallPairs, solver.readRebuilds());
  EXPECT_GE(saved, 5) << "the tile test kept the list where the reach test alone rebuilt it";
  EXPECT_GT(wallPairs, 0) << "the fluid reached the wall";
}

// The clusters' lists (interface/sph.h, "Clusters") against a brute-force double-precision
// search: every fluid member is named, exactly once, with exactly the particles within the
// list radius (the minimum image on periodic axes); fluid entries from the front, boundary
// entries marked, from the back where a member is within the repulsion's reach plus the skin
// (the force pass evaluates the repulsion only there) and from the front otherwise. Cases: a jittered block over a boundary plane, the same
// periodic in x and y, and random particles (some outside the grid) with a periodic x axis.
// The boundary particles' clusters (numbered after the fluid's) the same way: each member
// named once with every fluid particle within the list radius, and nothing else; and a slot
// appears at most once in a cluster's list, since the passes count every entry for every
// member. Clusters whose members sit in several rows of cells (each row's members walk their
// own cells, and the rows' walks overlap) must occur, or the grouping is not tested.
TEST_F(SphStageTest, ClusterListsHoldEachPairOnce) {
  auto rng = rngFor();
  struct Setup {
    const char* name;
    Case c;
    sim::SphSettings s;
    glm::vec3 lo, hi;
  };
  std::vector<Setup> setups;
  {
    sim::SphSettings s = settings();
    setups.push_back({"block", makeCase(rng, s, 9, 8, 7), s, glm::vec3(-0.05f), glm::vec3(0.15f)});
  }
  {
    sim::SphSettings s = settings();
    s.periodic = {true, true, false};
    const Case c = makeCase(rng, s, 9, 8, 6, 0.3f, true);
    setups.push_back({"periodic x, y", c, s, glm::vec3(0.0f, 0.0f, -0.05f), glm::vec3(0.09f, 0.08f, 0.1f)});
  }
  {
    sim::SphSettings s = settings();
    s.periodic = {true, false, false};
    s.neighbourCapacity = 1024;  // random positions crowd more than a fluid
    const float period = float(3.6 * s.listRadius());
    const Case c = randomCase(rng, s, period);
    setups.push_back({"random, periodic x, some outside the grid", c, s, glm::vec3(0.0f, -0.02f, -0.02f),
                      glm::vec3(period, 0.06f, 0.05f)});
  }
  std::size_t repeated = 0;  // entries of a slot already listed in its cluster
  std::size_t spanning = 0;  // clusters whose members sit in more than one row of cells
  std::size_t boundaryPairs = 0;
  std::size_t farBoundary = 0, nearBoundary = 0;  // fluid clusters' boundary entries by section
  std::size_t windows = 0, partialWindows = 0, moved = 0;  // the walk order's windows; clusters not in place
  std::size_t boundaryWindows = 0, movedBoundary = 0;      // the same for the boundary clusters' active list
  for (Setup& setup : setups) {
    SCOPED_TRACE(setup.name);
    setup.s.listLayout = sim::ListLayout::Clusters;
    const Stages st = runStages(setup.c, setup.s, setup.hi, setup.lo, true);
    const sim::SphSolver& solver = *st.solver;
    ASSERT_TRUE(solver.usesClusters());
    const auto n = static_cast<std::uint32_t>(setup.c.pos.size());
    const std::uint32_t fluid = st.store->fluidCount();
    const std::uint32_t clusters = (fluid + HEMO_CLUSTER_SIZE - 1) / HEMO_CLUSTER_SIZE;
    ASSERT_LT(fluid, n) << "the setup has boundary particles";
    ASSERT_TRUE(solver.usesBoundaryClusters());
    const std::uint32_t boundaryClusters = (n - fluid + HEMO_CLUSTER_SIZE - 1) / HEMO_CLUSTER_SIZE;
    const std::uint32_t all = clusters + boundaryClusters;
    const std::uint32_t cap = solver.clusterCapacity();
    const auto x = st.store->readPositions();
    const auto v = st.store->readVelocities();
    // each slot's row of cells (y, z), as the build finds it from the positions at the build
    const auto gp = solver.grid().push(n);
    const auto atBuild = solver.grid().positionsAtBuild().readback<glm::vec4>(n);
    auto row = [&](std::uint32_t i) {
      glm::ivec2 r;
      for (int a = 1; a < 3; ++a) {
        float f = std::floor((atBuild[i][a] - gp.origin[a]) * gp.invCell[a]);
        const auto dim = float(gp.dims[a]);
        if (gp.periodic[a] != 0u) f -= dim * std::floor(f / dim);
        r[a - 1] = int(std::clamp(f, 0.0f, dim - 1.0f));
      }
      return r;
    };
    const auto counts = solver.clusterCounts().readback<std::uint32_t>(all);
    const auto list = solver.clusterLists().readback<std::uint32_t>(std::size_t(all) * cap);
    // The walk orders (sph/cluster_order.comp): each window of HEMO_CLUSTER_ORDER_WINDOW items
    // (the last one shorter) sorted stably by the clusters' texels, front section first.
    // `items`: the clusters in their places before the sort; `cluster0`: the first cluster's
    // count. Returns the windows checked and adds the places whose cluster moved to `movedOut`.
    auto checkWindows = [&](const std::vector<std::uint32_t>& items, const std::vector<std::uint32_t>& got,
                            std::uint32_t cluster0, const char* what, std::size_t& movedOut) {
      auto key = [&](std::uint32_t c) {
        const std::uint32_t k = counts[cluster0 + c];
        return std::pair(((k & 0xffffu) + 3u) / 4u, ((k >> 16u) + 3u) / 4u);
      };
      std::size_t checked = 0;
      const auto count = static_cast<std::uint32_t>(items.size());
      for (std::uint32_t w = 0; w < count; w += HEMO_CLUSTER_ORDER_WINDOW) {
        const std::uint32_t end = std::min(count, w + HEMO_CLUSTER_ORDER_WINDOW);
        std::vector<std::uint32_t> expect(items.begin() + w, items.begin() + end);
        std::stable_sort(expect.begin(), expect.end(), [&](std::uint32_t a, std::uint32_t b) { return key(a) < key(b); });
        for (std::uint32_t k = w; k < end; ++k) {
          EXPECT_EQ(got[k], expect[k - w]) << what << ", place " << k;
          movedOut += got[k] != items[k];
        }
        ++checked;
      }
      return checked;
    };
    // the fluid's clusters, from grid order
    std::vector<std::uint32_t> fluidClusters(clusters);
    std::iota(fluidClusters.begin(), fluidClusters.end(), 0u);
    windows += checkWindows(fluidClusters, solver.clusterOrder().readback<std::uint32_t>(clusters), 0u, "walk order", moved);
    partialWindows += clusters % HEMO_CLUSTER_ORDER_WINDOW != 0u;
    // The boundary clusters' active list: each cluster with a fluid entry once, each window of
    // the list as appended sorted.
    const std::uint32_t active = solver.activeArgs().readback<glm::uvec4>(1)[0].w;
    const auto appended = solver.activeAppended().readback<std::uint32_t>(std::max(active, 1u));
    const auto walked = solver.activeList().readback<std::uint32_t>(std::max(active, 1u));
    std::vector<std::uint32_t> expectActive;
    for (std::uint32_t c = 0; c < boundaryClusters; ++c) {
      if ((counts[clusters + c] & 0xffffu) > 0) expectActive.push_back(c);
    }
    const std::vector<std::uint32_t> appendedActive(appended.begin(), appended.begin() + active);
    std::vector<std::uint32_t> gotActive = appendedActive;
    std::sort(gotActive.begin(), gotActive.end());
    EXPECT_EQ(gotActive, expectActive) << "the active list holds each cluster with fluid once";
    boundaryWindows += checkWindows(appendedActive, walked, clusters, "boundary walk order", movedBoundary);
    const auto status = solver.readStatus();
    EXPECT_EQ(status.neighbourOverflow, 0u);
    for (std::uint32_t slot = 0; slot < n; ++slot) {
      ASSERT_EQ(v[slot].w == float(sim::ParticleKind::Fluid), slot < fluid) << "the fluid's slots come first";
    }
    const auto& p = solver.params();
    auto distance = [&](std::uint32_t i, std::uint32_t j) {
      glm::dvec3 d = glm::dvec3(x[i]) - glm::dvec3(x[j]);
      for (int a = 0; a < 3; ++a) {
        if (p.period[a] > 0.0f) d[a] -= double(p.period[a]) * std::round(d[a] / double(p.period[a]));
      }
      return glm::length(d);
    };
    // The repulsion acts only within D of a boundary particle's plane, behind it by less than
    // dp - D, and within dp along it (common/repulsion.glsl); a pair closes in by less than
    // the skin (the list radius less the support) before the next build.
    const double normalReach = std::max(double(p.repulsionCutoff), double(p.wallSpacing) - double(p.repulsionCutoff));
    const double nearReach = std::hypot(normalReach, double(p.wallSpacing)) + (double(p.listRadius) - double(p.supportRadius));
    std::vector<std::vector<std::uint32_t>> named(n);
    for (std::uint32_t c = 0; c < all; ++c) {
      const bool boundaryMembers = c >= clusters;
      const std::uint32_t first = boundaryMembers ? fluid + (c - clusters) * HEMO_CLUSTER_SIZE : c * HEMO_CLUSTER_SIZE;
      const std::uint32_t end = boundaryMembers ? n : fluid;
      const std::uint32_t nf = counts[c] & 0xffffu, nb = counts[c] >> 16u;
      ASSERT_LE(nf + nb, cap);
      if (boundaryMembers) {
        ASSERT_EQ(nb, 0u) << "boundary cluster " << c << " lists boundary particles";
      }
      std::map<std::uint32_t, int> seen;
      for (std::uint32_t i = first + 1; i < std::min(first + HEMO_CLUSTER_SIZE, end); ++i) {
        if (row(i) != row(first)) {
          ++spanning;
          break;
        }
      }
      auto take = [&](std::uint32_t k, bool back) {
        const std::uint32_t e = list[std::size_t(c) * cap + k];
        const std::uint32_t j = e & HEMO_CLUSTER_SLOT_MASK;
        const std::uint32_t mask = (e >> HEMO_CLUSTER_MEMBER_SHIFT) & ((1u << HEMO_CLUSTER_SIZE) - 1u);
        ASSERT_LT(j, n);
        const bool boundary = j >= fluid;
        EXPECT_EQ((e & sim::SphSolver::kListBoundaryBit) != 0, boundary) << "cluster " << c << " entry " << k;
        EXPECT_NE(mask, 0u) << "an entry no member needs";
        if (!boundary) {
          EXPECT_FALSE(back) << "cluster " << c << " entry " << k << ": fluid in the boundary section";
        }
        if (seen[j]++ > 0) {
          ++repeated;
          ADD_FAILURE() << "cluster " << c << " lists slot " << j << " twice";
        }
        double nearest = 1e30;
        for (std::uint32_t m = 0; m < HEMO_CLUSTER_SIZE; ++m) {
          if (!(mask & (1u << m))) continue;
          const std::uint32_t i = first + m;
          ASSERT_LT(i, end) << "a mask names a member past its part";
          named[i].push_back(j);
          nearest = std::min(nearest, distance(i, j));
        }
        if (boundary && std::abs(nearest - nearReach) > 1e-5 * nearReach) {  // (else float rounding decides)
          EXPECT_EQ(back, nearest < nearReach) << "cluster " << c << " entry " << k << ": boundary slot " << j << " at "
                                               << nearest / nearReach << " of the repulsion's reach and skin";
          (back ? nearBoundary : farBoundary) += 1;
        }
      };
      for (std::uint32_t k = 0; k < nf; ++k) take(k, false);
      for (std::uint32_t k = cap - nb; k < cap; ++k) take(k, true);
    }
    const double radius = p.listRadius;
    std::size_t pairs = 0;
    std::uint32_t most = 0;  // neighbours of the most crowded member, itself not counted
    for (std::uint32_t i = 0; i < n; ++i) {
      auto& got = named[i];
      most = std::max(most, std::uint32_t(got.size()) - (i < fluid ? 1u : 0u));
      std::sort(got.begin(), got.end());
      EXPECT_TRUE(std::adjacent_find(got.begin(), got.end()) == got.end()) << "slot " << i << " names a neighbour twice";
      for (std::uint32_t j = 0; j < (i < fluid ? n : fluid); ++j) {  // boundary members: fluid neighbours only
        const double r = distance(i, j);
        if (std::abs(r - radius) < 1e-5 * radius) continue;  // float rounding decides
        const bool listed = std::binary_search(got.begin(), got.end(), j);
        EXPECT_EQ(listed, r < radius) << "slots " << i << " and " << j << " at " << r / radius << " list radii";
        pairs += r < radius && i < fluid;
        boundaryPairs += r < radius && i >= fluid;
      }
    }
    EXPECT_GT(pairs, 20u * fluid);
    EXPECT_EQ(status.maxNeighbours, most) << "the builds' count of the most crowded member's neighbours";
  }
  EXPECT_EQ(repeated, 0u);
  EXPECT_GT(spanning, 10u) << "too few clusters span rows of cells";
  EXPECT_GT(boundaryPairs, 1000u) << "the boundary clusters' lists were tested";
  EXPECT_GT(nearBoundary, 100u) << "boundary entries within the repulsion's reach were tested";
  EXPECT_GT(farBoundary, 100u) << "boundary entries beyond the repulsion's reach were tested";
  EXPECT_GT(windows, 4u) << "the walk order's windows";
  EXPECT_GT(partialWindows, 0u) << "a last window shorter than the others";
  EXPECT_GT(moved, 50u) << "the walk order moved clusters";
  EXPECT_GT(boundaryWindows, 2u) << "the boundary walk order's windows";
  EXPECT_GT(movedBoundary, 20u) << "the boundary walk order moved clusters";
}

}  // namespace
}  // namespace hemo::test
