#include "hemo/sim/wall.hpp"

#include "hemo/gpu/commands.hpp"
#include "hemo/gpu/pipeline_cache.hpp"
#include "interface/wall.h"

#include <glm/vec4.hpp>

#include <algorithm>
#include <cmath>
#include <set>
#include <stdexcept>
#include <string>
#include <utility>

namespace hemo::sim {

namespace {
constexpr std::uint32_t kWorkgroup = 256;

struct ForcesPush {
  float gravity[4];
  std::uint32_t n, idCount;
  float timeStepFactor, acousticLength, c0;
  std::uint32_t first;
  std::uint32_t dtPartialBase;
  std::uint32_t groupBase;  // the workgroups of the pass's earlier dispatches (pages)
  std::uint32_t last;       // 1: the pass's last dispatch (it writes the partials' count)
  std::uint32_t substeps;   // the wall's substeps per step
  std::uint32_t wallShear;  // 1: the wall shear stress too
};
static_assert(sizeof(ForcesPush) == 60);
struct ShearPush {  // wall/shear_accumulate.comp
  std::uint32_t idCount, clockIn;
};
struct SubstepPush {  // wall/substep.comp
  std::uint32_t n, first, idCount, substeps, mode, clockIn;
  float endTime;
};

bool finiteNonNegative(float x) { return std::isfinite(x) && x >= 0.0f; }
}  // namespace

void SpringNetwork::validate() const {
  const auto n = points.size();
  if (n >= 0xffffffffull) throw std::invalid_argument("spring network: too many points");
  for (std::size_t i = 0; i < n; ++i) {
    const WallPoint& p = points[i];
    if (!(std::isfinite(p.mass) && p.mass > 0.0f)) {
      throw std::invalid_argument("wall point " + std::to_string(i) + ": mass must be positive (kg)");
    }
    const bool none = p.frameA == WallPoint::kNoFrame && p.frameB == WallPoint::kNoFrame;
    if (!none && (p.frameA >= n || p.frameB >= n || p.frameA == p.frameB || p.frameA == i || p.frameB == i)) {
      throw std::invalid_argument("wall point " + std::to_string(i) +
                                  ": its normal's frame needs two other points of the network (or none)");
    }
  }
  if (!(std::isfinite(timeStepFactor) && timeStepFactor > 0.0f && timeStepFactor <= 1.0f)) {
    throw std::invalid_argument("spring network: time-step factor must be in (0, 1]");
  }
  if (substeps < 1 || substeps > 256) throw std::invalid_argument("spring network: substeps must be in [1, 256]");
  std::set<std::pair<std::uint32_t, std::uint32_t>> seen;
  for (std::size_t k = 0; k < springs.size(); ++k) {
    const Spring& s = springs[k];
    const std::string name = "spring " + std::to_string(k) + " (" + std::to_string(s.a) + "-" + std::to_string(s.b) + ")";
    if (s.a >= n || s.b >= n) throw std::invalid_argument(name + ": particle id beyond the " + std::to_string(n) + " wall points");
    if (s.a == s.b) throw std::invalid_argument(name + ": connects a particle to itself");
    if (!seen.insert({std::min(s.a, s.b), std::max(s.a, s.b)}).second) throw std::invalid_argument(name + ": duplicate spring");
    if (!(std::isfinite(s.restLength) && s.restLength > 0.0f)) throw std::invalid_argument(name + ": rest length must be positive (m)");
    if (!finiteNonNegative(s.stiffness)) throw std::invalid_argument(name + ": stiffness must be >= 0 (N/m)");
    if (!finiteNonNegative(s.damping)) throw std::invalid_argument(name + ": damping must be >= 0 (N s/m)");
    if (!(s.maxForce >= 0.0f) || std::isnan(s.maxForce)) throw std::invalid_argument(name + ": maximum force must be >= 0 (N)");
  }
}

namespace {
struct ShadePush {
  std::uint32_t n, idCount, mode;
};
struct PressureReactionPush {  // wall/dfsph_reaction.comp
  std::uint32_t n, first, idCount;
};
}  // namespace

MassSpring::MassSpring(gpu::Context& context, const ParticleStore& particles, const FluidBuffers& fluid,
                       const SpringNetwork& network, glm::vec3 gravity, float acousticLength, float soundSpeed)
    : context_(&context),
      particles_(&particles),
      springCount_(static_cast<std::uint32_t>(network.springs.size())),
      idCount_(static_cast<std::uint32_t>(network.points.size())),
      gravity_{gravity.x, gravity.y, gravity.z, 0.0f},
      timeStepFactor_(network.timeStepFactor),
      acousticLength_(acousticLength),
      soundSpeed_(soundSpeed),
      springs_(context, std::max<std::uint64_t>(network.springs.size(), 1) * sizeof(GpuSpring), gpu::MemoryUse::Device, "springs"),
      first_(context, (std::uint64_t(network.points.size()) + 1) * 4, gpu::MemoryUse::Device, "springs of each point: first"),
      springsOf_(context, std::max<std::uint64_t>(network.springs.size() * 2, 1) * 4, gpu::MemoryUse::Device, "springs of each point"),
      wallInfo_(context, std::max<std::uint64_t>(network.points.size(), 1) * 16, gpu::MemoryUse::Device, "wall mass and anchors"),
      frames_(context, std::max<std::uint64_t>(network.points.size(), 1) * 8, gpu::MemoryUse::Device, "wall normal frames"),
      counters_(context, 16, gpu::MemoryUse::Device, "wall counters"),
      shade_(context, std::uint64_t(std::max(particles.capacity(), 1u)) * 8, gpu::MemoryUse::Device, "wall shade"),
      held_(context, std::uint64_t(std::max(particles.capacity(), 1u)) * 16, gpu::MemoryUse::Device,
            "wall force held over the step"),
      wss_(context, std::uint64_t(std::max(particles.capacity(), 1u)) * 16, gpu::MemoryUse::Device, "wall shear stress"),
      slotOfId_(fluid.slotOfId),
      clock_(fluid.clock) {
  substeps_ = network.substeps;
  network.validate();
  wss_.upload(std::vector<glm::vec4>(std::max(particles.capacity(), 1u), glm::vec4(0.0f)));  // (read before the first shear pass)
  if (idCount_ > particles.capacity()) {
    throw std::invalid_argument("spring network: " + std::to_string(idCount_) + " points but the particle store holds " +
                                std::to_string(particles.capacity()));
  }
  // Springs with canonical ends (a < b), and the CSR adjacency by particle id.
  std::vector<GpuSpring> gpuSprings;
  std::vector<std::uint32_t> count(idCount_ + 1, 0);
  for (const Spring& s : network.springs) {
    gpuSprings.push_back({std::min(s.a, s.b), std::max(s.a, s.b), s.restLength, s.stiffness, s.damping, s.maxForce, 0u, 0u});
    ++count[s.a];
    ++count[s.b];
  }
  {
    std::vector<double> stiffness(idCount_, 0.0);
    for (const Spring& sp : network.springs) stiffness[sp.a] += sp.stiffness, stiffness[sp.b] += sp.stiffness;
    for (std::uint32_t i = 0; i < idCount_; ++i) {
      if (!network.points[i].anchored && stiffness[i] > 0.0) {
        springLimit_ = std::min(springLimit_, network.timeStepFactor * std::sqrt(network.points[i].mass / stiffness[i]));
      }
    }
  }
  std::vector<std::uint32_t> first(idCount_ + 1, 0);
  for (std::uint32_t i = 0; i < idCount_; ++i) first[i + 1] = first[i] + count[i];
  std::vector<std::uint32_t> springsOf(std::max<std::size_t>(network.springs.size() * 2, 1), 0);
  std::vector<std::uint32_t> fill(first.begin(), first.end() - 1);
  for (std::uint32_t k = 0; k < springCount_; ++k) {  // ascending spring index per point: a fixed summation order
    springsOf[fill[gpuSprings[k].a]++] = k;
    springsOf[fill[gpuSprings[k].b]++] = k;
  }
  std::vector<std::uint32_t> frames(std::max<std::size_t>(idCount_, 1) * 2, WallPoint::kNoFrame);
  for (std::uint32_t i = 0; i < idCount_; ++i) {
    frames[2 * i] = network.points[i].frameA;
    frames[2 * i + 1] = network.points[i].frameB;
  }
  frames_.upload(frames);
  std::vector<glm::vec4> info(std::max<std::size_t>(idCount_, 1), glm::vec4(0.0f));
  for (std::uint32_t i = 0; i < idCount_; ++i) info[i] = glm::vec4(network.points[i].mass, network.points[i].anchored ? 1.0f : 0.0f, network.points[i].shearArea, 0.0f);
  if (!gpuSprings.empty()) springs_.upload(gpuSprings);
  builtStiffness_.reserve(gpuSprings.size());
  builtDamping_.reserve(gpuSprings.size());
  for (const GpuSpring& g : gpuSprings) builtStiffness_.push_back(g.stiffness), builtDamping_.push_back(g.damping);
  first_.upload(first);
  springsOf_.upload(springsOf);
  wallInfo_.upload(info);

  auto& cache = context.pipelines();
  // Every read-only input of the spring pass is a texel slot (gpu/pipeline.hpp, texelSlots).
  const std::uint32_t springTexels =
      1u << HEMO_SPRINGF_BINDING_POSITIONS | 1u << HEMO_SPRINGF_BINDING_VELOCITIES | 1u << HEMO_SPRINGF_BINDING_IDS |
      1u << HEMO_SPRINGF_BINDING_SLOT_OF_ID | 1u << HEMO_SPRINGF_BINDING_SPRINGS | 1u << HEMO_SPRINGF_BINDING_FIRST |
      1u << HEMO_SPRINGF_BINDING_SPRINGS_OF | 1u << HEMO_SPRINGF_BINDING_WALL_INFO | 1u << HEMO_SPRINGF_BINDING_STATE |
      1u << HEMO_SPRINGF_BINDING_NCOUNT | 1u << HEMO_SPRINGF_BINDING_NLIST | 1u << HEMO_SPRINGF_BINDING_FRAMES |
      1u << HEMO_SPRINGF_BINDING_WALL_VEL | 1u << HEMO_SPRINGF_BINDING_PAIR_POSITION | 1u << HEMO_SPRINGF_BINDING_FLUID_ACCEL |
      1u << HEMO_SPRINGF_BINDING_VISCOSITY;
  if (!fluid.viscosity) throw std::invalid_argument("the wall's reaction needs the fluid's viscosity buffer");
  // constant 2 of the spring pass: the fluid's viscosity per particle (non-Newtonian blood)
  std::vector<std::uint32_t> springSpecialization = fluid.reactionSpecialization;
  springSpecialization.at(1) = fluid.variableViscosity ? 1u : 0u;
  forces_ = &cache.get({fluid.cellWalk ? "wall/spring_forces_cells" : "wall/spring_forces", HEMO_SPRINGF_BINDING_COUNT, sizeof(ForcesPush), kWorkgroup, springSpecialization,
                        1u << HEMO_SPRINGF_BINDING_PARAMS, springTexels});
  shadeStage_ = &cache.get({"wall/point_shade", HEMO_SHADE_BINDING_COUNT, sizeof(ShadePush), kWorkgroup, {}, 1u << HEMO_SHADE_BINDING_PARAMS});
  const ParticleArrays& a = particles.live();
  using gpu::texelBinding;
  using namespace gpu::texel;
  pageSlots_ = fluid.listPageSlots;
  for (const gpu::Buffer* page : fluid.neighbourListPages) {
    forcesSets_.push_back(forces_->makeSet({texelBinding(HEMO_SPRINGF_BINDING_POSITIONS, &a.positions, kVec4),
                                            texelBinding(HEMO_SPRINGF_BINDING_VELOCITIES, &a.velocities, kVec4),
                                            texelBinding(HEMO_SPRINGF_BINDING_IDS, &a.ids, kUint),
                                            texelBinding(HEMO_SPRINGF_BINDING_SLOT_OF_ID, fluid.slotOfId, kUint),
                                            texelBinding(HEMO_SPRINGF_BINDING_SPRINGS, &springs_, kUvec4),
                                            texelBinding(HEMO_SPRINGF_BINDING_FIRST, &first_, kUint),
                                            texelBinding(HEMO_SPRINGF_BINDING_SPRINGS_OF, &springsOf_, kUint),
                                            texelBinding(HEMO_SPRINGF_BINDING_WALL_INFO, &wallInfo_, kVec4),
                                            {HEMO_SPRINGF_BINDING_ACCEL, fluid.accel},
                                            texelBinding(HEMO_SPRINGF_BINDING_FLUID_ACCEL, fluid.accel, kVec4),
                                            {HEMO_SPRINGF_BINDING_DT_LIMIT, fluid.dtLimit},
                                            {HEMO_SPRINGF_BINDING_PARAMS, fluid.params},
                                            texelBinding(HEMO_SPRINGF_BINDING_STATE, fluid.state, kVec4),
                                            texelBinding(HEMO_SPRINGF_BINDING_NCOUNT, fluid.neighbourCounts, fluid.neighbourCountsFormat),
                                            texelBinding(HEMO_SPRINGF_BINDING_NLIST, page, fluid.listReadWidth == 4u ? kUvec4 : kUint),
                                            {HEMO_SPRINGF_BINDING_NORMALS, &a.normals},
                                            texelBinding(HEMO_SPRINGF_BINDING_WALL_VEL, fluid.viscousVelocities, kVec4),
                                            {HEMO_SPRINGF_BINDING_COUNTERS, &counters_},
                                            texelBinding(HEMO_SPRINGF_BINDING_FRAMES, &frames_, kUvec2),
                                            texelBinding(HEMO_SPRINGF_BINDING_PAIR_POSITION, fluid.pairPositions, kVec4),
                                            {HEMO_SPRINGF_BINDING_SPRINGS_RW, &springs_},
                                            {HEMO_SPRINGF_BINDING_DT_PARTIALS, fluid.dtPartials},
                                            {HEMO_SPRINGF_BINDING_DT_COUNTS, fluid.dtCounts},
                                            {HEMO_SPRINGF_BINDING_HELD, &held_},
                                            {HEMO_SPRINGF_BINDING_WSS, &wss_},
                                            texelBinding(HEMO_SPRINGF_BINDING_VISCOSITY, fluid.viscosity, kFloat)}));
  }
  if (fluid.kappa) {
    if (fluid.cellWalk || fluid.neighbourListPages.size() != 1) {
      throw std::invalid_argument("the wall's share of the DFSPH pressure needs the fluid's list in one page");
    }
    pressureReaction_ = &cache.get({"wall/dfsph_reaction", HEMO_WALLP_BINDING_COUNT, sizeof(PressureReactionPush), kWorkgroup,
                                    fluid.reactionSpecialization, 1u << HEMO_WALLP_BINDING_PARAMS,
                                    1u << HEMO_WALLP_BINDING_POSITIONS | 1u << HEMO_WALLP_BINDING_VELOCITIES |
                                        1u << HEMO_WALLP_BINDING_IDS | 1u << HEMO_WALLP_BINDING_WALL_INFO |
                                        1u << HEMO_WALLP_BINDING_STATE | 1u << HEMO_WALLP_BINDING_KAPPA |
                                        1u << HEMO_WALLP_BINDING_NCOUNT | 1u << HEMO_WALLP_BINDING_NLIST});
    pressureReactionSet_ = pressureReaction_->makeSet(
        {texelBinding(HEMO_WALLP_BINDING_POSITIONS, &a.positions, kVec4),
         texelBinding(HEMO_WALLP_BINDING_VELOCITIES, &a.velocities, kVec4),
         texelBinding(HEMO_WALLP_BINDING_IDS, &a.ids, kUint),
         texelBinding(HEMO_WALLP_BINDING_WALL_INFO, &wallInfo_, kVec4),
         texelBinding(HEMO_WALLP_BINDING_STATE, fluid.state, kVec4),
         texelBinding(HEMO_WALLP_BINDING_KAPPA, fluid.kappa, kVec4),
         texelBinding(HEMO_WALLP_BINDING_NCOUNT, fluid.neighbourCounts, fluid.neighbourCountsFormat),
         texelBinding(HEMO_WALLP_BINDING_NLIST, fluid.neighbourListPages[0], fluid.listReadWidth == 4u ? kUvec4 : kUint),
         {HEMO_WALLP_BINDING_PARAMS, fluid.params},
         {HEMO_WALLP_BINDING_ACCEL, fluid.accel},
         {HEMO_WALLP_BINDING_HELD, &held_}});
  }
  if (substeps_ > 1) {
    if (!fluid.stepLimits || !fluid.clock) throw std::invalid_argument("the wall's substeps need the step's dt and clock");
    substep_ = &cache.get({"wall/substep", HEMO_SUBSTEP_BINDING_COUNT, sizeof(SubstepPush), kWorkgroup,
                           fluid.reactionSpecialization,
                           1u << HEMO_SUBSTEP_BINDING_PARAMS | 1u << HEMO_SUBSTEP_BINDING_DT | 1u << HEMO_SUBSTEP_BINDING_CLOCK,
                           1u << HEMO_SUBSTEP_BINDING_POSITIONS_IN | 1u << HEMO_SUBSTEP_BINDING_VELOCITIES_IN |
                               1u << HEMO_SUBSTEP_BINDING_IDS | 1u << HEMO_SUBSTEP_BINDING_SLOT_OF_ID |
                               1u << HEMO_SUBSTEP_BINDING_SPRINGS | 1u << HEMO_SUBSTEP_BINDING_FIRST |
                               1u << HEMO_SUBSTEP_BINDING_SPRINGS_OF | 1u << HEMO_SUBSTEP_BINDING_WALL_INFO |
                               1u << HEMO_SUBSTEP_BINDING_HELD | 1u << HEMO_SUBSTEP_BINDING_KINDS});
    scratchPositions_ = gpu::Buffer(context, std::uint64_t(std::max(particles.capacity(), 1u)) * 16, gpu::MemoryUse::Device,
                                    "wall substep positions");
    scratchVelocities_ = gpu::Buffer(context, std::uint64_t(std::max(particles.capacity(), 1u)) * 16, gpu::MemoryUse::Device,
                                     "wall substep velocities");
    auto substepSet = [&](const gpu::Buffer& readX, const gpu::Buffer& readV, const gpu::Buffer& writeX,
                          const gpu::Buffer& writeV) {
      return substep_->makeSet({{HEMO_SUBSTEP_BINDING_POSITIONS, &writeX},
                                {HEMO_SUBSTEP_BINDING_VELOCITIES, &writeV},
                                texelBinding(HEMO_SUBSTEP_BINDING_POSITIONS_IN, &readX, kVec4),
                                texelBinding(HEMO_SUBSTEP_BINDING_VELOCITIES_IN, &readV, kVec4),
                                texelBinding(HEMO_SUBSTEP_BINDING_IDS, &a.ids, kUint),
                                texelBinding(HEMO_SUBSTEP_BINDING_SLOT_OF_ID, fluid.slotOfId, kUint),
                                texelBinding(HEMO_SUBSTEP_BINDING_SPRINGS, &springs_, kUvec4),
                                texelBinding(HEMO_SUBSTEP_BINDING_FIRST, &first_, kUint),
                                texelBinding(HEMO_SUBSTEP_BINDING_SPRINGS_OF, &springsOf_, kUint),
                                texelBinding(HEMO_SUBSTEP_BINDING_WALL_INFO, &wallInfo_, kVec4),
                                {HEMO_SUBSTEP_BINDING_ACCEL, fluid.accel},
                                texelBinding(HEMO_SUBSTEP_BINDING_HELD, &held_, kVec4),
                                {HEMO_SUBSTEP_BINDING_SPRINGS_RW, &springs_},
                                {HEMO_SUBSTEP_BINDING_COUNTERS, &counters_},
                                {HEMO_SUBSTEP_BINDING_PARAMS, fluid.params},
                                {HEMO_SUBSTEP_BINDING_DT, fluid.stepLimits},
                                {HEMO_SUBSTEP_BINDING_CLOCK, fluid.clock},
                                texelBinding(HEMO_SUBSTEP_BINDING_KINDS, &a.velocities, kVec4)});
    };
    substepSet_ = substepSet(a.positions, a.velocities, a.positions, a.velocities);
    substepToScratchSet_ = substepSet(a.positions, a.velocities, scratchPositions_, scratchVelocities_);
    substepFromScratchSet_ = substepSet(scratchPositions_, scratchVelocities_, a.positions, a.velocities);
  }
  params_ = fluid.params;
  state_ = fluid.state;
  makeShadeSet();
}

void MassSpring::makeShadeSet() {
  // (before the shear's sums exist, the stress buffer stands in for them: read only in mode 2,
  // which needs them)
  const ParticleArrays& a = particles_->live();
  shadeSet_ = shadeStage_->makeSet({{HEMO_SHADE_BINDING_POSITIONS, &a.positions},
                                    {HEMO_SHADE_BINDING_VELOCITIES, &a.velocities},
                                    {HEMO_SHADE_BINDING_IDS, &a.ids},
                                    {HEMO_SHADE_BINDING_SLOT_OF_ID, slotOfId_},
                                    {HEMO_SHADE_BINDING_SPRINGS, &springs_},
                                    {HEMO_SHADE_BINDING_FIRST, &first_},
                                    {HEMO_SHADE_BINDING_SPRINGS_OF, &springsOf_},
                                    {HEMO_SHADE_BINDING_PARAMS, params_},
                                    {HEMO_SHADE_BINDING_SHADE, &shade_},
                                    {HEMO_SHADE_BINDING_WSS, &wss_},
                                    {HEMO_SHADE_BINDING_SHEAR_SUMS, shearSums_ ? shearSums_.get() : &wss_},
                                    {HEMO_SHADE_BINDING_STATE, state_}});
}

void MassSpring::recordShade(gpu::CommandRecorder& rec, std::uint32_t n, ShadeBy by) {
  const bool shear = by == ShadeBy::WallShear || by == ShadeBy::MeanWallShear || by == ShadeBy::OscillatoryShear;
  if (std::uint32_t(by) >= kShadeModes) throw std::invalid_argument("recordShade: no such shade");
  if (shear && !wallShear_) throw std::logic_error("recordShade: shading by wall shear needs setWallShear(true)");
  rec.computeToCompute();
  rec.dispatch(*shadeStage_, shadeSet_, ShadePush{n, idCount_, std::uint32_t(by)}, shadeStage_->groupsFor(std::max(n, 1u)));
  rec.computeToCompute();
}

void MassSpring::recordReset(gpu::CommandRecorder& rec) {
  rec.fill(counters_, 0);
  rec.transferToCompute();
}

void MassSpring::record(gpu::CommandRecorder& rec, std::uint32_t first, std::uint32_t n, std::uint32_t dtPartialBase) {
  // Once per page of the fluid's list (one page unless it is split), each followed by a
  // barrier; the pages' time-step partials follow one another, and the last page writes their
  // count (common/dt_fold.glsl).
  const std::uint32_t lastPage = n > 0 ? (n - 1) / pageSlots_ : 0u;
  std::uint32_t groupBase = 0;
  forEachPage(first, n, [&](std::uint32_t p, std::uint32_t lo, std::uint32_t hi) {
    const ForcesPush push{{gravity_[0], gravity_[1], gravity_[2], 0.0f}, hi, idCount_, timeStepFactor_, acousticLength_,
                          soundSpeed_, lo, dtPartialBase, groupBase, p == lastPage ? 1u : 0u, substeps_, wallShear_ ? 1u : 0u};
    const gpu::Groups groups = forces_->groupsFor(hi - lo);
    rec.dispatch(*forces_, forcesSets_[p], push, groups);
    rec.computeToCompute();
    groupBase += static_cast<std::uint32_t>(groups.total());
  });
}

void MassSpring::setWallShear(bool on) {
  wallShear_ = on;
  if (!on || shearSums_) return;
  if (!clock_) throw std::logic_error("wall shear: the wall was built without the fluid's clock");
  gpu::Context& context = *context_;
  shearSums_ = std::make_unique<gpu::Buffer>(context, (std::uint64_t(idCount_) + 1) * 16, gpu::MemoryUse::Device, "wall shear sums");
  resetShearSums();
  shearAccumulate_ = &context.pipelines().get({"wall/shear_accumulate", HEMO_SHEARACC_BINDING_COUNT, sizeof(ShearPush), kWorkgroup, {},
                                               1u << HEMO_SHEARACC_BINDING_CLOCK,
                                               1u << HEMO_SHEARACC_BINDING_IDS_SLOT | 1u << HEMO_SHEARACC_BINDING_WSS});
  using gpu::texelBinding;
  using namespace gpu::texel;
  shearSet_ = shearAccumulate_->makeSet({texelBinding(HEMO_SHEARACC_BINDING_IDS_SLOT, slotOfId_, kUint),
                                         texelBinding(HEMO_SHEARACC_BINDING_WSS, &wss_, kVec4),
                                         {HEMO_SHEARACC_BINDING_CLOCK, clock_},
                                         {HEMO_SHEARACC_BINDING_SUMS, shearSums_.get()}});
  makeShadeSet();
}

void MassSpring::recordShearSums(gpu::CommandRecorder& rec, std::uint32_t clockIn) {
  if (!wallShear_ || !shearAccumulate_) throw std::logic_error("recordShearSums: wall shear is off");
  rec.dispatch(*shearAccumulate_, shearSet_, ShearPush{idCount_, clockIn}, shearAccumulate_->groupsFor(std::max(idCount_, 1u)));
  rec.computeToCompute();
}

MassSpring::ShearSums MassSpring::readShearSums() const {
  ShearSums out;
  if (!shearSums_) {
    out.perPoint.assign(idCount_, glm::vec4(0.0f));
    return out;
  }
  out.perPoint = shearSums_->readback<glm::vec4>(std::size_t(idCount_) + 1);
  out.seconds = out.perPoint.back().x;
  out.perPoint.pop_back();
  return out;
}

void MassSpring::resetShearSums() {
  if (shearSums_) shearSums_->upload(std::vector<glm::vec4>(std::size_t(idCount_) + 1, glm::vec4(0.0f)));
}

void MassSpring::recordPressureReaction(gpu::CommandRecorder& rec, std::uint32_t first, std::uint32_t n) {
  if (!pressureReaction_) throw std::logic_error("recordPressureReaction: the wall was built without DFSPH's pressure");
  const std::uint32_t count = n > first ? n - first : 0u;
  rec.dispatch(*pressureReaction_, pressureReactionSet_, PressureReactionPush{n, first, idCount_},
               pressureReaction_->groupsFor(std::max(count, 1u)));
  rec.computeToCompute();
}

void MassSpring::recordSubsteps(gpu::CommandRecorder& rec, std::uint32_t first, std::uint32_t n, std::uint32_t clockIn,
                                float endTime) {
  if (!substep_) throw std::logic_error("recordSubsteps: the wall takes no substeps");
  const gpu::Groups groups = substep_->groupsFor(std::max(n > first ? n - first : 0u, 1u));
  // One dispatch a substep: substep k reads what substep k - 1 wrote and writes the other
  // pair, the live arrays for the last (k = N - 1) and so for every k with N - 1 - k even.
  // The first reads the live arrays (it advances each particle from its own record, so in
  // place when it writes them too).
  for (std::uint32_t k = 0; k < substeps_; ++k) {
    const bool toLive = (substeps_ - 1 - k) % 2 == 0;
    const gpu::DescriptorSet& set = k == 0 ? (toLive ? substepSet_ : substepToScratchSet_)
                                           : (toLive ? substepFromScratchSet_ : substepToScratchSet_);
    rec.dispatch(*substep_, set,
                 SubstepPush{n, first, idCount_, substeps_, k == 0 ? HEMO_SUBSTEP_MODE_ADVANCE : HEMO_SUBSTEP_MODE_STEP,
                             clockIn, endTime},
                 groups);
    rec.computeToCompute();
  }
}

std::uint32_t MassSpring::workgroups(std::uint32_t first, std::uint32_t n) const {
  std::uint64_t total = 0;
  forEachPage(first, n, [&](std::uint32_t, std::uint32_t lo, std::uint32_t hi) { total += forces_->groupsFor(hi - lo).total(); });
  return static_cast<std::uint32_t>(total);
}

std::uint32_t MassSpring::readBrokenCount() const {
  return counters_.readback<std::uint32_t>(4)[HEMO_WALL_COUNTER_BROKEN];
}

std::uint32_t MassSpring::readDetachedCount() const {
  return counters_.readback<std::uint32_t>(4)[HEMO_WALL_COUNTER_DETACHED];
}

void MassSpring::setStiffnessScale(float scale) {
  if (!(std::isfinite(scale) && scale > 0.0f)) {
    throw std::invalid_argument("wall stiffness scale must be positive and finite, got " + std::to_string(scale));
  }
  stiffnessScale_ = scale;
  if (springCount_ == 0) return;
  std::vector<GpuSpring> springs = readSprings();
  const float dampingScale = std::sqrt(scale);
  for (std::size_t k = 0; k < springs.size(); ++k) {
    springs[k].stiffness = builtStiffness_[k] * scale;
    springs[k].damping = builtDamping_[k] * dampingScale;
  }
  springs_.upload(springs);
}

std::vector<GpuSpring> MassSpring::readSprings() const {
  if (springCount_ == 0) return {};
  return springs_.readback<GpuSpring>(springCount_);
}

}  // namespace hemo::sim
