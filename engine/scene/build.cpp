#include "hemo/scene/build.hpp"

#include "hemo/scene/bifurcation.hpp"
#include "hemo/scene/fusiform.hpp"
#include "hemo/scene/mesh_vessel.hpp"
#include "hemo/scene/statics.hpp"

#include "interface/sph.h"

#include <cmath>
#include <stdexcept>

namespace hemo::scene {

AneurysmSpec vesselSpec(const Scene& s) {
  if (!s.vessel) throw SceneError(s.name + ": the scene has no vessel");
  return vesselSpec(*s.vessel, s.sph);
}

AneurysmSpec vesselSpec(const Vessel& v, const sim::SphSettings& fluid) {
  AneurysmSpec a;
  TubeSpec& t = a.tube;
  t.x0 = v.start.x;
  t.length = v.length;
  t.centreYZ = {v.start.y, v.start.z};
  t.radius = v.radius;
  t.spacing = fluid.spacing;
  t.layers = v.layers;
  t.pointMass = v.pointMass;
  t.stiffness = v.stiffness;
  t.damping = v.damping;
  t.maxForce = v.maxForce;
  t.periodic = v.periodic;
  t.anchorEnds = v.anchorEnds;
  t.fluidMass = fluid.particleMass();
  a.mesh = v.mesh;
  a.openEnds = v.inflow && v.inflow->open;
  for (const MeshRegion& r : v.meshRegions) a.regions.push_back({glm::dvec3(r.centre), double(r.radius), r.stiffnessScale, r.strengthScale});
  if (v.shape == Vessel::Shape::SaccularAneurysm) {
    a.sacRadius = v.sacRadius;
    a.neckWidth = v.neckWidth;
  }
  if (v.shape == Vessel::Shape::FusiformAneurysm) {
    a.bulgeRadius = v.bulgeRadius;
    a.bulgeLength = v.bulgeLength;
  }
  if (v.shape == Vessel::Shape::Bifurcation) {
    a.branchAngle = v.branchAngle;
    a.branchLength = v.branchLength;
  }
  if (v.shape == Vessel::Shape::SaccularAneurysm || v.shape == Vessel::Shape::FusiformAneurysm) {
    a.sacStiffnessScale = v.sacStiffnessScale;
    a.sacStrengthScale = v.sacStrengthScale;
  }
  return a;
}

namespace {
// Open ends: the free fluid slots (vessel.outlet.reserve_particles, or twice the inlet buffer's
// fluid particles and half the fluid) for the particles `set` holds; 0 without open ends.
// `vessel`: the particles of the vessel alone (its wall and its fluid).
std::uint32_t reserveFor(const Scene& s, const ParticleSet& set, std::uint32_t vessel) {
  if (!s.vessel || !s.vessel->inflow || !s.vessel->inflow->open) return 0;
  if (s.vessel->reserveParticles != 0) return s.vessel->reserveParticles;
  const sim::Inflow& in = *s.vessel->inflow;
  std::uint32_t buffer = 0, fluid = 0;
  for (std::size_t i = 0; i < vessel && i < set.positions.size(); ++i) {
    if (set.velocities[i].w != float(sim::ParticleKind::Fluid)) continue;
    ++fluid;
    buffer += in.open->inlet.inBuffer(glm::dvec3(set.positions[i])) ? 1u : 0u;
  }
  return 2 * buffer + fluid / 2;
}

// The scene's particles without the free slots; `vessel`: how many come first from the vessel.
SceneBuild buildWithoutReserve(const Scene& s, std::uint32_t& vessel);
}  // namespace

SceneBuild buildScene(const Scene& s) {
  std::uint32_t vessel = 0;
  SceneBuild out = buildWithoutReserve(s, vessel);
  ParticleSet& set = out.particles;
  // Open ends: the free fluid slots, parked (interface/sph.h, HEMO_KIND_PARKED), after all else.
  const std::uint32_t reserve = reserveFor(s, set, vessel);
  for (std::uint32_t k = 0; k < reserve; ++k) set.add(s.vessel->inflow->open->parking, s.sph.particleMass(), float(HEMO_KIND_PARKED));
  set.parked = reserve;
  set.numberIds();
  return out;
}

namespace {
SceneBuild buildWithoutReserve(const Scene& s, std::uint32_t& vessel) {
  SceneBuild out;
  ParticleSet& set = out.particles;
  if (s.vessel) {
    const AneurysmSpec spec = vesselSpec(s);
    try {
      if (s.vessel->shape == Vessel::Shape::Mesh) {
        MeshVesselBuild b = buildMeshVessel(spec);
        set = std::move(b.particles);
        out.network = std::move(b.network);
        out.wall = b.wall;
      } else if (s.vessel->shape == Vessel::Shape::SaccularAneurysm) {
        AneurysmBuild b = buildSaccularAneurysm(spec);
        set = std::move(b.particles);
        out.network = std::move(b.network);
        out.wall = b.wall;
      } else if (s.vessel->shape == Vessel::Shape::FusiformAneurysm) {
        FusiformBuild b = buildFusiformAneurysm(spec);
        set = std::move(b.particles);
        out.network = std::move(b.network);
        out.wall = b.wall;
      } else if (s.vessel->shape == Vessel::Shape::Bifurcation) {
        BifurcationBuild b = buildBifurcation(spec);
        set = std::move(b.particles);
        out.network = std::move(b.network);
        out.wall = b.wall;
      } else {
        TubeBuild b = buildTube(spec.tube);
        set = std::move(b.particles);
        out.network = std::move(b.network);
        out.wall = b.wall;
      }
      // Each layer holds one point per dp^2 of the lumen: a point carries the wall shear of
      // dp^2 / layers of it.
      const float shearArea = s.sph.spacing * s.sph.spacing / float(s.vessel->layers);
      for (std::uint32_t i = 0; i < out.wall; ++i) out.network->points[i].shearArea = shearArea;
      out.network->timeStepFactor = s.vessel->timeStepFactor;
      out.network->substeps = s.vessel->substeps;
    } catch (const std::invalid_argument& e) {
      throw SceneError(s.name + ": vessel: " + e.what());
    }
  }
  vessel = set.size();
  const ParticleSet rest = buildParticles(s);
  // buildParticles gives fluid then boundary; append both after the vessel.
  for (std::uint32_t i = 0; i < rest.size(); ++i) {
    set.positions.push_back(rest.positions[i]);
    set.velocities.push_back(rest.velocities[i]);
    set.normals.push_back(rest.normals[i]);
  }
  set.fluid += rest.fluid;
  set.boundary += rest.boundary;
  return out;
}
}  // namespace

std::uint64_t countSceneParticles(const Scene& s) {
  if (!s.vessel) return countParticles(s);
  // A vessel has thousands to hundreds of thousands of particles: building it is the
  // simplest exact count (its free slots counted, not made).
  Scene vesselOnly = s;
  vesselOnly.blocks.clear();
  vesselOnly.tanks.clear();
  std::uint32_t vessel = 0;
  const ParticleSet set = buildWithoutReserve(vesselOnly, vessel).particles;
  return countParticles(s) + set.size() + reserveFor(s, set, vessel);
}

namespace {
// Position and velocity finite, component by component (a sum could overflow).
bool finiteState(const glm::vec4& position, const glm::vec4& velocity) {
  for (int a = 0; a < 3; ++a) {
    if (!std::isfinite(position[a]) || !std::isfinite(velocity[a])) return false;
  }
  return true;
}
}  // namespace

std::uint32_t countEscaped(const Scene& s, const std::vector<glm::vec4>& positions, const std::vector<glm::vec4>& velocities) {
  const std::optional<AneurysmSpec> vessel = s.vessel ? std::optional(vesselSpec(s)) : std::nullopt;
  std::uint32_t escaped = 0;
  for (std::size_t i = 0; i < positions.size(); ++i) {
    if (velocities[i].w != float(sim::ParticleKind::Fluid)) continue;
    const glm::vec3 p(positions[i]);
    if (!finiteState(positions[i], velocities[i])) continue;  // lost (countLost)
    bool out = vessel && outsideVessel(*vessel, p, s.sph.spacing);
    for (int a = 0; a < 3; ++a) out = out || !(p[a] >= s.domain.min[a] && p[a] <= s.domain.max[a]);
    escaped += out;
  }
  return escaped;
}

std::vector<std::uint32_t> escapeMask(const Scene& s) {
  if (!s.vessel || !s.vessel->inflow || !s.vessel->inflow->open || !(s.vessel->inflow->open->parkBeyond > 0.0f)) return {};
  const sim::OpenEnds& o = *s.vessel->inflow->open;
  const AneurysmSpec spec = vesselSpec(s);
  const sim::EscapeGrid& g = o.escape;
  // (all of a cell: its centre that far and half its diagonal more)
  const float margin = o.parkBeyond + 0.5f * std::sqrt(3.0f) * g.cell;
  std::vector<std::uint32_t> words(g.words(), 0u);
  const std::size_t cells = std::size_t(g.dims.x) * g.dims.y * g.dims.z;
  for (std::size_t k = 0; k < cells; ++k) {
    if (outsideVessel(spec, g.centre(k), margin)) words[k / 32] |= 1u << (k % 32);
  }
  return words;
}

std::uint32_t countLost(const std::vector<glm::vec4>& positions, const std::vector<glm::vec4>& velocities) {
  std::uint32_t lost = 0;
  for (std::size_t i = 0; i < positions.size() && i < velocities.size(); ++i) {
    lost += !finiteState(positions[i], velocities[i]);
  }
  return lost;
}

namespace {
std::optional<RuptureEstimate> ruptureEstimateOf(const Scene& s) {
  if (!s.vessel || s.vessel->shape == Vessel::Shape::Bifurcation || s.vessel->shape == Vessel::Shape::Mesh) return std::nullopt;
  constexpr std::uint32_t kMaxPoints = 60000;
  const AneurysmSpec spec = vesselSpec(s);
  auto staticOf = [&](const ParticleSet& set, const sim::SpringNetwork& net, std::uint32_t wall, const AneurysmSpec& a) {
    return staticResponse(net, set.positions, a.tube.periodic ? double(a.tube.length) : 0.0,
                          lumenLoads(a, set.positions, set.normals, wall))
        .rupturePressure;
  };
  try {
    if (s.vessel->shape == Vessel::Shape::SaccularAneurysm) {
      const AneurysmBuild b = buildSaccularAneurysm(spec);
      if (b.wall > kMaxPoints) return std::nullopt;
      const TubeBuild tube = buildTube(spec.tube);
      const double sac = sacRupturePressure(b), parent = staticOf(tube.particles, tube.network, tube.wall, AneurysmSpec{spec.tube});
      return sac <= parent ? RuptureEstimate{sac, "the sac widening uniformly"} : RuptureEstimate{parent, "static, the parent tube"};
    }
    if (s.vessel->shape == Vessel::Shape::FusiformAneurysm) {
      const FusiformBuild b = buildFusiformAneurysm(spec);
      if (b.wall > kMaxPoints) return std::nullopt;
      return RuptureEstimate{staticOf(b.particles, b.network, b.wall, spec), "static, the whole wall"};
    }
    const TubeBuild b = buildTube(spec.tube);
    if (b.wall > kMaxPoints) return std::nullopt;
    return RuptureEstimate{staticOf(b.particles, b.network, b.wall, spec), "static, the whole wall"};
  } catch (const std::invalid_argument&) {
    return std::nullopt;  // no spring stretches, or the solve did not converge
  }
}
}  // namespace

std::optional<RuptureEstimate> ruptureEstimate(const Scene& s) {
  const std::optional<RuptureEstimate> e = ruptureEstimateOf(s);
  // Springs left at their default strength (1e30 N) do not break at any pressure that means anything.
  if (e && !(e->pressure < 1e15)) return std::nullopt;
  return e;
}

}  // namespace hemo::scene
