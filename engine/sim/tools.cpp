#include "hemo/sim/tools.hpp"

#include "hemo/gpu/commands.hpp"
#include "hemo/gpu/pipeline_cache.hpp"
#include "interface/tool.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>

namespace hemo::sim {

namespace {
constexpr std::uint32_t kWorkgroup = 256;  // a power of two: the passes' trees halve it
static_assert((kWorkgroup & (kWorkgroup - 1)) == 0);

struct ContactPush {  // tool/contact.comp
  std::uint32_t n, idCount, tools, held, stride, clockIn;
};
struct CutPush {  // tool/cut.comp
  std::uint32_t springCount, tools, clockIn;
};
// SIMD groups of at least this many lanes (the engine's assumption for every device; a
// device reporting fewer gets that many)
constexpr std::uint32_t kMinSubgroup = 4;

bool finite(glm::vec3 v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }

void validateKeys(const std::string& name, const std::vector<ToolKey>& keys) {
  if (keys.empty()) throw std::invalid_argument(name + ": needs at least one keyframe");
  if (keys.size() > HEMO_TOOL_MAX_KEYS) {
    throw std::invalid_argument(name + ": " + std::to_string(keys.size()) + " keyframes, at most " +
                                std::to_string(HEMO_TOOL_MAX_KEYS));
  }
  for (std::size_t k = 0; k < keys.size(); ++k) {
    const ToolKey& key = keys[k];
    const std::string at = name + ": keyframe " + std::to_string(k);
    if (!std::isfinite(key.time) || key.time < 0.0) throw std::invalid_argument(at + ": time must be >= 0 (s)");
    if (k > 0 && !(key.time > keys[k - 1].time)) {
      throw std::invalid_argument(at + ": time " + std::to_string(key.time) + " s is not after the previous keyframe's " +
                                  std::to_string(keys[k - 1].time) + " s (keyframes must be in time order)");
    }
    if (!finite(key.position)) throw std::invalid_argument(at + ": position must be finite (m)");
    const glm::quat& q = key.orientation;
    const double norm = std::sqrt(double(q.w) * q.w + double(q.x) * q.x + double(q.y) * q.y + double(q.z) * q.z);
    if (!(std::abs(norm - 1.0) < 1e-3)) throw std::invalid_argument(at + ": orientation must be a unit quaternion");
    if (k > 0) {
      const glm::quat& p = keys[k - 1].orientation;
      const double c = std::abs(double(p.w) * q.w + double(p.x) * q.x + double(p.y) * q.y + double(p.z) * q.z);
      // a turn of theta between unit quaternions has |cos(theta / 2)| = c
      if (!(c > std::cos(std::numbers::pi / 4.0) + 1e-6)) {
        throw std::invalid_argument(at + ": turns 90 degrees or more from the previous keyframe (add keyframes in between)");
      }
    }
  }
}
}  // namespace

void ToolSpec::validate() const {
  const std::string n = "tool \"" + name + "\"";
  if (!(std::isfinite(radius) && radius > 0.0f)) throw std::invalid_argument(n + ": radius must be positive (m)");
  if (!(std::isfinite(length) && length >= 0.0f)) throw std::invalid_argument(n + ": length must be >= 0 (m)");
  if (!(std::isfinite(contactDistance) && contactDistance >= 0.0f)) {
    throw std::invalid_argument(n + ": contact distance must be >= 0 (m)");
  }
  if (!(std::isfinite(contactScale) && contactScale > 0.0f)) throw std::invalid_argument(n + ": contact scale must be positive");
  if (kind == ToolKind::Blade && !(length > 0.0f)) throw std::invalid_argument(n + ": a blade needs an edge (length > 0 m)");
  if (!(std::isfinite(jawWidth) && jawWidth >= 0.0f)) throw std::invalid_argument(n + ": the jaw width must be >= 0 (m)");
  if (kind != ToolKind::Grasper && jawWidth != 0.0f) throw std::invalid_argument(n + ": only a grasper has jaws (a jaw width)");
  if (!(std::isfinite(gripStiffness) && gripStiffness >= 0.0f)) {
    throw std::invalid_argument(n + ": the grip stiffness must be >= 0 (N/m)");
  }
  if (kind != ToolKind::Grasper && gripStiffness != 0.0f) throw std::invalid_argument(n + ": only a grasper grips (a grip stiffness)");
  validateKeys(n, keys);
  for (std::size_t k = 0; k < keys.size(); ++k) {
    const std::string at = n + ": keyframe " + std::to_string(k);
    if (kind != ToolKind::Blade && keys[k].cutting) throw std::invalid_argument(at + " cuts, but only a blade cuts");
    if (!(std::isfinite(keys[k].jawOpening) && keys[k].jawOpening >= 0.0f)) {
      throw std::invalid_argument(at + ": the jaw opening must be >= 0 (m)");
    }
    if (kind != ToolKind::Grasper && keys[k].jawOpening != 0.0f) {
      throw std::invalid_argument(at + " has a jaw opening, but only a grasper has jaws");
    }
  }
}

ToolContact::ToolContact(gpu::Context& context, const ParticleStore& particles, const ToolBuffers& buffers,
                         std::vector<ToolSpec> tools, float psiPerScale, float spacing, std::uint32_t maxStepsPerBatch)
    : particles_(&particles),
      tools_(std::move(tools)),
      psiPerScale_(psiPerScale),
      spacing_(spacing),
      timeStepFactor_(buffers.timeStepFactor),
      maxSteps_(std::max(maxStepsPerBatch, 1u)),
      wallPoints_(buffers.wallInfo ? buffers.wallPoints : 0u),
      stride_(0) {
  if (tools_.empty() || tools_.size() > HEMO_TOOL_MAX_TOOLS) {
    throw std::invalid_argument("tools: 1 to " + std::to_string(HEMO_TOOL_MAX_TOOLS) + " tools, got " +
                                std::to_string(tools_.size()));
  }
  for (ToolSpec& t : tools_) {
    if (t.contactDistance == 0.0f) t.contactDistance = spacing_;
    t.validate();
  }
  if (!(std::isfinite(timeStepFactor_) && timeStepFactor_ > 0.0f)) {
    throw std::invalid_argument("tools: the wall's time-step factor must be positive");
  }
  static_assert(HEMO_TOOL_MAX_TOOLS * (HEMO_TOOL_RECORD_VEC4S + HEMO_TOOL_KEY_VEC4S * HEMO_TOOL_MAX_KEYS) <=
                HEMO_TOOL_DATA_VEC4S);
  toolData_ = gpu::Buffer(context, HEMO_TOOL_DATA_VEC4S * 16, gpu::MemoryUse::Device, "tools and keyframes");
  log_ = gpu::Buffer(context, std::uint64_t(maxSteps_) * tools_.size() * sizeof(ToolSample), gpu::MemoryUse::Device,
                     "tool log");
  // (bound where the scene has no wall or no substeps: never read or written then)
  placeholder_ = gpu::Buffer(context, 16, gpu::MemoryUse::Device,
                             "tool placeholder (no wall)");
  // every wall point starts free (a resumed run restores the records from its checkpoint)
  grips_ = gpu::Buffer(context, std::max<std::uint64_t>(std::uint64_t(wallPoints_) * 16, 16), gpu::MemoryUse::Device,
                       "tool grips");
  grips_.upload(std::vector<glm::vec4>(std::max(wallPoints_, 1u), glm::vec4(0.0f)));
  upload();

  auto& cache = context.pipelines();
  contact_ = &cache.get({"tool/contact", HEMO_TOOLC_BINDING_COUNT, sizeof(ContactPush), kWorkgroup, {},
                         1u << HEMO_TOOLC_BINDING_PARAMS | 1u << HEMO_TOOLC_BINDING_TOOLS,
                         1u << HEMO_TOOLC_BINDING_POSITIONS | 1u << HEMO_TOOLC_BINDING_VELOCITIES |
                             1u << HEMO_TOOLC_BINDING_IDS | 1u << HEMO_TOOLC_BINDING_WALL_INFO});
  // One partial per SIMD group of the largest dispatch (folded into y on devices with few
  // workgroups along x), per tool; the time step's likewise.
  const std::uint64_t groups = contact_->groupsFor(std::max(particles.capacity(), 1u)).total();
  const std::uint32_t lanes = std::max(1u, std::min(kMinSubgroup, context.subgroupSize()));
  stride_ = static_cast<std::uint32_t>(groups * ((kWorkgroup + lanes - 1) / lanes));
  partials_ = gpu::Buffer(context, std::uint64_t(stride_) * tools_.size() * 2 * 16, gpu::MemoryUse::Device,
                          "tool force partials");
  dtPartials_ = gpu::Buffer(context, std::uint64_t(stride_) * 8, gpu::MemoryUse::Device, "tool time-step partials");
  partialCount_ = gpu::Buffer(context, 4, gpu::MemoryUse::Device, "tool partials written");
  const ParticleArrays& a = particles.live();
  using gpu::texelBinding;
  using namespace gpu::texel;
  contactSet_ = contact_->makeSet(
      {texelBinding(HEMO_TOOLC_BINDING_POSITIONS, &a.positions, kVec4),
       texelBinding(HEMO_TOOLC_BINDING_VELOCITIES, &a.velocities, kVec4),
       texelBinding(HEMO_TOOLC_BINDING_IDS, &a.ids, kUint),
       texelBinding(HEMO_TOOLC_BINDING_WALL_INFO, buffers.wallInfo ? buffers.wallInfo : &placeholder_, kVec4),
       {HEMO_TOOLC_BINDING_PARAMS, buffers.params},
       {HEMO_TOOLC_BINDING_TOOLS, &toolData_},
       {HEMO_TOOLC_BINDING_CLOCK, buffers.clock},
       {HEMO_TOOLC_BINDING_ACCEL, buffers.accel},
       {HEMO_TOOLC_BINDING_HELD, buffers.held ? buffers.held : &placeholder_},
       {HEMO_TOOLC_BINDING_PARTIALS, &partials_},
       {HEMO_TOOLC_BINDING_PARTIAL_COUNT, &partialCount_},
       {HEMO_TOOLC_BINDING_DT_PARTIALS, &dtPartials_},
       {HEMO_TOOLC_BINDING_DT_COUNTS, buffers.dtCounts},
       {HEMO_TOOLC_BINDING_GRIPS, &grips_}});
  const bool blade = std::any_of(tools_.begin(), tools_.end(), [](const ToolSpec& t) { return t.kind == ToolKind::Blade; });
  if (blade && buffers.springs && buffers.springCount > 0) {
    springCount_ = buffers.springCount;
    cut_ = &cache.get({"tool/cut", HEMO_TOOLCUT_BINDING_COUNT, sizeof(CutPush), kWorkgroup, {},
                       1u << HEMO_TOOLCUT_BINDING_PARAMS | 1u << HEMO_TOOLCUT_BINDING_TOOLS,
                       1u << HEMO_TOOLCUT_BINDING_POSITIONS | 1u << HEMO_TOOLCUT_BINDING_SLOT_OF_ID});
    cutSet_ = cut_->makeSet({texelBinding(HEMO_TOOLCUT_BINDING_POSITIONS, &a.positions, kVec4),
                             texelBinding(HEMO_TOOLCUT_BINDING_SLOT_OF_ID, buffers.slotOfId, kUint),
                             {HEMO_TOOLCUT_BINDING_SPRINGS, buffers.springs},
                             {HEMO_TOOLCUT_BINDING_COUNTERS, buffers.wallCounters},
                             {HEMO_TOOLCUT_BINDING_PARAMS, buffers.params},
                             {HEMO_TOOLCUT_BINDING_TOOLS, &toolData_},
                             {HEMO_TOOLCUT_BINDING_CLOCK, buffers.clock}});
  }
}

void ToolContact::recordCut(gpu::CommandRecorder& rec, std::uint32_t clockIn) {
  if (!cut_) return;
  rec.dispatch(*cut_, cutSet_, CutPush{springCount_, count(), clockIn}, cut_->groupsFor(springCount_));
}

void ToolContact::upload() {
  std::vector<glm::vec4> data(HEMO_TOOL_DATA_VEC4S, glm::vec4(0.0f));
  for (std::size_t k = 0; k < tools_.size(); ++k) {
    const ToolSpec& t = tools_[k];
    const std::uint32_t first = static_cast<std::uint32_t>(k * HEMO_TOOL_MAX_KEYS);
    const std::size_t record = HEMO_TOOL_RECORD_VEC4S * k;
    data[record] = glm::vec4(float(static_cast<std::uint32_t>(t.kind)), t.radius, t.length, t.contactDistance);
    data[record + 1] = glm::vec4(t.contactScale * psiPerScale_, float(first), float(t.keys.size()), 0.5f * t.jawWidth);
    data[record + 2] = glm::vec4(t.gripStiffness, timeStepFactor_, 0.0f, 0.0f);
    for (std::size_t j = 0; j < t.keys.size(); ++j) {
      const ToolKey& key = t.keys[j];
      const std::size_t at = HEMO_TOOL_RECORD_VEC4S * HEMO_TOOL_MAX_TOOLS + HEMO_TOOL_KEY_VEC4S * (first + j);
      data[at] = glm::vec4(float(key.time), key.position);
      const glm::quat q = glm::normalize(key.orientation);
      data[at + 1] = glm::vec4(q.x, q.y, q.z, q.w);
      data[at + 2] = glm::vec4(key.jawOpening, key.cutting ? 1.0f : 0.0f, 0.0f, 0.0f);
    }
  }
  toolData_.upload(data);
}

void ToolContact::setKeys(std::uint32_t tool, const std::vector<ToolKey>& keys) {
  if (tool >= tools_.size()) throw std::out_of_range("tool " + std::to_string(tool) + " of " + std::to_string(tools_.size()));
  validateKeys("tool \"" + tools_[tool].name + "\"", keys);
  tools_[tool].keys = keys;
  upload();
}

void ToolContact::record(gpu::CommandRecorder& rec, std::uint32_t n, std::uint32_t clockIn, bool held) {
  // At least one workgroup: invocation 0 writes the tools' own limit and the partials' counts.
  rec.dispatch(*contact_, contactSet_, ContactPush{n, wallPoints_, count(), held ? 1u : 0u, stride_, clockIn},
               contact_->groupsFor(std::max(n, 1u)));
}

std::vector<ToolSample> ToolContact::readLog(std::uint32_t steps) const {
  if (steps > maxSteps_) throw std::out_of_range("tool log: " + std::to_string(steps) + " rows of " + std::to_string(maxSteps_));
  return log_.readback<ToolSample>(std::size_t(steps) * tools_.size());
}

}  // namespace hemo::sim
