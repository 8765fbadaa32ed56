#pragma once
// A whole scene's particles and wall: the vessel (if any) first, its wall particles taking
// ids 0 .. wall-1 (the spring network's points), then its fluid, the fluid blocks and the
// tanks' boundary particles.
#include "hemo/scene/aneurysm.hpp"

#include <optional>

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
std::uint32_t countEscaped(const Scene& scene, const std::vector<glm::vec4>& positions,
                           const std::vector<glm::vec4>& velocities);

}  // namespace hemo::scene
