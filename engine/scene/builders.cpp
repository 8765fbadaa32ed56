#include "hemo/scene/builders.hpp"

#include "hemo/reference/sph.hpp"

#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>

namespace hemo::scene {

namespace {

glm::ivec3 cellsAlong(const Box& b, float dp) {
  glm::ivec3 n;
  for (int a = 0; a < 3; ++a) n[a] = std::max(1, int(std::lround((b.max[a] - b.min[a]) / dp)));
  return n;
}

// Calls f(lattice point, normal) for every boundary particle of the tank.
template <class F>
void forEachTankParticle(const Tank& t, float dp, F&& f) {
  const glm::ivec3 n = cellsAlong(t.box, dp);
  glm::ivec3 lo, hi;  // lattice range, walls of L layers outside the box except across periodic axes
  for (int a = 0; a < 3; ++a) {
    const int L = t.periodic[a] ? 0 : int(t.layers);
    lo[a] = -L;
    hi[a] = n[a] + L;
  }
  if (t.openTop) hi.z = n.z;
  for (int k = lo.z; k < hi.z; ++k)
    for (int j = lo.y; j < hi.y; ++j)
      for (int i = lo.x; i < hi.x; ++i) {
        const bool inside = i >= 0 && i < n.x && j >= 0 && j < n.y && k >= 0 && k < n.z;
        if (inside) continue;
        const glm::vec3 p = t.box.min + (glm::vec3(i, j, k) + 0.5f) * dp;
        const glm::vec3 q = glm::clamp(p, t.box.min, t.box.max);
        f(p, glm::normalize(q - p));
      }
}

// A body-centred block: cells of edge 2^(1/3) dp (two particles per cell, the cubic
// lattice's particles per volume), as many per axis as fit best, stretched to fill the box.
glm::ivec3 bccCells(const Box& b, float dp) { return cellsAlong(b, std::cbrt(2.0f) * dp); }

glm::vec3 bccEdges(const Box& b, float dp) { return (b.max - b.min) / glm::vec3(bccCells(b, dp)); }

// Calls f(position) for every particle of the block, in a fixed order.
template <class F>
void forEachBlockParticle(const FluidBlock& b, float dp, F&& f) {
  if (b.lattice == FluidBlock::Lattice::Cubic) {
    const glm::ivec3 n = cellsAlong(b.box, dp);
    for (int k = 0; k < n.z; ++k)
      for (int j = 0; j < n.y; ++j)
        for (int i = 0; i < n.x; ++i) f(b.box.min + (glm::vec3(i, j, k) + 0.5f) * dp);
    return;
  }
  // Corner and centre sites a quarter cell in from either side, so each layer of particles
  // (a half cell apart along every axis) sits in the middle of its half-cell slab of fluid.
  const glm::ivec3 n = bccCells(b.box, dp);
  const glm::vec3 a = bccEdges(b.box, dp);
  for (int k = 0; k < n.z; ++k)
    for (int j = 0; j < n.y; ++j)
      for (int i = 0; i < n.x; ++i) {
        f(b.box.min + (glm::vec3(i, j, k) + 0.25f) * a);
        f(b.box.min + (glm::vec3(i, j, k) + 0.75f) * a);
      }
}

// Mass per particle of a block: rho0 over the kernel sum at a particle of its (infinite)
// lattice, so the block starts at the rest density (SphSettings::particleMass for cubic).
float blockMass(const FluidBlock& b, const sim::SphSettings& sph) {
  if (b.lattice == FluidBlock::Lattice::Cubic) return sph.particleMass();
  const glm::dvec3 a(bccEdges(b.box, sph.spacing));
  const double h = sph.h();
  glm::ivec3 reach;
  for (int ax = 0; ax < 3; ++ax) reach[ax] = int(std::ceil(2.0 * h / a[ax])) + 1;
  double sum = 0.0;
  for (int k = -reach.z; k <= reach.z; ++k)
    for (int j = -reach.y; j <= reach.y; ++j)
      for (int i = -reach.x; i <= reach.x; ++i) {
        const glm::dvec3 corner = glm::dvec3(i, j, k) * a;
        sum += reference::kernelW(glm::length(corner), h);
        sum += reference::kernelW(glm::length(corner + 0.5 * a), h);
      }
  return float(double(sph.restDensity) / sum);
}

}  // namespace

std::uint64_t countParticles(const Scene& s) {
  std::uint64_t count = 0;
  for (const auto& b : s.blocks) {
    const bool bcc = b.lattice == FluidBlock::Lattice::BodyCentred;
    const glm::ivec3 n = bcc ? bccCells(b.box, s.sph.spacing) : cellsAlong(b.box, s.sph.spacing);
    count += std::uint64_t(n.x) * n.y * n.z * (bcc ? 2u : 1u);
  }
  for (const auto& t : s.tanks) {
    const glm::ivec3 n = cellsAlong(t.box, s.sph.spacing);
    std::uint64_t outer = 1;
    for (int a = 0; a < 3; ++a) {
      const std::uint64_t walls = t.periodic[a] ? 0 : (a == 2 && t.openTop ? 1 : 2);
      outer *= std::uint64_t(n[a]) + walls * t.layers;
    }
    count += outer - std::uint64_t(n.x) * n.y * n.z;
  }
  return count;
}

ParticleSet buildParticles(const Scene& s) {
  ParticleSet set;
  const float dp = s.sph.spacing;
  const float mass = s.sph.particleMass();
  for (const auto& b : s.blocks) {
    const float blockM = blockMass(b, s.sph);
    forEachBlockParticle(b, dp, [&](const glm::vec3& p) {
      set.positions.emplace_back(p, blockM);
      set.velocities.emplace_back(b.velocity, float(sim::ParticleKind::Fluid));
      set.normals.emplace_back(0.0f);
    });
  }
  set.fluid = set.size();
  for (const auto& t : s.tanks) {
    forEachTankParticle(t, dp, [&](const glm::vec3& p, const glm::vec3& normal) {
      set.positions.emplace_back(p, mass);
      set.velocities.emplace_back(0.0f, 0.0f, 0.0f, float(sim::ParticleKind::Boundary));
      set.normals.emplace_back(normal, 0.0f);
    });
  }
  set.boundary = set.size() - set.fluid;
  set.ids.resize(set.size());
  for (std::uint32_t i = 0; i < set.size(); ++i) set.ids[i] = i;
  return set;
}

Scene withSlabThickness(Scene s, int axis, int spacings) {
  if (axis < 0 || axis > 2 || !s.sph.periodic[axis]) {
    throw SceneError(s.name + ": a slab thickness needs a periodic axis (axis " + std::to_string(axis) + " is not)");
  }
  const std::string name(1, "xyz"[axis]);
  const float lo = s.domain.min[axis], hi = s.domain.max[axis], slack = 1e-6f * s.sph.spacing;
  const float top = lo + float(spacings) * s.sph.spacing;
  for (auto& b : s.blocks) {
    if (std::abs(b.box.min[axis] - lo) > slack || std::abs(b.box.max[axis] - hi) > slack) {
      throw SceneError(s.name + ": a fluid block does not span the periodic axis " + name);
    }
    b.box.max[axis] = top;
  }
  for (auto& t : s.tanks) t.box.max[axis] = top;  // the loader made tanks span periodic axes
  s.domain.max[axis] = top;
  checkPeriodicAxes(s, s.name + " with a slab of " + std::to_string(spacings) + " spacings", axis);
  return s;
}

}  // namespace hemo::scene
