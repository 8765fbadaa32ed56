#pragma once
// Vessel wall as a mass-spring network on the GPU (compute_shaders/wall/). Wall particles
// (kind HEMO_KIND_WALL) are boundary particles for the fluid and mass points of the springs.
// Per force evaluation, one pass (wall/spring_forces.comp):
//   rupture ...... springs whose tension exceeds their maximum force break, for good (both
//                  ends compute the same tension; end a sets the flag)
//   spring forces  each wall particle gathers its unbroken springs (CSR by particle id, no
//                  atomics; the two ends get exactly opposite forces) and the reaction of
//                  every force the fluid felt from it (gathered over its fluid neighbours),
//                  divides by its mass, adds gravity (anchored particles: zero), and writes
//                  its time-step limit
// Under DFSPH a second pass (wall/dfsph_reaction.comp), after the density solve, adds the
// reaction of the pressure the solve gave the fluid through the wall.
// The SPH integrator then moves wall particles like fluid particles. Attach a network to an
// SphSolver with SphSolver::attachWall.
#include "hemo/gpu/pipeline.hpp"
#include "hemo/sim/list_pages.hpp"
#include "hemo/sim/particles.hpp"

#include <glm/vec3.hpp>

#include <cstdint>
#include <memory>
#include <vector>

namespace hemo::gpu {
class CommandRecorder;
}

namespace hemo::sim {

struct Spring {
  std::uint32_t a = 0, b = 0;  // particle ids of the two ends
  float restLength = 0.0f;     // m
  float stiffness = 0.0f;      // N/m
  float damping = 0.0f;        // N s/m, along the spring
  float maxForce = 3.0e38f;    // N: a tension above this breaks the spring
};

struct WallPoint {
  static constexpr std::uint32_t kNoFrame = 0xffffffffu;
  float mass = 0.0f;      // kg
  bool anchored = false;  // fixed in place (vessel ends)
  // The normal follows the deformed wall: n = normalize((x_A - x) x (x_B - x)) with frame
  // points A and B (ids, ordered so that n points into the fluid); kNoFrame keeps the
  // particle's normal as it is.
  std::uint32_t frameA = kNoFrame, frameB = kNoFrame;
  // The lumen area whose wall shear the point carries (m^2): dp^2 over the wall's layers
  // (each layer holds one point per dp^2 of the lumen). 0: no wall shear.
  float shearArea = 0.0f;
};

struct SpringNetwork {
  std::vector<WallPoint> points;  // indexed by particle id; ids of other particles may be listed
                                  // too (unused: only wall-kind particles are moved)
  std::vector<Spring> springs;
  float timeStepFactor = 0.1f;    // dt <= factor sqrt(m / sum k) per particle (per substep)
  // Substeps of the wall per fluid step (1: none). With N > 1 the wall takes N substeps of
  // dt / N, the fluid's force on it held for the step and its springs (and rupture) evaluated
  // at each (wall/substep.comp), so its springs limit the step to N factor sqrt(m / sum k).
  // Symplectic Euler only.
  std::uint32_t substeps = 1;
  // Throws std::invalid_argument naming the spring or point (ids out of range, a spring from a
  // particle to itself, a duplicate, non-positive rest length or mass, negative stiffness,
  // damping or maximum force, non-finite values, a frame with missing, repeated or
  // out-of-range points).
  void validate() const;
};

// Mirror of the GLSL Spring record (interface/wall.h).
struct GpuSpring {
  std::uint32_t a, b;
  float restLength, stiffness, damping, maxForce;
  std::uint32_t broken, pad;
};
static_assert(sizeof(GpuSpring) == 32);

// The SPH solver's buffers the wall stages read (and accel / dtLimit, which they write for
// wall particles).
struct FluidBuffers {
  const gpu::Buffer* slotOfId;
  const gpu::Buffer* accel;
  const gpu::Buffer* dtLimit;
  const gpu::Buffer* params;
  const gpu::Buffer* state;
  const gpu::Buffer* neighbourCounts;
  VkFormat neighbourCountsFormat;  // its texel format (walking cells: the positions at build, as RGBA32UI)
  // The fluid's neighbour list in pages of listPageSlots slots (SphSolver::listPages): the
  // reaction pass runs once per page over the wall slots in it.
  std::vector<const gpu::Buffer*> neighbourListPages;
  std::uint32_t listPageSlots;
  const gpu::Buffer* viscousVelocities;  // a wall particle's entry: the no-slip velocity the fluid saw
  const gpu::Buffer* pairPositions;      // (x, V p) per slot (interface/sph.h, the pair data)
  std::uint32_t listReadWidth;           // list entries per texel read (SphSolver::listReadWidth)
  // The time step's reduction's first level (common/dt_fold.glsl): the partials, after the
  // SPH force pass's, and how many each pass wrote.
  const gpu::Buffer* dtPartials;
  const gpu::Buffer* dtCounts;
  std::vector<std::uint32_t> reactionSpecialization;  // of the spring pass (SphSolver::pairSpecialization)
  bool cellWalk;  // the fluid keeps no list: the spring pass's variant that walks cells (interface/sph.h)
  // DFSPH's stiffness and pressure per slot (interface/sph.h, HEMO_DFSPH_BINDING_KAPPA), for
  // the wall's share of the solve's pressure; null under WCSPH.
  const gpu::Buffer* kappa = nullptr;
  // The wall's substeps read the step's dt as the integrator does: the time step's reduction
  // (vec2) and the clock's two records.
  const gpu::Buffer* stepLimits = nullptr;
  const gpu::Buffer* clock = nullptr;
  // Each fluid slot's viscosity (float), read by the reaction when the blood is non-Newtonian
  // (interface/sph.h, "Viscosity"); bound either way.
  const gpu::Buffer* viscosity = nullptr;
  bool variableViscosity = false;
};

class MassSpring {
 public:
  // Gravity (m/s^2), acoustic length C_a h (m) and c0 (m/s) come from the SPH parameters.
  MassSpring(gpu::Context& context, const ParticleStore& particles, const FluidBuffers& fluid,
             const SpringNetwork& network, glm::vec3 gravity, float acousticLength, float soundSpeed);

