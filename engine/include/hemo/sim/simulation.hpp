#pragma once
// A scene on the GPU: builds its particles, assembles the step from what the scene needs,
// and runs it in batches of many steps per submit. The host waits once per batch (to read
// the clock and the status), never per step.
#include "hemo/scene/build.hpp"
#include "hemo/sim/sph.hpp"
#include "hemo/sim/stats.hpp"
#include "hemo/surface/marching_cubes.hpp"

#include <glm/vec2.hpp>

#include <chrono>
#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <string>

namespace hemo::sim {

// The simulation became non-finite or unstable (hemo-run exit code 2).
class SimulationError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct Progress {
  std::uint64_t steps = 0;
  std::uint64_t firstStep = 0;  // the step count when this run began (a resumed run's checkpoint)
  double time = 0.0;       // simulated s
  double endTime = 0.0;    // s (0 when running a fixed number of steps)
  std::uint64_t targetSteps = 0;
  double wallSeconds = 0.0;
};

// One tool's record of one step (with tools): the step's index (0 = the run's first step
// ever), its dt (s) and the tool's index in the scene.
struct ToolLogRow {
  std::uint64_t step = 0;
  float dt = 0.0f;
  std::uint32_t tool = 0;
  ToolSample sample{};
};

// How the tools' force signal reached the host (Simulation::toolFeedback): each batch's rows
// arrive with its report, once the batch's fence signals.
struct ToolFeedback {
  std::uint64_t batches = 0;   // batches that delivered rows
  std::uint64_t samples = 0;   // steps delivered (each with every tool's force and torque)
  double seconds = 0.0;        // wall time over which they arrived: each run's, from its start
                               // to its last batch's rows in hand (the rate's denominator)
  double latencySeconds = 0.0; // the batches' times from submission to the rows in hand, summed
                               // (a pipelined run's batches overlap: this exceeds `seconds`)
  double maxLatency = 0.0;     // s: the longest such batch (the age of its first step's force, at most)
};

struct RunOptions {
  std::optional<std::uint64_t> steps;  // run this many steps ...
  std::optional<double> until;         // ... or until this simulated time (s); default: scene end time
  std::uint32_t outputEvery = 0;       // call onOutput every N steps (0: never)
  std::function<void(const Progress&)> onBatch;
  std::function<void(const Progress&)> onOutput;
  // With enableStepStats: the rows of each batch (steps that changed nothing are left out).
  std::function<void(const std::vector<StepStatsRow>&)> onStepStats;
  // With tools: every step's force, torque and pose of each tool, once per batch (the GPU
  // logs them inside the batch; no host wait per step).
  std::function<void(const std::vector<ToolLogRow>&)> onToolLog;
  // DFSPH: the (correction, prediction) regions recorded per solve (SphSolver::
  // setRecordedIterations), 1 to the cap. Unset: chosen per batch from what the last batch's
  // solves took. Any depth gives the same results bit for bit; a shallow one costs batches run
  // again (Simulation::redoneBatches), a deep one empty dispatches.
  std::optional<std::uint32_t> recordedSolveIterations;
  // Keep a second batch in flight: the next batch is recorded and submitted before the last
  // one's report is read, so the GPU does not wait while the host reads a report, records and
  // submits (two command buffers; the reports' ring of two). Results are the same bit for
  // bit. Taken only where nothing reads or changes the state between batches: not with
  // outputEvery, step statistics or DFSPH (whose batches may have to run again), which run
  // one batch at a time. A failure is reported after the batch in flight has finished too,
  // so the state left behind is that batch's.
  bool pipelined = false;
};

struct RunResult {
  std::uint64_t steps = 0;
  double simTime = 0.0;     // s
  double wallSeconds = 0.0;
};

// Fluid state in input (id) order, for output and tests: row k is particle ids[k], which is k
// except with open vessel ends, whose parked slots (no particle) are left out.
struct Snapshot {
  std::vector<glm::vec4> positions;   // xyz m, w mass
  std::vector<glm::vec4> velocities;  // xyz m/s, w kind
  std::vector<glm::vec2> densityPressure;  // kg/m^3, Pa (of the last density pass)
  std::vector<std::uint32_t> ids;
  // Non-Newtonian blood only (else empty): each fluid particle's viscosity at the last force
  // evaluation (Pa s; 0 for other particles and before the first step).
  std::vector<float> viscosity;
};

class Simulation {
 public:
  // Throws scene::SceneError if the scene does not fit the device (names the field).
  Simulation(gpu::Context& context, const scene::Scene& scene);

