#pragma once
// A whole scene's particles and wall: the vessel (if any) first, its wall particles taking
// ids 0 .. wall-1 (the spring network's points), then its fluid, the fluid blocks and the
// tanks' boundary particles.
#include "hemo/scene/aneurysm.hpp"

#include <optional>
#include <string>

namespace hemo::scene {

struct SceneBuild {
  ParticleSet particles;
  std::optional<sim::SpringNetwork> network;  // present when the scene has a vessel
  std::uint32_t wall = 0;                     // wall particles (ids 0 .. wall-1)
};

// The builder's description of the scene's vessel (a tube is an aneurysm spec without sac).
AneurysmSpec vesselSpec(const Scene& scene);
// The same for a vessel and the fluid it is filled with (spacing, particle mass).
AneurysmSpec vesselSpec(const Vessel& vessel, const sim::SphSettings& fluid);
// Throws SceneError naming the vessel's parameter if the builder rejects it.
SceneBuild buildScene(const Scene& scene);
std::uint64_t countSceneParticles(const Scene& scene);
// Fluid particles that have left the scene: outside the domain, or outside the vessel's wall
// by more than a spacing. `positions` and `velocities` as in ParticleSet (w: mass, kind).
// A particle whose position or velocity is not finite is lost, not escaped (countLost).
// Open ends with an escape distance (vessel.outlet.park_escaped_beyond_m, sim::OpenEnds): the
// escape grid's mask, a bit per cell, set where all of the cell lies farther than the distance
// outside the vessel's wall (its built geometry: scene::outsideVessel). Empty without.
std::vector<std::uint32_t> escapeMask(const Scene& scene);

std::uint32_t countEscaped(const Scene& scene, const std::vector<glm::vec4>& positions,
                           const std::vector<glm::vec4>& velocities);
// Particles of any kind whose position or velocity is not finite: the simulation has lost
// them (it stops at the end of the batch in which the first one appears).
std::uint32_t countLost(const std::vector<glm::vec4>& positions, const std::vector<glm::vec4>& velocities);

// The lumen pressure (Pa) at which the scene's wall would first fail under a pressure applied
// slowly, from the built spring layout, and how it was found: a tube or a fusiform aneurysm by
// the static response of the whole network (hemo/scene/statics.hpp); a saccular aneurysm by the
// lower of the sac's uniform-widening estimate (sacRupturePressure) and its parent tube's static
// estimate. None for scenes without a vessel, for bifurcations, for walls of more than 60,000
// points (the solve would take minutes), for unbreakable springs (an estimate above 1e15 Pa)
// or when the solve does not converge. The dynamic
// first break comes somewhat lower (0.82-0.96 of it in the tests: the wall overshoots).
struct RuptureEstimate {
  double pressure = 0.0;  // Pa
  std::string method;
};
std::optional<RuptureEstimate> ruptureEstimate(const Scene& scene);

}  // namespace hemo::scene
