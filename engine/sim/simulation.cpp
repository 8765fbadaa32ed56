#include "hemo/sim/simulation.hpp"

#include "hemo/io/checkpoint.hpp"
#include "hemo/io/hash.hpp"
#include "hemo/sim/wall_surface.hpp"
#include "interface/sph.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <sstream>

namespace hemo::sim {

namespace {

// DFSPH's recorded regions per solve (Simulation::run): the first batch's, and the fewest a
// batch records. Solves mostly take 0-3 corrections; each region recorded but not needed costs
// two empty dispatches and their barriers, a batch run again costs the whole batch.
constexpr std::uint32_t kFirstSolveDepth = 8;
constexpr std::uint32_t kMinSolveDepth = 4;

// What the physics of a run depends on, as built: a checkpoint of another scene (or another
// version of this one) does not match it.
std::uint64_t fingerprintOf(const scene::Scene& scene, const scene::SceneBuild& build) {
  io::Hash64 h;
  const scene::ParticleSet& set = build.particles;
  auto addVectors = [&](const auto& v) {
    h.addValue(std::uint64_t(v.size()));
    h.add(v.data(), v.size() * sizeof v[0]);
  };
  addVectors(set.positions);
  addVectors(set.velocities);
  addVectors(set.normals);
  addVectors(set.ids);
  h.addValue(set.fluid);
  h.addValue(set.boundary);
  const SphParams params = makeParams(scene.sph);
  h.add(&params, sizeof params);
  for (int a = 0; a < 3; ++a) {
    h.addValue(scene.domain.min[a]);
    h.addValue(scene.domain.max[a]);
    h.addValue(std::uint32_t(scene.sph.periodic[a] ? 1 : 0));
  }
  h.addValue(std::uint32_t(scene.sph.integrator));
  h.addValue(std::uint32_t(scene.sph.densityMethod));
  h.addValue(std::uint32_t(scene.sph.neighbourSearch));
  h.addValue(std::uint32_t(scene.sph.listLayout));
  h.addValue(std::uint32_t(scene.sph.pressureSolver));
  h.addValue(scene.sph.solverTolerance);
  h.addValue(scene.sph.solverMaxIterations);
  if (build.network) {
    const SpringNetwork& net = *build.network;
    h.addValue(net.timeStepFactor);
    h.addValue(net.substeps);
    h.addValue(std::uint64_t(net.springs.size()));
    for (const Spring& s : net.springs) {
      h.addValue(s.a);
      h.addValue(s.b);
      h.addValue(s.restLength);
      h.addValue(s.stiffness);
      h.addValue(s.damping);
      h.addValue(s.maxForce);
    }
    h.addValue(std::uint64_t(net.points.size()));
    for (const WallPoint& p : net.points) {
      h.addValue(p.mass);
      h.addValue(std::uint32_t(p.anchored ? 1 : 0));
      h.addValue(p.frameA);
      h.addValue(p.frameB);
    }
  }
  if (scene.vessel && scene.vessel->inflow) {
    const InflowParams inflow =
        makeInflowParams(*scene.vessel->inflow, scene.sph.restDensity, scene.sph.particleMass());
    h.add(&inflow, sizeof inflow);
  }
  // the tools and their paths (a checkpoint carries the keyframes it ran with)
  h.addValue(std::uint64_t(scene.tools.size()));
  for (const ToolSpec& t : scene.tools) {
    h.addValue(std::uint32_t(t.kind));
    h.addValue(t.radius);
    h.addValue(t.length);
    h.addValue(t.contactDistance);
    h.addValue(t.contactScale);
    h.addValue(t.jawWidth);
    h.addValue(std::uint64_t(t.keys.size()));
    for (const ToolKey& k : t.keys) {
      h.addValue(k.time);
      for (int a = 0; a < 3; ++a) h.addValue(k.position[a]);
      for (int a = 0; a < 4; ++a) h.addValue(k.orientation[a]);
      h.addValue(std::uint32_t(k.cutting ? 1 : 0));
      h.addValue(k.jawOpening);
    }
  }
  return h.value();
}

}  // namespace

Simulation::Simulation(gpu::Context& context, const scene::Scene& scene) : context_(&context), scene_(scene) {
  // Before building anything: slots are 32-bit indices, with a bit of list entries to spare.
  // (The neighbour list splits into pages where one buffer would pass a binding limit, and a
  // buffer the device's memory cannot hold is refused as it is made: gpu::OutOfDeviceMemory.)
  const std::uint64_t count = scene::countSceneParticles(scene);
  if (count > 0x7fffffffull) {
    throw scene::SceneError(scene.name + ": particles.spacing_m: " + std::to_string(scene.sph.spacing) + " m gives " +
                            std::to_string(count) + " particles, more than hemo's 32-bit slot indices allow");
  }
  const scene::SceneBuild build = scene::buildScene(scene);
  const scene::ParticleSet& set = build.particles;
  if (set.fluid == 0) throw scene::SceneError(scene.name + ": fluid.blocks: the scene holds no fluid particles");
  fluid_ = set.fluid;
  fingerprint_ = fingerprintOf(scene, build);
  boundary_ = set.boundary;
  wall_ = build.wall;
  springs_ = build.network ? static_cast<std::uint32_t>(build.network->springs.size()) : 0;
  store_ = std::make_unique<ParticleStore>(context, set.size());
  store_->upload(set.positions, set.velocities, set.ids, set.normals);
  solver_ = std::make_unique<SphSolver>(context, *store_, scene.domain.min, scene.domain.max, scene.sph,
                                        scene.stepsPerBatch);
  solver_->grid().setUploadedSlots(set.ids);
  if (build.network) solver_->attachWall(*build.network);  // a scene without walls runs no wall stage
  if (build.network) {  // the builders' normals of the wall points, for enableWallSurface
    wallNormals_.resize(build.network->points.size());
    for (std::size_t id = 0; id < wallNormals_.size() && id < set.normals.size(); ++id) {
      wallNormals_[id] = glm::vec3(set.normals[id]);
    }
  }
  if (scene.vessel && scene.vessel->inflow) {
    inflow_ = *scene.vessel->inflow;
    solver_->setInflow(*inflow_);
    if (inflow_->open && inflow_->open->parkBeyond > 0.0f) solver_->setEscapeMask(scene::escapeMask(scene));
  }
  if (!scene.tools.empty()) {  // (after the wall: the tools push its free points)
    try {
      solver_->attachTools(scene.tools);
    } catch (const std::invalid_argument& e) {
      throw scene::SceneError(scene.name + ": tools: " + e.what());
    }
  }
  minStep_ = scene.minTimeStep > 0.0 ? scene.minTimeStep : 1.0e-4 * designTimeStep();
  {  // the batch reports (recordReport), each part 16-byte aligned
    const std::uint64_t rows = std::max(scene.stepsPerBatch, 1u);
    const std::uint64_t tools = solver_->tools() ? solver_->tools()->count() : 0u;
    report_.clock = 0;
    report_.status = 32;
    report_.stepLog = report_.status + (HEMO_STATUS_COUNT * 4 + 15) / 16 * 16;
    report_.toolLog = report_.stepLog + (rows * 8 + 15) / 16 * 16;
    report_.bytes = report_.toolLog + rows * tools * sizeof(ToolSample);
    for (gpu::Buffer& b : reports_) b = gpu::Buffer(context, report_.bytes, gpu::MemoryUse::Readback, "batch report");
  }
  recorder_ = std::make_unique<gpu::CommandRecorder>(context);
  recorder_->begin();
  solver_->recordReset(*recorder_);
  recorder_->end();
  recorder_->submitAndWait();
}

void Simulation::setInflowSpeed(float metresPerSecond) {
  if (!inflow_) throw std::logic_error("the scene has no inflow zone (vessel.inflow)");
  if (!std::isfinite(metresPerSecond)) throw std::invalid_argument("inflow speed must be finite (m/s)");
  Inflow changed = *inflow_;
  changed.meanSpeed = metresPerSecond;
  solver_->setInflow(changed);
  inflow_ = changed;
}

void Simulation::setWallStiffnessScale(float scale) {
  if (!solver_->wall()) throw std::logic_error("the scene has no vessel wall");
  solver_->wall()->setStiffnessScale(scale);
}

const gpu::Buffer& Simulation::enableWallSurface() {
  if (wallTriangles_) return *wallTriangles_;
  const MassSpring* wall = solver_->wall();
  if (!wall || wall->springCount() == 0) throw std::logic_error("the scene has no vessel wall with springs");
  const Snapshot state = snapshot();
  const std::vector<std::uint32_t> triangles =
      wallSurfaceTriangles(wall->readSprings(), wall->readFrames(), state.positions, solver_->grid().spec().period,
                           wallNormals_);
  wallTriangleCount_ = static_cast<std::uint32_t>(triangles.size() / kWallTriangleWords);
  wallTriangles_.emplace(*context_, std::max<std::size_t>(triangles.size(), 1) * 4, gpu::MemoryUse::Device,
                         "wall surface triangles");
  if (!triangles.empty()) wallTriangles_->upload(triangles);
  return *wallTriangles_;
}

double Simulation::time() const { return solver_->readClock().time; }

Progress Simulation::progressOf(const RunOptions& options, std::uint64_t firstStep, double time, double endTime,
                                std::chrono::steady_clock::time_point start) const {
  Progress p;
  p.steps = steps_;
  p.firstStep = firstStep;
  p.time = time;
  p.endTime = options.steps ? 0.0 : endTime;
  p.targetSteps = options.steps ? firstStep + *options.steps : 0;
  p.wallSeconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return p;
}

RunResult Simulation::run(const RunOptions& options) {
  lastDelivery_ = std::chrono::steady_clock::now();
  if (options.pipelined && !solver_->solvesPressure() && !stats_ && !wallShear_ && options.outputEvery == 0) return runPipelined(options);
  const auto start = std::chrono::steady_clock::now();
  const double endTime = options.steps ? 3.0e38 : options.until.value_or(scene_.endTime);
  const std::uint64_t targetSteps = options.steps.value_or(~0ull);
  const std::uint64_t firstStep = steps_;
  SphClock clock = solver_->readClock();
  auto progress = [&]() { return progressOf(options, firstStep, clock.time, endTime, start); };
  while (steps_ - firstStep < targetSteps && (options.steps || clock.time < endTime)) {
    std::uint64_t batch = scene_.stepsPerBatch;
    if (options.steps) batch = std::min<std::uint64_t>(batch, firstStep + *options.steps - steps_);
    if (options.outputEvery) batch = std::min<std::uint64_t>(batch, options.outputEvery - steps_ % options.outputEvery);
    if (!options.steps && clock.lastDt > 0.0f && std::isfinite(clock.lastDt)) {
      // Steps past the end time change nothing but still run every pass: near the end, a
      // batch of about the steps left at the last step's dt (10% and two more, as dt may
      // shrink; if it falls short, the next batch is smaller still).
      const double left = std::ceil((endTime - clock.time) / double(clock.lastDt));
      if (left < double(batch)) batch = std::min<std::uint64_t>(batch, std::uint64_t(left * 1.1) + 2);
    }
    const std::uint64_t before = clock.steps;
    // DFSPH records its solves' iterations to a depth below the cap where it can (RunOptions::
    // recordedSolveIterations): a batch in which some solve needed more runs again from a
    // copy of its starting state, recorded to the cap, so that every result is the cap's.
    const bool solves = solver_->solvesPressure();
    const std::uint32_t cap = solver_->settings().solverMaxIterations;
    if (solves) {
      if (solveDepth_ == 0) solveDepth_ = std::min(cap, kFirstSolveDepth);
      solver_->setRecordedIterations(options.recordedSolveIterations.value_or(solveDepth_));
    }
    std::uint32_t statsRows = 0;
    const auto submitted = std::chrono::steady_clock::now();
    const SphSolver::SolveDepth depth = submitSteps([&] {
      statsRows = 0;
      for (std::uint64_t k = 0; k < batch; ++k) {
        const std::uint64_t dispatches = recorder_->dispatchCount(), barriers = recorder_->barrierCount();
        solver_->recordStep(*recorder_, static_cast<std::uint32_t>(steps_ + k), static_cast<std::uint32_t>(k),
                            static_cast<float>(endTime));
        recordedDispatches_ += recorder_->dispatchCount() - dispatches;
        recordedBarriers_ += recorder_->barrierCount() - barriers;
        if (stats_ && (steps_ + k) % statsEvery_ == 0) stats_->record(*recorder_, statsRows++);
        if (wallShear_) solver_->wall()->recordShearSums(*recorder_, solver_->clockParity());
      }
      if (solves) recordedSolveRegions_ += 2 * std::uint64_t(solver_->recordedIterations()) * batch;
      recordReport(*recorder_, reportSlot_, static_cast<std::uint32_t>(batch));
    });
    // The next batch records half as much again as this one's solves took at most, and two
    // more: a batch's most changes slowly from one batch to the next.
    if (solves) {
      solveDepth_ = std::clamp(depth.maxIterations + depth.maxIterations / 2 + 2, std::min(cap, kMinSolveDepth), cap);
    }
    recordedSteps_ += batch;
    const std::uint64_t done = takeReport(options, reportSlot_, solver_->clockParity(), batch, clock, endTime, submitted);
    reportSlot_ ^= 1u;
    if (statsRows > 0 && options.onStepStats) {
      std::vector<StepStatsRow> rows;
      std::uint32_t last = static_cast<std::uint32_t>(before);
      for (const StepStatsRow& r : stats_->read(statsRows)) {
        if (r.steps > last) rows.push_back(r), last = r.steps;  // steps after the end time changed nothing
      }
      options.onStepStats(rows);
    }
    // Steps after the end time change nothing and are not counted by the GPU clock.
    steps_ += done;
    if (options.onBatch) options.onBatch(progress());
    if (options.outputEvery && steps_ % options.outputEvery == 0 && options.onOutput) options.onOutput(progress());
    if (done < batch) break;  // the end time was reached inside this batch
  }
  RunResult r;
  r.steps = steps_ - firstStep;
  r.simTime = clock.time;
  r.wallSeconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return r;
}

std::uint64_t Simulation::takeReport(const RunOptions& options, std::uint32_t slot, std::uint32_t parity,
                                     std::uint64_t batch, SphClock& clock, double endTime,
                                     std::chrono::steady_clock::time_point submitted) {
  // the batch's outcome from its report (no readback submission)
  const gpu::Buffer& report = reports_[slot];
  const std::uint64_t before = clock.steps;
  {
    std::uint32_t words[HEMO_STATUS_COUNT];
    report.readbackBytes(words, sizeof words, report_.status);
    std::byte records[32];
    report.readbackBytes(records, sizeof records, report_.clock);
    clock = SphSolver::clockFrom(records, parity);
    checkStatus(steps_, SphSolver::statusFrom(words));
  }
  if (clock.steps - before == batch) checkStep(clock, steps_, endTime);
  if (options.onToolLog && solver_->tools() && clock.steps > before) {
    // the steps that advanced the clock (later ones of the batch changed nothing)
    const auto steps = static_cast<std::uint32_t>(clock.steps - before);
    const std::uint32_t tools = solver_->tools()->count();
    const auto samples = report.readback<ToolSample>(std::size_t(steps) * tools, report_.toolLog);
    const auto log = report.readback<glm::vec2>(steps, report_.stepLog);
    std::vector<ToolLogRow> rows;
    rows.reserve(samples.size());
    for (std::uint32_t k = 0; k < steps; ++k) {
      for (std::uint32_t t = 0; t < tools; ++t) rows.push_back({steps_ + k, log[k].y, t, samples[std::size_t(k) * tools + t]});
    }
    const auto now = std::chrono::steady_clock::now();
    const double latency = std::chrono::duration<double>(now - submitted).count();
    ++feedback_.batches;
    feedback_.samples += steps;
    feedback_.seconds += std::chrono::duration<double>(now - lastDelivery_).count();
    lastDelivery_ = now;
    feedback_.latencySeconds += latency;
    feedback_.maxLatency = std::max(feedback_.maxLatency, latency);
    options.onToolLog(rows);
  }
  return clock.steps - before;
}

RunResult Simulation::runPipelined(const RunOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  const double endTime = options.steps ? 3.0e38 : options.until.value_or(scene_.endTime);
  const std::uint64_t firstStep = steps_;
  const std::uint64_t lastStep = options.steps ? firstStep + *options.steps : ~0ull;
  SphClock clock = solver_->readClock();
  if (!recorder2_) recorder2_ = std::make_unique<gpu::CommandRecorder>(*context_);
  struct InFlight {
    gpu::CommandRecorder* recorder;
    std::uint32_t slot;
    std::uint32_t parity;  // the clock's, after the batch's steps
    std::uint64_t batch;
    std::chrono::steady_clock::time_point submitted;
  };
  std::vector<InFlight> inFlight;  // oldest first, at most two
  std::uint64_t recordedUpTo = steps_;  // the step index the next recorded batch starts at
  bool ended = false;
  gpu::CommandRecorder* nextRecorder = recorder_.get();
  // The next batch's size: full, or the steps left to the target, or near the end time about
  // the steps left at the last known dt beyond those already in flight (0: none to submit).
  auto nextBatch = [&]() -> std::uint64_t {
    if (ended || recordedUpTo >= lastStep) return 0;
    std::uint64_t batch = std::min<std::uint64_t>(scene_.stepsPerBatch, lastStep - recordedUpTo);
    if (!options.steps) {
      if (!(clock.time < endTime)) return 0;
      if (clock.lastDt > 0.0f && std::isfinite(clock.lastDt)) {
        const double left = std::ceil((endTime - clock.time) / double(clock.lastDt)) - double(recordedUpTo - steps_);
        if (left <= 0.0) return 0;
        if (left < double(batch)) batch = std::min<std::uint64_t>(batch, std::uint64_t(left * 1.1) + 2);
      }
    }
    return batch;
  };
  auto submit = [&](std::uint64_t batch) {
    gpu::CommandRecorder& rec = *nextRecorder;
    nextRecorder = nextRecorder == recorder_.get() ? recorder2_.get() : recorder_.get();
    rec.begin();  // (its previous batch, two back, has been read)
    for (std::uint64_t k = 0; k < batch; ++k) {
      const std::uint64_t dispatches = rec.dispatchCount(), barriers = rec.barrierCount();
      solver_->recordStep(rec, static_cast<std::uint32_t>(recordedUpTo + k), static_cast<std::uint32_t>(k),
                          static_cast<float>(endTime));
      recordedDispatches_ += rec.dispatchCount() - dispatches;
      recordedBarriers_ += rec.barrierCount() - barriers;
    }
    recordReport(rec, reportSlot_, static_cast<std::uint32_t>(batch));
    rec.end();
    rec.submit();
    inFlight.push_back({&rec, reportSlot_, solver_->clockParity(), batch, std::chrono::steady_clock::now()});
    reportSlot_ ^= 1u;
    recordedSteps_ += batch;
    recordedUpTo += batch;
  };
  auto progress = [&]() { return progressOf(options, firstStep, clock.time, endTime, start); };
  try {
    for (;;) {
      while (inFlight.size() < 2) {
        const std::uint64_t batch = nextBatch();
        if (batch == 0) break;
        submit(batch);
      }
      if (inFlight.empty()) break;
      const InFlight oldest = inFlight.front();
      inFlight.erase(inFlight.begin());
      oldest.recorder->wait();
      const std::uint64_t done =
          takeReport(options, oldest.slot, oldest.parity, oldest.batch, clock, endTime, oldest.submitted);
      steps_ += done;
      if (options.onBatch) options.onBatch(progress());
      if (done < oldest.batch) ended = true;  // the end time was reached inside it
    }
  } catch (...) {
    for (const InFlight& f : inFlight) f.recorder->wait();  // nothing may run past the throw
    throw;
  }
  RunResult r;
  r.steps = steps_ - firstStep;
  r.simTime = clock.time;
  r.wallSeconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return r;
}

SphSolver::SolveDepth Simulation::submitSteps(const std::function<void()>& record) {
  const bool solves = solver_->solvesPressure();
  const std::uint32_t cap = solver_->settings().solverMaxIterations;
  const std::vector<std::uint32_t> hostAtStart = solver_->hostState();
  bool again = false;
  for (;;) {
    if (solves && solver_->recordedIterations() < cap && !canSaveState()) solver_->setRecordedIterations(cap);
    const bool speculative = solves && solver_->recordedIterations() < cap;
    recorder_->begin();
    if (again) recordRestoreState(*recorder_);
    if (speculative) recordSaveState(*recorder_);
    if (solves) solver_->recordSolveDepthReset(*recorder_);
    record();
    recorder_->end();
    recorder_->submitAndWait();
    const SphSolver::SolveDepth depth = solves ? solver_->readSolveDepth() : SphSolver::SolveDepth{};
    if (!speculative || depth.deeper == 0) return depth;
    // Some solve was left open after the last recorded region: back to the start, to the cap.
    ++redoneBatches_;
    again = true;
    solver_->restoreHostState(hostAtStart);
    solver_->setRecordedIterations(cap);
  }
}

bool Simulation::canSaveState() {
  if (saveRefused_) return false;
  const std::vector<gpu::Buffer*> state = checkpointBuffers();
  if (saved_.size() == state.size()) return true;
  saved_.clear();
  saved_.reserve(state.size());
  try {
    for (const gpu::Buffer* b : state) saved_.emplace_back(*context_, b->size(), gpu::MemoryUse::Device, b->name() + " (batch start)");
  } catch (const gpu::OutOfDeviceMemory&) {
    // (refused before anything was allocated for the buffer that did not fit)
    saved_.clear();
    saveRefused_ = true;
  }
  return !saveRefused_;
}

void Simulation::recordSaveState(gpu::CommandRecorder& rec) {
  const std::vector<gpu::Buffer*> state = checkpointBuffers();
  if (!canSaveState()) throw std::logic_error("Simulation: no room to save the state");
  rec.computeToTransfer();
  rec.transferToTransfer();
  for (std::size_t i = 0; i < state.size(); ++i) rec.copy(*state[i], saved_[i], state[i]->size());
  rec.transferToTransfer();
  rec.transferToCompute();
}

void Simulation::recordRestoreState(gpu::CommandRecorder& rec) {
  const std::vector<gpu::Buffer*> state = checkpointBuffers();
  if (saved_.size() != state.size()) throw std::logic_error("Simulation: no saved state to restore");
  rec.computeToTransfer();
  rec.transferToTransfer();
  for (std::size_t i = 0; i < state.size(); ++i) rec.copy(saved_[i], *state[i], state[i]->size());
  rec.transferToTransfer();
  rec.transferToCompute();
}

double Simulation::designTimeStep() const {
  const SphParams& p = solver_->params();
  const double speed = double(scene_.expectedMaxSpeed) + (solver_->solvesPressure() ? 0.0 : double(p.c0));
  double dt = std::min(double(p.dtMax), double(p.dtViscous));
  if (speed > 0.0) dt = std::min(dt, double(p.cflAcoustic) * p.h / speed);
  if (const MassSpring* wall = solver_->wall()) dt = std::min(dt, wall->springTimeStepLimit() * wall->substeps());
  return dt;
}

void Simulation::checkStep(const SphClock& clock, std::uint64_t batchFirstStep, double endTime) {
  // (the step that lands on the end time may be as short as it likes)
  if (!(clock.lastDt < minStep_) || clock.time >= static_cast<float>(endTime)) return;
  // The first step of the batch below the limit, from the step log.
  const auto log = solver_->stepLog().readback<glm::vec2>(scene_.stepsPerBatch);
  std::uint64_t bad = batchFirstStep + scene_.stepsPerBatch - 1;
  glm::vec2 at(clock.time, clock.lastDt);
  for (std::size_t k = 0; k < log.size(); ++k) {
    if (log[k].y < minStep_) {
      bad = batchFirstStep + k;
      at = log[k];
      break;
    }
  }
  std::ostringstream msg;
  msg << "the time step collapsed to " << at.y << " s at step " << bad << " (t = " << at.x << " s), below time.min_dt_s = "
      << minStep_ << " s";
  if (scene_.minTimeStep <= 0.0) msg << " (1e-4 of the scene's own step, " << designTimeStep() << " s)";
  msg << ": a particle's speed or acceleration ran away, and the run would not reach its end (lower time.cfl_acoustic / "
         "time.max_dt_s, or check the forces)";
  throw SimulationError(msg.str());
}

void Simulation::recordReport(gpu::CommandRecorder& rec, std::uint32_t slot, std::uint32_t steps) {
  const gpu::Buffer& report = reports_[slot];
  rec.computeToTransfer();
  rec.copy(solver_->clockBuffer(), report, 32, 0, report_.clock);
  rec.copy(solver_->statusBuffer(), report, HEMO_STATUS_COUNT * 4, 0, report_.status);
  rec.copy(solver_->stepLog(), report, std::uint64_t(steps) * 8, 0, report_.stepLog);
  if (const ToolContact* tools = solver_->tools()) {
    rec.copy(tools->log(), report, std::uint64_t(steps) * tools->count() * sizeof(ToolSample), 0, report_.toolLog);
  }
  rec.computeToHost();
}

void Simulation::checkStatus(std::uint64_t batchFirstStep) { checkStatus(batchFirstStep, solver_->readStatus()); }

void Simulation::checkStatus(std::uint64_t batchFirstStep, const SphStatus& status) {
  if (status.neighbourOverflow > 0) {
    std::ostringstream msg;
    msg << "a particle had " << status.maxNeighbours << " neighbours, more than particles.neighbour_capacity = "
        << scene_.sph.neighbourCapacity << " (in the batch from step " << batchFirstStep << ", t = " << time()
        << " s): the fluid is compressed far beyond its rest density, or the capacity is too small";
    throw SimulationError(msg.str());
  }
  if (status.openShortfall > 0) {
    std::ostringstream msg;
    msg << "the open ends ran out of free fluid slots (in the batch from step " << batchFirstStep << ", t = " << time()
        << " s): particles that entered the lumen found no slot for their images in the buffers (" << status.openShortfall
        << " times, counted at each refill); raise vessel.outlet.reserve_particles, or let blood that leaves the vessel "
        << "free its slot nearer the wall than the domain's faces (vessel.outlet.park_escaped_beyond_m)";
    throw SimulationError(msg.str());
  }
  if (status.nonFinite == 0) return;
  // Find where: the step from the status, its time from the step log, the particle from the state.
  const auto log = solver_->stepLog().readback<glm::vec2>(scene_.stepsPerBatch);
  const std::uint64_t bad = status.firstBadStep;
  const double t = bad >= batchFirstStep && bad - batchFirstStep < log.size() ? log[bad - batchFirstStep].x : time();
  std::ostringstream msg;
  msg << "the simulation became non-finite at step " << bad << " (t = " << t << " s): " << status.nonFinite
      << " particle updates produced NaN/Inf";
  if (status.badInputId != 0xffffffffu) {
    msg << "; particle id " << status.badInputId << " was the first with a non-finite state";
  } else if (status.badForceId != 0xffffffffu) {
    msg << "; the forces on particle id " << status.badForceId << " were the first to turn non-finite";
  }
  msg << " (increase the resolution, lower time.cfl_acoustic / time.max_dt_s, or check the forces)";
  throw SimulationError(msg.str());
}

std::vector<std::pair<std::string, double>> Simulation::profileStep(int repeats, bool rebuild) {
  std::vector<std::pair<std::string, double>> result;
  if (!context_->timestampsSupported()) return result;
  gpu::TimestampQueries ts(*context_, 32);
  std::vector<std::vector<std::pair<std::string, double>>> runs;
  // DFSPH: each step recorded to the depth the last run chose, and run again when a solve
  // needed more (submitSteps), as run() does: a profiled step is a step like any other. The
  // timings are the run's that counted.
  const std::uint32_t depth = solver_->recordedIterations();
  for (int r = 0; r < repeats; ++r) {
    submitSteps([&] {
      ts.reset(*recorder_);
      if (rebuild) solver_->recordRebuildRequest(*recorder_);
      ts.mark(*recorder_, "start");
      solver_->recordStep(*recorder_, static_cast<std::uint32_t>(steps_), 0, 3.0e38f, &ts);
    });
    if (solver_->solvesPressure()) solver_->setRecordedIterations(depth);
    checkStatus(steps_);
    ++steps_;
    runs.push_back(ts.stageMs());
  }
  for (std::size_t k = 0; k < runs.front().size(); ++k) {
    std::vector<double> ms;
    for (const auto& run : runs) ms.push_back(run[k].second);
    std::sort(ms.begin(), ms.end());
    result.emplace_back(runs.front()[k].first, ms[ms.size() / 2]);
  }
  return result;
}

surface::MarchingCubes& Simulation::enableSurface() {
  if (!surface_) {
    const scene::SurfaceSpec& spec = scene_.surface;
    surface_ = std::make_unique<surface::MarchingCubes>(*context_, spec.resolution, spec.maxTriangles);
    surface::FieldSettings settings;
    settings.resolution = spec.resolution;
    settings.iso = spec.iso;
    settings.h = solver_->settings().h();
    settings.restDensity = solver_->settings().restDensity;
    settings.splatVoxelOverH = spec.splatVoxelOverH;
    // The scene's domain, grown by the kernel's support: fluid beyond it has escaped.
    settings.clipLo = scene_.domain.min - glm::vec3(settings.h * 2.0f);
    settings.clipHi = scene_.domain.max + glm::vec3(settings.h * 2.0f);
    field_ = std::make_unique<surface::ParticleField>(*context_, *surface_, *store_, solver_->state(), settings);
  }
  return *surface_;
}

void Simulation::recordSurface(gpu::CommandRecorder& rec, gpu::TimestampQueries* timestamps) {
  enableSurface();
  rec.computeToCompute();
  field_->record(rec, store_->count(), timestamps);
  surface_->record(rec, timestamps);
}

void Simulation::recordWallShade(gpu::CommandRecorder& rec, MassSpring::ShadeBy by) {
  if (auto* wall = solver_->wall()) wall->recordShade(rec, store_->count(), by);
}

surface::SurfaceMesh Simulation::extractSurface() {
  recorder_->begin();
  recordSurface(*recorder_);
  recorder_->end();
  recorder_->submitAndWait();
  return surface_->readMesh();
}

void Simulation::enableWallShear() {
  if (!solver_->wall()) throw std::logic_error("wall shear: the scene has no vessel wall");
  if (solver_->solvesPressure()) throw std::logic_error("wall shear: not under DFSPH (a batch run again would count its steps twice)");
  solver_->wall()->setWallShear(true);
  wallShear_ = true;
}

Simulation::WallShearMaps Simulation::readWallShear() const {
  WallShearMaps m;
  const MassSpring* wall = solver_->wall();
  if (!wall) return m;
  const std::uint32_t points = wall->pointCount();
  m.wss.assign(points, glm::vec3(0.0f));
  m.tawss.assign(points, 0.0f);
  m.osi.assign(points, 0.0f);
  if (!wallShear_) return m;
  const auto ids = store_->readIds();
  const auto tau = wall->wallShearStress().readback<glm::vec4>(ids.size());
  for (std::size_t slot = 0; slot < ids.size(); ++slot) {
    if (ids[slot] < points) m.wss[ids[slot]] = glm::vec3(tau[slot]);
  }
  const MassSpring::ShearSums sums = wall->readShearSums();
  m.seconds = sums.seconds;
  for (std::uint32_t i = 0; i < points; ++i) {
    const glm::vec4 s = sums.perPoint[i];
    if (sums.seconds > 0.0) m.tawss[i] = float(s.w / sums.seconds);
    if (s.w > 0.0f) m.osi[i] = float(0.5 * (1.0 - std::min(1.0, double(glm::length(glm::vec3(s))) / s.w)));
  }
  return m;
}

void Simulation::enableStepStats(std::uint32_t every) {
  statsEvery_ = std::max(every, 1u);
  if (!stats_) stats_ = std::make_unique<StepStats>(*context_, *store_, *solver_, scene_.stepsPerBatch);
}

Snapshot Simulation::snapshot() const {
  // Boundary particles without fluid in the list keep the state of the last list build in
  // the steps; give them the last step's.
  recorder_->begin();
  solver_->recordBoundaryRest(*recorder_);
  recorder_->end();
  recorder_->submitAndWait();
  Snapshot s;
  const std::uint32_t n = store_->count();
  const auto pos = store_->readPositions();
  const auto vel = store_->readVelocities();
  const auto ids = store_->readIds();
  const auto state = solver_->state().readback<glm::vec4>(n);
  s.positions.resize(n);
  s.velocities.resize(n);
  s.densityPressure.resize(n);
  s.ids.resize(n);
  for (std::uint32_t slot = 0; slot < n; ++slot) {
    const std::uint32_t id = ids[slot];
    if (id >= n) continue;
    s.positions[id] = pos[slot];
    s.velocities[id] = vel[slot];
    s.densityPressure[id] = glm::vec2(state[slot]);
    s.ids[id] = id;
  }
  if (solver_->settings().nonNewtonian()) {
    // the solver's viscosities are over the lattice factor (interface/sph.h, params.mu)
    const auto mu = solver_->viscosities().readback<float>(n);
    const double factor = solver_->settings().viscousLatticeFactor();
    s.viscosity.assign(n, 0.0f);
    for (std::uint32_t slot = 0; slot < n; ++slot) {
      const std::uint32_t id = ids[slot];
      if (id < n && vel[slot].w == float(ParticleKind::Fluid)) s.viscosity[id] = float(mu[slot] * factor);
    }
  }
  if (solver_->openEnds()) {
    // Open ends: the parked slots hold no particle (interface/sph.h, HEMO_KIND_PARKED).
    std::size_t k = 0;
    for (std::size_t r = 0; r < s.positions.size(); ++r) {
      if (std::uint32_t(s.velocities[r].w) == HEMO_KIND_PARKED) continue;
      s.positions[k] = s.positions[r];
      s.velocities[k] = s.velocities[r];
      s.densityPressure[k] = s.densityPressure[r];
      s.ids[k] = s.ids[r];
      if (!s.viscosity.empty()) s.viscosity[k] = s.viscosity[r];
      ++k;
    }
    s.positions.resize(k);
    s.velocities.resize(k);
    s.densityPressure.resize(k);
    s.ids.resize(k);
    if (!s.viscosity.empty()) s.viscosity.resize(k);
  }
  return s;
}

std::vector<gpu::Buffer*> Simulation::checkpointBuffers() {
  std::vector<gpu::Buffer*> all;
  solver_->checkpointBuffers(all);
  std::vector<gpu::Buffer*> buffers;
  for (gpu::Buffer* b : all) {
    if (b->valid()) buffers.push_back(b);
  }
  return buffers;
}

void Simulation::writeCheckpoint(const std::filesystem::path& path) {
  io::CheckpointHeader h;
  h.scene = scene_.name;
  h.sceneFingerprint = fingerprint_;
  const VkPhysicalDeviceProperties& device = context_->properties();
  h.device = context_->info().name;
  h.driver = context_->driver();
  h.vendorId = device.vendorID;
  h.deviceId = device.deviceID;
  std::copy(std::begin(device.pipelineCacheUUID), std::end(device.pipelineCacheUUID), h.pipelineCacheUuid.begin());
  h.steps = steps_;
  h.time = time();
  h.host = {static_cast<std::uint32_t>(steps_), static_cast<std::uint32_t>(steps_ >> 32)};
  const std::vector<std::uint32_t> solver = solver_->hostState();
  h.host.insert(h.host.end(), solver.begin(), solver.end());
  std::vector<io::CheckpointPayload> payloads;
  for (const gpu::Buffer* b : checkpointBuffers()) payloads.push_back(io::payloadOf(*b));
  io::writeCheckpoint(path, h, payloads);
}

void Simulation::resume(const std::filesystem::path& path) {
  const io::CheckpointFile file = io::readCheckpoint(path);
  const io::CheckpointHeader& h = file.header;
  const std::string name = "checkpoint '" + path.string() + "'";
  if (h.sceneFingerprint != fingerprint_) {
    throw io::CheckpointError(name + " was written for scene '" + h.scene + "'" +
                              (h.scene == scene_.name ? " as it was then" : "") + ": the particles, springs or settings of scene '" +
                              scene_.name + "' differ from it");
  }
  const VkPhysicalDeviceProperties& device = context_->properties();
  if (h.device != context_->info().name || h.driver != context_->driver() || h.vendorId != device.vendorID ||
      h.deviceId != device.deviceID ||
      !std::equal(h.pipelineCacheUuid.begin(), h.pipelineCacheUuid.end(), std::begin(device.pipelineCacheUUID))) {
    throw io::CheckpointError(name + " was written on " + h.device + " (" + h.driver + "), this run is on " +
                              context_->info().name + " (" + context_->driver() +
                              "): a checkpoint resumes on the device and driver that wrote it");
  }
  const std::vector<std::uint32_t> solverState(h.host.begin() + std::min<std::size_t>(2, h.host.size()), h.host.end());
  if (h.host.size() < 2 || solverState.size() != solver_->hostState().size()) {
    throw io::CheckpointError(name + " does not fit this simulation (written by another build of hemo): " +
                              std::to_string(h.host.size()) + " words of host state");
  }
  io::loadCheckpointBuffers(path, file, checkpointBuffers());
  solver_->restoreHostState(solverState);
  steps_ = std::uint64_t(h.host[0]) | std::uint64_t(h.host[1]) << 32;
}

std::uint32_t Simulation::escapedParticles() const {
  // (with open ends, blood that left the domain was parked: counted on the GPU)
  const std::uint32_t parked = solver_->openEnds() ? solver_->readOpenCounts().parkedOutside : 0u;
  return scene::countEscaped(scene_, store_->readPositions(), store_->readVelocities()) + parked;
}

std::uint32_t Simulation::activeFluidParticles() const {
  std::uint32_t n = 0;
  for (const glm::vec4& v : store_->readVelocities()) n += std::uint32_t(v.w) == HEMO_KIND_FLUID ? 1u : 0u;
  return n;
}

std::uint32_t Simulation::lostParticles() const {
  return scene::countLost(store_->readPositions(), store_->readVelocities());
}

std::uint32_t Simulation::brokenSprings() const { return solver_->wall() ? solver_->wall()->readBrokenCount() : 0; }

std::uint32_t Simulation::detachedParticles() const { return solver_->wall() ? solver_->wall()->readDetachedCount() : 0; }

}  // namespace hemo::sim