  // Runs; throws SimulationError (with step, time and particle) if the state becomes
  // non-finite or a particle's neighbours exceed the capacity.
  RunResult run(const RunOptions& options);

  Snapshot snapshot() const;
  // What the solver recorded per step, on average over every step run() has recorded so far:
  // dispatches (the gated neighbour rebuild's included, which the GPU runs with no workgroups
  // when it stays closed) and barriers. On a GPU each costs a few microseconds whatever the
  // particle count, so at small N they set the step time. 0 before the first step.
  double dispatchesPerStep() const { return recordedSteps_ ? double(recordedDispatches_) / double(recordedSteps_) : 0.0; }
  double barriersPerStep() const { return recordedSteps_ ? double(recordedBarriers_) / double(recordedSteps_) : 0.0; }
  // DFSPH: batches that run() ran again from their start because a solve needed more
  // iterations than the batch recorded (their first runs' dispatches count in the averages
  // above), and the solve's recorded regions per step on average.
  std::uint64_t redoneBatches() const { return redoneBatches_; }
  // The tools' force signal so far (runs with onToolLog).
  const ToolFeedback& toolFeedback() const { return feedback_; }
  double recordedSolveIterationsPerStep() const {
    return recordedSteps_ ? double(recordedSolveRegions_) / double(recordedSteps_) : 0.0;
  }

  // Checkpoints (hemo/io/checkpoint.hpp). writeCheckpoint writes the whole state between runs
  // (atomically; throws io::WriteError naming the file). resume replaces the state of a
  // simulation built from the same scene, on the same device and driver, with a checkpoint's:
  // the steps that follow are bit for bit those of the run that wrote it. It throws
  // io::CheckpointError naming the file and the problem (not a checkpoint, another format
  // version, truncated, damaged, another scene, device or build) before changing anything,
  // except for a read failure while uploading (the state is then undefined: build anew).
  void writeCheckpoint(const std::filesystem::path& path);
  void resume(const std::filesystem::path& path);
  // A hash of what the scene built (particles, springs, settings, inflow, domain): what a
  // checkpoint must have been written for.
  std::uint64_t sceneFingerprint() const { return fingerprint_; }

