#pragma once
// Surgical tools on the GPU (compute_shaders/tool/, interface/tool.h): rigid bodies that the
// scene's keyframes (or the user, between batches) move, pressing on the fluid and the vessel
// wall. Per force evaluation, after the fluid's forces and the wall's springs:
//   contact .. every fluid and free wall particle within the contact distance of a tool's
//              surface gets the tool's push (added to its acceleration); the tool takes the
//              opposite force and its torque, summed per SIMD group; the particles it touched
//              and the tools' own motion bound the time step
//   reduce ... the solver's time-step reduction (one workgroup) also sums each tool's
//              partials in a fixed order into the batch's tool log (force, torque, pose per
//              step), which the host reads once per batch
// Attach tools to an SphSolver with SphSolver::attachTools. docs/physics.md, "Tools".
#include "hemo/gpu/pipeline.hpp"
#include "hemo/sim/particles.hpp"

#include <glm/gtc/quaternion.hpp>
#include <glm/vec3.hpp>
#include <glm/vec4.hpp>

#include <cstdint>
#include <string>
#include <vector>

namespace hemo::gpu {
class CommandRecorder;
}

namespace hemo::sim {

// A probe pushes; a blade is a probe whose segment, its edge, also cuts: while its keys say
// so, every spring the edge sweeps through breaks (interface/tool.h, tool/cut.comp).
// A grasper has two jaws side by side, the gap between them keyed (its jaw opening): closing
// it squeezes what lies between, a vessel clamped shut for one, and grips the wall points it
// squeezes (they follow the jaws in the jaws' plane until the jaws open again).
enum class ToolKind : std::uint32_t { Probe = 0, Blade = 1, Grasper = 2 };

// A pose of the tool at a time. The tool's own frame: the tip at the origin, the shaft along +z.
struct ToolKey {
  double time = 0.0;                                 // s
  glm::vec3 position{0.0f};                          // m: where the tip is
  glm::quat orientation{1.0f, 0.0f, 0.0f, 0.0f};     // rotation of the tool's frame (unit)
  bool cutting = false;  // a blade cuts from this key to the next
  float jawOpening = 0.0f;  // m: a grasper's gap between its jaws (linear between keys)
};

struct ToolSpec {
  std::string name;
  ToolKind kind = ToolKind::Probe;
  float radius = 0.0f;           // m: the capsule's radius (a probe's tip; each of a grasper's jaws)
  float length = 0.0f;           // m: its shaft from the tip along +z (0: a sphere); a blade's edge
  float contactDistance = 0.0f;  // m: D, the push's reach beyond the surface
  float contactScale = 0.01f;    // Psi = scale c0^2 / (2h), as the boundary repulsion's
  float jawWidth = 0.0f;         // m: a grasper's jaws are rounded plates this wide (0: capsules)
  // N/m: the spring that holds a gripped wall point to where the jaws took it (a grasper;
  // 0: its jaws squeeze but do not grip). interface/tool.h, "Grasping".
  float gripStiffness = 0.0f;
  // At least one; times strictly increasing. Before the first key the tool holds the first
  // pose, after the last the last; in between the pose is interpolated (position linearly,
  // orientation by normalised linear interpolation, which needs a turn of under 90 degrees
  // from key to key).
  std::vector<ToolKey> keys;
  // Throws std::invalid_argument naming the tool and the problem (no keys, too many, times
  // out of order, a turn of 90 degrees or more between keys, a non-unit orientation,
  // non-positive radius or contact distance, negative length, a blade without an edge, a
  // negative grip stiffness or one on a tool other than a grasper, a
  // key that cuts on a tool other than a blade, a negative jaw opening or one on a tool other
  // than a grasper, non-finite values).
  void validate() const;
};

// One tool's record of one step (interface/tool.h, the log record).
struct ToolSample {
  glm::vec4 force;        // xyz: the force on the tool (N); w: the time of the force evaluation (s)
  glm::vec4 torque;       // xyz: about the tool's position (N m)
  glm::vec4 position;     // xyz: the tip (m); w: a bound on the tool's surface speed (m/s)
  glm::vec4 orientation;  // quaternion (x, y, z, w)
};
static_assert(sizeof(ToolSample) == 64);

// The solver's buffers the contact pass reads and writes.
struct ToolBuffers {
  const gpu::Buffer* accel;
  const gpu::Buffer* params;
  const gpu::Buffer* clock;
  const gpu::Buffer* dtCounts;      // uint[3]: the tools' pass writes index 2
  const gpu::Buffer* wallInfo;      // vec4 per wall point id (mass, anchored); null without a wall
  std::uint32_t wallPoints;         // ids with a record in wallInfo
  const gpu::Buffer* held;          // the wall's held force (substeps); null without
  float timeStepFactor = 0.1f;      // the wall's C: a gripped point's step is at most C sqrt(m / k_grip)
  // For blades: the wall's springs (GpuSpring records, broken flags written), its counters, the
  // slot of each particle id and the number of springs; null / 0 without a wall.
  const gpu::Buffer* springs = nullptr;
  const gpu::Buffer* wallCounters = nullptr;
  const gpu::Buffer* slotOfId = nullptr;
  std::uint32_t springCount = 0;
};

class ToolContact {
 public:
  // `psiPerScale` is c0^2 / (2h) (m/s^2), `spacing` dp (m): a tool without a contact distance
  // gets dp. Throws std::invalid_argument for bad tools or more than HEMO_TOOL_MAX_TOOLS.
  ToolContact(gpu::Context& context, const ParticleStore& particles, const ToolBuffers& buffers,
              std::vector<ToolSpec> tools, float psiPerScale, float spacing, std::uint32_t maxStepsPerBatch);