  void recordReset(gpu::CommandRecorder& rec);  // counters to zero (flags stay)
  // Rupture, then spring forces for the slots [first, n) (after the SPH force pass, whose
  // accelerations of wall particles this replaces). Slots before `first` must hold no wall
  // particle (SphSolver::nonFluidStart). The pass's SIMD groups write the time step's partials
  // from index dtPartialBase (past the force pass's) on (common/dt_fold.glsl).
  void record(gpu::CommandRecorder& rec, std::uint32_t first, std::uint32_t n, std::uint32_t dtPartialBase);
  // DFSPH (FluidBuffers::kappa set): after the density solve, the reaction of the pressure the
  // solve gave the fluid through the wall particles in [first, n), added to their
  // accelerations (wall/dfsph_reaction.comp; the list in one page). Ends with a barrier.
  void recordPressureReaction(gpu::CommandRecorder& rec, std::uint32_t first, std::uint32_t n);
  bool takesPressureReaction() const { return pressureReaction_ != nullptr; }
  // With substeps() > 1: after the step's dt is known (and the wall's forces, DFSPH's share
  // included, are in), the wall's substeps for the slots [first, n) to the end of the step
  // (wall/substep.comp): substeps() dispatches, each followed by a barrier. `clockIn`
  // and `endTime` as the integrator's, which then leaves the wall particles where they are.
  void recordSubsteps(gpu::CommandRecorder& rec, std::uint32_t first, std::uint32_t n, std::uint32_t clockIn,
                      float endTime);
  std::uint32_t substeps() const { return substeps_; }
  float timeStepFactor() const { return timeStepFactor_; }
  // The springs' own explicit limit on a (sub)step as built, time_step_factor sqrt(m / sum k),
  // the smallest over the free points with springs (s; 3e38 without any); the step's limit is
  // substeps() times this.
  double springTimeStepLimit() const { return springLimit_; }
  // vec4 per slot, for wall slots: (what the fluid and gravity give the particle for the step,
  // as an acceleration, 0), as the last force evaluation left it (interface/wall.h,
  // HEMO_SPRINGF_BINDING_HELD).
  const gpu::Buffer& held() const { return held_; }
  // The workgroups record(first, n, ...) dispatches.
  std::uint32_t workgroups(std::uint32_t first, std::uint32_t n) const;