  // Records per-step statistics (hemo/sim/stats.hpp) of every `every`-th step from now on,
  // delivered through RunOptions::onStepStats once per batch.
  void enableStepStats(std::uint32_t every = 1);
  // The wall maps clinicians read (hemo/sim/wall.hpp, MassSpring::setWallShear): from now on
  // every step fits the wall shear stress at each wall particle and adds it to time sums, on
  // the GPU (no host work per step; runs are not pipelined). Throws std::logic_error without a
  // vessel wall, or under DFSPH (a batch run again would count its steps twice).
  void enableWallShear();
  bool wallShearEnabled() const { return wallShear_; }
  // Per wall point id: the last step's wall shear stress (Pa, as a vector), its magnitude
  // averaged over the time since enableWallShear (TAWSS, Pa) and the oscillatory shear index
  // OSI = 0.5 (1 - |mean tau| / mean |tau|) (0 for one-way shear, up to 0.5 when it reverses;
  // Ku et al. 1985). Points no fluid touches read 0. A readback.
  struct WallShearMaps {
    std::vector<glm::vec3> wss;
    std::vector<float> tawss;
    std::vector<float> osi;
    double seconds = 0.0;  // the time averaged over
  };
  WallShearMaps readWallShear() const;
  // GPU milliseconds of each stage of one step (median of `repeats` steps, run now and
  // counted like any other step). Empty if the device has no timestamps. Most steps reuse
  // the neighbour list, and so do the profiled ones unless `rebuild` forces the grid and
  // list build into each of them (the cost of a rebuild step).
  std::vector<std::pair<std::string, double>> profileStep(int repeats = 5, bool rebuild = false);
  // The blood surface (hemo/surface/marching_cubes.hpp) on the grid of the scene's `surface`
  // section. The extractor is built on first use: a run nobody looks at never has one.
  // recordSurface records the field and the extraction (after the steps recorded before it);
  // extractSurface records, submits, waits and reads the mesh back (for files).
  surface::MarchingCubes& enableSurface();
  void recordSurface(gpu::CommandRecorder& rec, gpu::TimestampQueries* timestamps = nullptr);
  surface::SurfaceMesh extractSurface();
  const surface::MarchingCubes* surfaceExtractor() const { return surface_.get(); }
  // The wall's per-particle strain (or, with the wall maps on, its wall shear stress or the
  // stress's time average, Pa) and broken fraction for the renderer (recorded on request;
  // nullptr without a wall).
  void recordWallShade(gpu::CommandRecorder& rec, MassSpring::ShadeBy by = MassSpring::ShadeBy::Strain);
  const gpu::Buffer* wallShade() const { return solver_->wall() ? &solver_->wall()->shade() : nullptr; }
  // The wall's outermost layer as a surface for drawing (hemo/sim/wall_surface.hpp): triangles
  // of particle ids with their edges' springs, kWallTriangleWords uints each. Built on first use from the
  // wall's springs and frames (readbacks) and the particles' positions now: a run nobody looks
  // at never has them. Throws std::logic_error without a wall.
  const gpu::Buffer& enableWallSurface();
  const gpu::Buffer* wallTriangles() const { return wallTriangles_ ? &*wallTriangles_ : nullptr; }
  std::uint32_t wallTriangleCount() const { return wallTriangleCount_; }
  const scene::Scene& scene() const { return scene_; }
  std::uint32_t fluidParticles() const { return fluid_; }
  std::uint32_t boundaryParticles() const { return boundary_; }
  std::uint64_t steps() const { return steps_; }
  double time() const;
  std::uint32_t wallParticles() const { return wall_; }
  std::uint32_t springs() const { return springs_; }
  // Fluid particles that have left the scene now: outside the domain, or outside the
  // vessel's wall (through a rupture); with open ends, also those parked once they had left
  // the domain across the axis.
  std::uint32_t escapedParticles() const;
  // Particles whose state is no longer finite (0 unless the run stopped with a SimulationError).
  std::uint32_t lostParticles() const;
  // Open vessel ends (hemo/sim/inflow.hpp): what has crossed the inlet and outlet planes since
  // the start (counts of particles of the fluid's mass; a readback). Zeros without open ends.
  bool openEnds() const { return solver_->openEnds(); }
  SphSolver::OpenCounts openCounts() const { return solver_->readOpenCounts(); }
  // The fluid particles now: fluidParticles() less those that left through open ends plus those
  // the inlet made (a readback).
  std::uint32_t activeFluidParticles() const;
  // Springs broken and wall particles detached so far (0 without a wall).
  std::uint32_t brokenSprings() const;
  std::uint32_t detachedParticles() const;
  ParticleStore& store() { return *store_; }
  SphSolver& solver() { return *solver_; }

  // Live controls, between runs (hemo-view's panel): each is an upload that takes effect from
  // the next step. They are not checkpoint state: a checkpoint written after a change resumes
  // with the scene's values.
  // The lumen's background pressure p_bg (Pa; fluid.background_pressure_Pa). Throws
  // std::invalid_argument if it is not finite.
  void setLumenPressure(float pascals) { solver_->setBackgroundPressure(pascals); }
  float lumenPressure() const { return solver_->settings().backgroundPressure; }
  // The inflow zone's mean speed U (m/s; a waveform scales it, a ramp still applies). Throws
  // std::logic_error without an inflow zone, std::invalid_argument for a non-finite speed.
  bool hasInflow() const { return inflow_.has_value(); }
  void setInflowSpeed(float metresPerSecond);
  float inflowSpeed() const { return inflow_ ? inflow_->meanSpeed : 0.0f; }
  // The wall's springs' stiffness times `scale` (MassSpring::setStiffnessScale). Throws
  // std::logic_error without a wall.
  void setWallStiffnessScale(float scale);
  float wallStiffnessScale() const { return solver_->wall() ? solver_->wall()->stiffnessScale() : 1.0f; }

  // The step below which a run stops (time.min_dt_s, or 1e-4 of the scene's own step), and
  // that own step: the smallest of the fluid's acoustic (DFSPH: flow) limit at the expected
  // speed, max_dt_s, the viscous limit and the wall's spring limit times its substeps.
  double minTimeStep() const { return minStep_; }
  double designTimeStep() const;