  // The contact pass over the slots [0, n) at the time of clock record `clockIn` (no barrier
  // after it). The solver's time-step reduction (sph/dt_reduce.comp), after a barrier, reads
  // its time-step partials and sums its force partials into the log.
  void record(gpu::CommandRecorder& rec, std::uint32_t n, std::uint32_t clockIn, bool held);
  // Whether a blade can cut: the scene has one and a wall with springs.
  bool cuts() const { return cut_ != nullptr; }
  // The blades' cut (tool/cut.comp) at the time of clock record `clockIn`: every unbroken
  // spring the edge of a cutting blade swept through since the last step breaks. Before the
  // wall's spring pass (no barrier after it).
  void recordCut(gpu::CommandRecorder& rec, std::uint32_t clockIn);
  // (min, max) partials of the time step the contact pass wrote (pass 2 of the reduction).
  const gpu::Buffer& dtPartials() const { return dtPartials_; }
  // The tools buffer (interface/tool.h), the force and torque partials with their count and
  // the partials per tool, and the log (maxStepsPerBatch rows of count() ToolSample, readLog).
  const gpu::Buffer& data() const { return toolData_; }
  const gpu::Buffer& partials() const { return partials_; }
  const gpu::Buffer& partialCount() const { return partialCount_; }
  std::uint32_t partialStride() const { return stride_; }
  const gpu::Buffer& log() const { return log_; }
  // Replaces a tool's keyframes (validated as ToolSpec::validate; between batches: an upload).
  void setKeys(std::uint32_t tool, const std::vector<ToolKey>& keys);
  // The log rows [0, steps) of the last batch: steps x tools samples, row-major (a readback).
  std::vector<ToolSample> readLog(std::uint32_t steps) const;
  const std::vector<ToolSpec>& tools() const { return tools_; }
  std::uint32_t count() const { return static_cast<std::uint32_t>(tools_.size()); }
  // The grip records, one vec4 per wall point id (interface/tool.h, "Grasping"); a
  // placeholder without a wall.
  const gpu::Buffer& grips() const { return grips_; }
  gpu::Buffer& grips() { return grips_; }
  // Its buffers, for a checkpoint (the keyframes may have been changed since the scene's; the
  // grips are state).
  void checkpointBuffers(std::vector<gpu::Buffer*>& out) { out.insert(out.end(), {&toolData_, &grips_}); }

 private:
  void upload();
  const ParticleStore* particles_;
  std::vector<ToolSpec> tools_;
  float psiPerScale_, spacing_, timeStepFactor_;
  std::uint32_t maxSteps_, wallPoints_, stride_;
  gpu::Buffer toolData_, partials_, partialCount_, dtPartials_, log_, placeholder_, grips_;
  const gpu::ComputePipeline* contact_;
  const gpu::ComputePipeline* cut_ = nullptr;  // with a blade and springs only
  std::uint32_t springCount_ = 0;
  gpu::DescriptorSet contactSet_, cutSet_;
};

}  // namespace hemo::sim