  std::uint32_t springCount() const { return springCount_; }
  // vec4 per point id below pointCount(): (mass kg, anchored 0/1, shear area m^2, 0).
  const gpu::Buffer& pointInfo() const { return wallInfo_; }
  std::uint32_t pointCount() const { return idCount_; }
  std::uint32_t readBrokenCount() const;             // since the last reset (a readback)
  // Wall particles detached since the last reset: all their springs broken, so their SPH mass
  // is set to zero (by the integrator, at the end of that step) and the fluid no longer sees
  // them (a readback).
  std::uint32_t readDetachedCount() const;
  std::vector<GpuSpring> readSprings() const;        // with their broken flags (a readback)
  // The normal frames, two ids per point id (frame A, frame B; WallPoint::kNoFrame without).
  std::vector<std::uint32_t> readFrames() const { return frames_.readback<std::uint32_t>(std::size_t(idCount_) * 2); }
  // Every spring's stiffness as built times `scale` (> 0, finite) and its damping times
  // sqrt(scale), which keeps each spring's damping ratio; rest lengths, maximum forces and
  // broken flags stay (a softer wall stretches further before it tears). Between batches: a
  // readback and an upload. The step's spring limit follows on the GPU (it reads the live
  // stiffness); the substeps stay as built. Throws std::invalid_argument for a bad scale.
  void setStiffnessScale(float scale);
  float stiffnessScale() const { return stiffnessScale_; }
  const gpu::Buffer& counters() const { return counters_; }  // uint[4] (interface/wall.h)
  // Per slot of the first n: vec2(largest strain of the particle's unbroken springs, fraction
  // of its springs broken) for wall particles, 0 for others (wall/point_shade.comp), into
  // shade(); what the renderer colours the wall by. The first component is instead, with
  // ShadeBy::WallShear, the particle's wall shear stress (Pa), with MeanWallShear its time
  // average (Pa), with OscillatoryShear its oscillatory shear index (0 to 1/2; these three
  // need setWallShear(true)), with Pressure its pressure (Pa), with BrokenFraction the fraction
  // of its springs broken.
  enum class ShadeBy : std::uint32_t { Strain = 0, WallShear = 1, MeanWallShear = 2, OscillatoryShear = 3, Pressure = 4, BrokenFraction = 5 };
  static constexpr std::uint32_t kShadeModes = 6;
  void recordShade(gpu::CommandRecorder& rec, std::uint32_t n, ShadeBy by = ShadeBy::Strain);
  const gpu::Buffer& shade() const { return shade_; }
  const gpu::Buffer& springs() const { return springs_; }  // GpuSpring records, broken flags live
  // Wall shear stress: with it on, the force pass also writes each wall particle's share of
  // the wall shear stress (the tangential viscous force the fluid exerts on it over its
  // WallPoint::shearArea; wall/spring_forces.comp) into wallShearStress(), vec4 per slot (tau
  // in Pa, 1 where fluid wets the particle), and recordShearSums adds each step's into the time
  // sums behind the maps (wall/shear_accumulate.comp).
  void setWallShear(bool on);
  bool wallShear() const { return wallShear_; }
  const gpu::Buffer& wallShearStress() const { return wss_; }
  // After a step (clockIn: the clock record holding it): its stress times its dt into the sums.
  void recordShearSums(gpu::CommandRecorder& rec, std::uint32_t clockIn);
  // The sums so far, per point id: (sum tau dt (Pa s), sum |tau| dt (Pa s)), and the time
  // summed (s). A readback; zeros before setWallShear(true).
  struct ShearSums {
    std::vector<glm::vec4> perPoint;
    double seconds = 0.0;
  };
  ShearSums readShearSums() const;
  void resetShearSums();
  // Its buffers, for a checkpoint (hemo/io/checkpoint.hpp).
  void checkpointBuffers(std::vector<gpu::Buffer*>& out) {
    out.insert(out.end(), {&springs_, &first_, &springsOf_, &wallInfo_, &frames_, &counters_, &shade_});
  }

 private:
  gpu::Context* context_;
  const ParticleStore* particles_;
  std::uint32_t springCount_;
  std::uint32_t idCount_;
  float gravity_[4];
  float timeStepFactor_, acousticLength_, soundSpeed_;
  std::uint32_t substeps_ = 1;
  double springLimit_ = 3.0e38;
  float stiffnessScale_ = 1.0f;
  std::vector<float> builtStiffness_, builtDamping_;  // as built (setStiffnessScale)
  gpu::Buffer springs_, first_, springsOf_, wallInfo_, frames_, counters_, shade_;
  gpu::Buffer held_;  // vec4 per slot: what the fluid and gravity give a wall particle for the step
  gpu::Buffer wss_;   // vec4 per slot: the wall shear stress (with wallShear_)
  bool wallShear_ = false;
  const gpu::Buffer* slotOfId_ = nullptr;
  const gpu::Buffer* clock_ = nullptr;
  std::unique_ptr<gpu::Buffer> shearSums_;  // vec4 per id and one more (setWallShear(true))
  const gpu::ComputePipeline* shearAccumulate_ = nullptr;
  gpu::DescriptorSet shearSet_;
  const gpu::Buffer* params_ = nullptr;
  const gpu::Buffer* state_ = nullptr;  // the fluid's state per slot (the shade's pressure)
  void makeShadeSet();
  const gpu::ComputePipeline* forces_;
  const gpu::ComputePipeline* shadeStage_;
  const gpu::ComputePipeline* pressureReaction_ = nullptr;  // DFSPH only
  const gpu::ComputePipeline* substep_ = nullptr;           // substeps > 1 only
  // The substeps' sets: in place (the live arrays), live to scratch, scratch to live; the
  // scratch pair of positions and velocities (substeps > 1 only)
  gpu::DescriptorSet substepSet_, substepToScratchSet_, substepFromScratchSet_;
  gpu::Buffer scratchPositions_, scratchVelocities_;
  std::vector<gpu::DescriptorSet> forcesSets_;  // one per page of the fluid's list
  gpu::DescriptorSet shadeSet_, pressureReactionSet_;
  std::uint32_t pageSlots_ = 0;
  template <class Fn>
  void forEachPage(std::uint32_t begin, std::uint32_t end, Fn fn) const {
    forEachListPage(pageSlots_, static_cast<std::uint32_t>(forcesSets_.size()), begin, end, fn);
  }
};

}  // namespace hemo::sim