 private:
  // RunOptions::pipelined.
  RunResult runPipelined(const RunOptions& options);
  // A run's progress now, for its callbacks.
  Progress progressOf(const RunOptions& options, std::uint64_t firstStep, double time, double endTime,
                      std::chrono::steady_clock::time_point start) const;
  // Reads a batch's report from its slot (after its fence): the clock (into `clock`; its
  // record by `parity`, the clock's after the batch) and the status words (throws on a
  // failure), and with onToolLog the batch's tool log. Returns the steps the batch advanced
  // the clock by.
  std::uint64_t takeReport(const RunOptions& options, std::uint32_t slot, std::uint32_t parity, std::uint64_t batch,
                           SphClock& clock, double endTime, std::chrono::steady_clock::time_point submitted);
  void checkStatus(std::uint64_t batchFirstStep);
  void checkStatus(std::uint64_t batchFirstStep, const SphStatus& status);
  // The batch report: at the end of each batch's command buffer, copies of the solver's clock
  // records and status words, the batch's step log and (with tools) its tool log, into a
  // host-visible slot of a ring of two. The host reads the batch's outcome from there once its
  // fence signals, with no readback submission of its own: on a discrete GPU, whose device
  // memory the host cannot map, every readback is otherwise a copy, a submission and a wait.
  void recordReport(gpu::CommandRecorder& rec, std::uint32_t slot, std::uint32_t steps);
  struct ReportLayout {
    VkDeviceSize clock = 0, status = 0, stepLog = 0, toolLog = 0, bytes = 0;
  };
  // Throws when the batch that started at `batchFirstStep` and did not reach the end time
  // left the step below minTimeStep(): a blow-up that stays finite (a particle at 1e9 m/s)
  // shrinks the step until the clock no longer advances, and the run would never end.
  void checkStep(const SphClock& clock, std::uint64_t batchFirstStep, double endTime);
  // A batch that may have to run again (DFSPH recorded below its cap) starts from a copy of
  // the whole state (the checkpoint's buffers) made on the GPU: save records the copy, restore
  // records the copy back. canSaveState allocates the copy on first use; false (for good) when
  // the device's memory cannot hold it, and the solves are then recorded to their cap.
  bool canSaveState();
  // Records (`record`, after the command buffer's prologue), submits and waits; under DFSPH
  // recorded below the cap, from a copy of the starting state, and again recorded to the cap
  // while a solve was left open (redoneBatches_). Returns what the solves needed.
  SphSolver::SolveDepth submitSteps(const std::function<void()>& record);
  void recordSaveState(gpu::CommandRecorder& rec);
  void recordRestoreState(gpu::CommandRecorder& rec);

  gpu::Context* context_;
  scene::Scene scene_;
  std::uint32_t fluid_ = 0;
  std::uint32_t boundary_ = 0;
  std::uint32_t wall_ = 0;
  std::uint32_t springs_ = 0;
  std::unique_ptr<ParticleStore> store_;
  std::unique_ptr<SphSolver> solver_;
  std::unique_ptr<gpu::CommandRecorder> recorder_;
  std::unique_ptr<gpu::CommandRecorder> recorder2_;  // the second batch in flight (pipelined runs)
  std::unique_ptr<StepStats> stats_;
  std::unique_ptr<surface::MarchingCubes> surface_;
  std::unique_ptr<surface::ParticleField> field_;
  std::uint32_t statsEvery_ = 0;
  bool wallShear_ = false;
  std::uint64_t steps_ = 0;
  std::uint64_t fingerprint_ = 0;
  std::uint64_t recordedDispatches_ = 0, recordedBarriers_ = 0, recordedSteps_ = 0;
  std::uint64_t redoneBatches_ = 0, recordedSolveRegions_ = 0;
  double minStep_ = 0.0;             // s (minTimeStep)
  std::uint32_t solveDepth_ = 0;     // the next batch's recorded regions per solve (adaptive)
  std::vector<gpu::Buffer> saved_;   // recordSaveState's copy
  bool saveRefused_ = false;         // the device's memory could not hold the copy
  std::vector<gpu::Buffer*> checkpointBuffers();
  ReportLayout report_;
  gpu::Buffer reports_[2];
  std::uint32_t reportSlot_ = 0;
  ToolFeedback feedback_;
  std::chrono::steady_clock::time_point lastDelivery_;  // the run's start, then its last tool rows
  std::optional<Inflow> inflow_;  // the inflow zone as driven now (setInflowSpeed)
  std::optional<gpu::Buffer> wallTriangles_;  // enableWallSurface
  std::vector<glm::vec3> wallNormals_;         // by wall point id, as built (inward)
  std::uint32_t wallTriangleCount_ = 0;
};

}  // namespace hemo::sim
