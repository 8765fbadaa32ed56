// hemo-run SCENE.json [--out DIR] [--steps N | --until SECONDS] [--device SEL] [--vtk-every N] [--stats-every N]
//          [--surface-every N] [--png-every N] [--png-size WxH] [--profile N] [--checkpoint-every N]
//          [--resume FILE]
// Runs a scene headless: a progress line, then a summary on screen and in DIR/summary.json.
// Exit codes: 0 success; 1 bad input (a bad checkpoint too); 2 the simulation became
// non-finite or unstable; 3 no usable Vulkan device or a device error; 4 an output that cannot
// be written.
#include "cli.hpp"
#include "hemo/io/atomic_file.hpp"
#include "hemo/io/checkpoint.hpp"
#include "hemo/io/output.hpp"
#include "hemo/render/renderer.hpp"
#include "hemo/scene/scene.hpp"
#include "hemo/scene/build.hpp"
#include "hemo/sim/simulation.hpp"

#include <nlohmann/json.hpp>

#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <numeric>
#include <optional>
#include <cstdlib>
#include <tuple>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>

namespace {

using Json = nlohmann::json;

// A per-step CSV (written under a temporary name, renamed when the run ends): its header, and
// on a resumed run the rows of the run it continues up to the checkpoint's step (rows start
// with the step count), then 9 significant digits.
std::unique_ptr<hemo::io::AtomicFile> openStepCsv(const std::filesystem::path& path, const std::string& header,
                                                  bool resumed, std::uint64_t firstStep) {
  std::vector<std::string> kept;
  if (resumed) {
    std::ifstream old(path);
    std::string line;
    if (std::getline(old, line) && line == header) {
      while (std::getline(old, line)) {
        char* end = nullptr;
        const unsigned long long step = std::strtoull(line.c_str(), &end, 10);
        if (end == line.c_str() || *end != ',' || step > firstStep) break;
        kept.push_back(line);
      }
    }
  }
  auto file = std::make_unique<hemo::io::AtomicFile>(path);
  std::ostream& csv = file->stream();
  csv << header << "\n";
  for (const std::string& line : kept) csv << line << "\n";
  csv.precision(9);
  return file;
}

const char* kUsage =
    "usage: hemo-run SCENE.json [--out DIR] [--steps N | --until SECONDS] [--device SEL] [--vtk-every N]\n"
    "                [--vtk-format xml|legacy] [--stats-every N] [--surface-every N] [--png-every N]\n"
    "                [--png-size WxH] [--profile N] [--checkpoint-every N] [--resume FILE]\n"
    "                [--pipeline on|off]\n"
    "  --out DIR        output directory (default: out/<scene name>)\n"
    "  --steps N        run until step N (N steps; a resumed run counts the checkpoint's steps)\n"
    "  --until SECONDS  run until this simulated time (default: the scene's time.end_time_s)\n"
    "  --device SEL     Vulkan device index or name part (default: HEMO_DEVICE, else the best)\n"
    "  --vtk-every N    write DIR/particles_<step>.vtu every N steps (and at the end), listed with\n"
    "                   their times in DIR/particles.pvd (a ParaView time series); with a vessel also\n"
    "                   DIR/springs_<step>.vtp (strain, tension, broken) in DIR/springs.pvd\n"
    "  --vtk-format F   xml (default): binary VTK XML as above; legacy: ASCII legacy VTK,\n"
    "                   DIR/particles_<step>.vtk and DIR/springs_<step>.vtk, no .pvd\n"
    "  --stats-every N  write DIR/steps.csv: time, dt, max fluid speed, max density error, broken\n"
    "                   springs and detached wall particles of every N-th step (recorded on the GPU)\n"
    "  --profile N      after the run, time N more steps stage by stage (GPU ms in stage_ms),\n"
    "                   then N steps that rebuild the neighbour list (rebuild_stage_ms)\n"
    "  --surface-every N  write the blood surface (GPU marching cubes, the scene's surface section)\n"
    "                   as DIR/surface_<step>.ply every N steps (and at the end)\n"
    "  --png-every N    render DIR/frame_<step>.png every N steps (and at the end): the blood\n"
    "                   surface, the vessel wall cut open on the camera's side, offscreen\n"
    "  --png-size WxH   frame size in pixels (default 960x540)\n"
    "  --checkpoint-every N  write the whole state to DIR/checkpoint.hemo every N steps (and at the\n"
    "                   end), replacing the last one\n"
    "  --resume FILE    continue from a checkpoint of this scene written on this device and driver:\n"
    "                   the run is bit-identical to the uninterrupted one; DIR/steps.csv keeps its\n"
    "                   rows up to the checkpoint\n"
    "  --pipeline on|off  keep a second batch in flight while the last one's report is read (on,\n"
    "                   the default, where no output reads the state between batches): the GPU\n"
    "                   never waits for the host, and the tools' force rows arrive a batch later\n"
    "hemo-run --describe-scene   prints the scene-file parameter table\n"
    "hemo-run --help             prints this text\n";

void printProgress(const hemo::sim::Progress& p, bool tty) {
  const double fraction = p.endTime > 0 ? p.time / p.endTime
                                        : (p.targetSteps ? double(p.steps) / double(p.targetSteps) : 0.0);
  const int width = 30;
  const int filled = std::clamp(int(fraction * width + 0.5), 0, width);
  const double rate = p.wallSeconds > 0 ? double(p.steps - p.firstStep) / p.wallSeconds : 0.0;
  std::fprintf(stderr, "%s[%.*s%*s] %5.1f%%  step %llu  t = %.4g s  %.0f steps/s%s", tty ? "\r" : "", filled,
               "##############################", width - filled, "", 100.0 * std::min(fraction, 1.0),
               static_cast<unsigned long long>(p.steps), p.time, rate, tty ? "" : "\n");
  std::fflush(stderr);
}

}  // namespace

int main(int argc, char** argv) {
  if (hemo::cli::printUsageIfAsked(argc, argv, kUsage)) return 0;
  if (argc == 2 && std::string(argv[1]) == "--describe-scene") {
    std::printf("%s", hemo::scene::schemaMarkdown().c_str());  // the table of docs/scene-format.md
    return 0;
  }
  hemo::cli::Args args;
  try {
    args = hemo::cli::parse(argc, argv, {"--out", "--steps", "--until", "--device", "--vtk-every", "--png-every",
                                         "--surface-every", "--profile", "--stats-every", "--png-size",
                                         "--checkpoint-every", "--resume", "--vtk-format", "--pipeline"});
    if (args.positional.size() != 1) throw hemo::cli::UsageError("expected exactly one SCENE.json");
    if (args.has("--steps") && args.has("--until")) throw hemo::cli::UsageError("give --steps or --until, not both");

  } catch (const hemo::cli::UsageError& e) {
    std::cerr << "hemo-run: " << e.what() << "\n" << kUsage;
    return 1;
  }

  hemo::sim::RunOptions options;
  std::uint32_t vtkEvery = 0;
  bool vtkLegacy = false;
  std::uint32_t surfaceEvery = 0;
  std::uint32_t pngEvery = 0;
  std::uint32_t pngWidth = 960, pngHeight = 540;
  std::uint64_t profileSteps = 0;
  std::uint32_t statsEvery = 0;
  std::uint32_t checkpointEvery = 0;
  std::optional<std::uint64_t> stepsTotal;
  hemo::scene::Scene scene;
  try {
    if (args.has("--steps")) stepsTotal = args.count("--steps", 0, 1, 4000000000ull);
    if (args.has("--until")) options.until = args.seconds("--until", 0.0);
    vtkEvery = static_cast<std::uint32_t>(args.count("--vtk-every", 0, 1, 1000000000));
    const std::string vtkFormat = args.text("--vtk-format", "xml");
    if (vtkFormat != "xml" && vtkFormat != "legacy") throw hemo::cli::UsageError("--vtk-format expects xml or legacy");
    vtkLegacy = vtkFormat == "legacy";
    surfaceEvery = static_cast<std::uint32_t>(args.count("--surface-every", 0, 1, 1000000000));
    pngEvery = static_cast<std::uint32_t>(args.count("--png-every", 0, 1, 1000000000));
    std::tie(pngWidth, pngHeight) = args.size("--png-size", {960, 540});
    profileSteps = args.count("--profile", 0, 1, 1000);
    statsEvery = static_cast<std::uint32_t>(args.count("--stats-every", 0, 1, 1000000000));
    checkpointEvery = static_cast<std::uint32_t>(args.count("--checkpoint-every", 0, 1, 1000000000));
    if (args.has("--resume") && args.text("--resume").empty()) throw hemo::cli::UsageError("--resume expects a FILE");
    const std::string pipeline = args.text("--pipeline", "on");
    if (pipeline != "on" && pipeline != "off") throw hemo::cli::UsageError("--pipeline expects on or off, got '" + pipeline + "'");
    // A second batch in flight while the last one's report is read, where no output reads the
    // state between batches (the engine runs one batch at a time otherwise).
    options.pipelined = pipeline == "on";
    scene = hemo::scene::loadScene(args.positional[0]);
  } catch (const hemo::cli::UsageError& e) {
    std::cerr << "hemo-run: " << e.what() << "\n" << kUsage;
    return 1;
  } catch (const hemo::scene::SceneError& e) {
    std::cerr << "hemo-run: " << e.what() << "\n";
    return 1;
  }

  const std::filesystem::path out = args.text("--out", "out/" + scene.name);
  std::error_code ec;
  std::filesystem::create_directories(out, ec);
  if (ec) {
    std::cerr << "hemo-run: cannot create the output directory '" << out.string() << "': " << ec.message() << "\n";
    return 1;
  }

  Json summary;
  int code = 0;
  std::string failure;
  try {
    hemo::gpu::ContextOptions ctxOptions;
    ctxOptions.device = args.text("--device");
    hemo::gpu::Context ctx(ctxOptions);
    hemo::sim::Simulation sim(ctx, scene);
    std::fprintf(stderr, "hemo-run: %s on %s: %u fluid + %u boundary + %u wall particles, %u springs\n", scene.name.c_str(),
                 ctx.info().name.c_str(), sim.fluidParticles(), sim.boundaryParticles(), sim.wallParticles(), sim.springs());
    const bool resumed = args.has("--resume");
    if (resumed) {
      sim.resume(args.text("--resume"));
      std::fprintf(stderr, "hemo-run: resumed from %s at step %llu (t = %.6g s)\n", args.text("--resume").c_str(),
                   static_cast<unsigned long long>(sim.steps()), sim.time());
    }
    const std::uint64_t firstStep = sim.steps();
    if (stepsTotal) options.steps = *stepsTotal > firstStep ? *stepsTotal - firstStep : 0;
    const std::optional<hemo::scene::RuptureEstimate> rupture = hemo::scene::ruptureEstimate(scene);
    if (rupture) {
      std::fprintf(stderr,
                   "hemo-run: the wall fails at a lumen (fluid) pressure of about %.0f Pa reached slowly (%s); the scene's background "
                   "pressure is %.0f Pa, which the fluid's own pressure lags while the wall stretches\n",
                   rupture->pressure, rupture->method.c_str(), double(scene.sph.backgroundPressure));
    }
    if (const auto* wall = sim.solver().wall()) {
      // what sets the step: the springs' own limit (times the substeps) against the fluid's
      const hemo::sim::SphParams& sp = sim.solver().params();
      const bool dfsph = sim.solver().solvesPressure();
      const double fluidLimit = double(sp.cflAcoustic) * sp.h / (dfsph ? double(scene.expectedMaxSpeed) : double(sp.c0));
      std::fprintf(stderr,
                   "hemo-run: the wall's springs limit the step to %.3g s (%u substep%s of time_step_factor sqrt(m / sum k) = "
                   "%.3g s); the fluid's own limit is about %.3g s (%s)\n",
                   wall->springTimeStepLimit() * wall->substeps(), wall->substeps(), wall->substeps() == 1 ? "" : "s",
                   wall->springTimeStepLimit(), fluidLimit, dfsph ? "C_a h / expected_max_speed" : "C_a h / c0");
      const double wallLimit = wall->springTimeStepLimit() * wall->substeps();
      if (dfsph && wallLimit < 0.5 * fluidLimit) {
        // (at the wall's own step the solve turns the fill's density errors into fast flow)
        std::fprintf(stderr,
                     "hemo-run: warning: DFSPH with a vessel whose springs limit the step to under half the fluid's own "
                     "limit: at so small a step the solve turns density errors into fast flow and the wall tears early "
                     "(docs/physics.md, \"The pressure solver\"); set vessel.substeps to %.0f or more\n",
                     std::ceil(0.5 * fluidLimit / wall->springTimeStepLimit()));
      }
    }
    const bool tty = isatty(2);
    double lastPrint = -1.0;
    options.onBatch = [&](const hemo::sim::Progress& p) {
      if (tty || p.wallSeconds - lastPrint >= 5.0) {
        printProgress(p, tty);
        lastPrint = p.wallSeconds;
      }
    };
    // The XML frames' time series; a resumed run keeps the frames up to its checkpoint's step.
    std::optional<hemo::io::PvdSeries> particleSeries, springSeries;
    auto keepFrame = [&](const std::string& file) {
      const std::size_t digits = file.find_last_of('_');
      return resumed && digits != std::string::npos &&
             std::strtoull(file.c_str() + digits + 1, nullptr, 10) <= firstStep;
    };
    std::uint64_t vtkFiles = 0;  // particle frames written by this run
    auto writeVtk = [&](const hemo::sim::Progress& p) {
      ++vtkFiles;
      const auto step = static_cast<unsigned long long>(p.steps);
      char name[64];
      const hemo::sim::Snapshot snap = sim.snapshot();
      const glm::vec3 period = sim.solver().grid().spec().period;
      const auto* wall = sim.solver().wall();
      const std::vector<hemo::sim::GpuSpring> springs = wall ? wall->readSprings() : std::vector<hemo::sim::GpuSpring>{};
      hemo::sim::Simulation::WallShearMaps maps;
      hemo::io::WallShearFields shear;
      if (sim.wallShearEnabled()) {
        maps = sim.readWallShear();
        shear = {&maps.wss, &maps.tawss, &maps.osi};
      }
      const hemo::io::WallShearFields* shearFields = sim.wallShearEnabled() ? &shear : nullptr;
      if (vtkLegacy) {
        std::snprintf(name, sizeof name, "particles_%08llu.vtk", step);
        hemo::io::writeParticlesVtk(out / name, snap, p.time, wall ? &springs : nullptr, period, shearFields);
        if (wall) {
          std::snprintf(name, sizeof name, "springs_%08llu.vtk", step);
          hemo::io::writeSpringsVtk(out / name, snap, springs, p.time, period);
        }
        return;
      }
      std::snprintf(name, sizeof name, "particles_%08llu.vtu", step);
      hemo::io::writeParticlesVtu(out / name, snap, p.time, wall ? &springs : nullptr, period, shearFields);
      if (!particleSeries) particleSeries.emplace(out / "particles.pvd", keepFrame);
      particleSeries->add(p.time, name);
      if (wall) {
        std::snprintf(name, sizeof name, "springs_%08llu.vtp", step);
        hemo::io::writeSpringsVtp(out / name, snap, springs, p.time, period);
        if (!springSeries) springSeries.emplace(out / "springs.pvd", keepFrame);
        springSeries->add(p.time, name);
      }
    };
    // The wall maps (wall shear stress, its time average and the oscillatory shear index) go
    // into the particle files of a vessel under WCSPH: averaged from the run's start (or its
    // resumption).
    if (vtkEvery && sim.solver().wall() && !sim.solver().solvesPressure()) sim.enableWallShear();
    // (written under a temporary name during the run, renamed when it ends: hemo/io/atomic_file.hpp)
    std::unique_ptr<hemo::io::AtomicFile> csvFile;
    if (statsEvery) {
      csvFile = openStepCsv(out / "steps.csv",
                            "step,time_s,dt_s,max_speed_m_s,max_density_error,broken_springs,detached_particles",
                            resumed, firstStep);
      std::ostream& csv = csvFile->stream();
      sim.enableStepStats(statsEvery);
      options.onStepStats = [&](const std::vector<hemo::sim::StepStatsRow>& rows) {
        for (const auto& r : rows) {
          csv << r.steps << ',' << r.time << ',' << r.dt << ',' << r.maxSpeed << ',' << r.maxDensityError << ','
              << r.brokenSprings << ',' << r.detachedParticles << '\n';
        }
        if (!csv) csvFile->commit();  // (throws the write's error, naming the file)
      };
    }
    // With tools: every step's force, torque and pose of each tool (the GPU logs them inside
    // the batch), kept up to the checkpoint's step on a resumed run like steps.csv.
    std::unique_ptr<hemo::io::AtomicFile> toolFile;
    if (!scene.tools.empty()) {
      const char* header =
          "step,time_s,dt_s,tool,force_x_N,force_y_N,force_z_N,torque_x_N_m,torque_y_N_m,torque_z_N_m,"
          "position_x_m,position_y_m,position_z_m";
      toolFile = openStepCsv(out / "tools.csv", header, resumed, firstStep);
      std::ostream& csv = toolFile->stream();
      options.onToolLog = [&](const std::vector<hemo::sim::ToolLogRow>& rows) {
        for (const auto& r : rows) {
          const auto& f = r.sample;
          csv << r.step + 1 << ',' << f.force.w << ',' << r.dt << ',' << scene.tools[r.tool].name << ',' << f.force.x << ','
              << f.force.y << ',' << f.force.z << ',' << f.torque.x << ',' << f.torque.y << ',' << f.torque.z << ','
              << f.position.x << ',' << f.position.y << ',' << f.position.z << '\n';
        }
        if (!csv) toolFile->commit();  // (throws the write's error, naming the file)
      };
    }
    std::uint64_t surfaceFiles = 0;
    hemo::surface::McTotals lastSurface;
    auto writeSurface = [&](const hemo::sim::Progress& p) {
      char name[64];
      std::snprintf(name, sizeof name, "surface_%08llu.ply", static_cast<unsigned long long>(p.steps));
      const hemo::surface::SurfaceMesh mesh = sim.extractSurface();
      hemo::io::writeSurfacePly(out / name, mesh, p.time);
      if (mesh.totals.overflow() && !lastSurface.overflow()) {
        std::fprintf(stderr, "hemo-run: %s holds %u of %u triangles; raise surface.max_triangles\n", name,
                     mesh.totals.written, mesh.totals.triangles);
      }
      lastSurface = mesh.totals;
      ++surfaceFiles;
    };
    // Frames: the camera frames every particle of the first frame (tank and wall included).
    std::unique_ptr<hemo::render::OffscreenRenderer> renderer;
    std::unique_ptr<hemo::gpu::CommandRecorder> frameRec;
    hemo::render::Camera camera;
    hemo::render::FrameOptions frame;
    std::uint64_t pngFiles = 0;
    auto writePng = [&](const hemo::sim::Progress& p) {
      if (!renderer) {
        renderer = std::make_unique<hemo::render::OffscreenRenderer>(ctx, pngWidth, pngHeight);
        frameRec = std::make_unique<hemo::gpu::CommandRecorder>(ctx);
        // (the snapshot's positions: without an open vessel's parked slots, far outside the domain)
        camera = hemo::render::defaultCamera(sim.snapshot().positions, float(pngWidth) / float(pngHeight),
                                             sim.wallParticles() > 0);
        frame.fluid = false;  // the surface shows the blood
        frame.wall = true;
        frame.boundary = true;  // the tank or walls, cut open on the camera's side
        frame.cutaway = true;
        frame.particleRadius = 0.5f * scene.sph.spacing;
      }
      frameRec->begin();
      sim.recordSurface(*frameRec);
      sim.recordWallShade(*frameRec);
      const hemo::render::ToolView tools{sim.solver().tools() ? &sim.solver().tools()->tools() : nullptr, sim.time()};
      renderer->record(*frameRec, camera, frame,
                       {&sim.store().live().positions, &sim.store().live().velocities, sim.store().count(),
                        sim.wallShade()},
                       sim.surfaceExtractor(), nullptr, &tools);
      frameRec->end();
      frameRec->submitAndWait();
      char name[64];
      std::snprintf(name, sizeof name, "frame_%08llu.png", static_cast<unsigned long long>(p.steps));
      hemo::render::writePng(out / name, pngWidth, pngHeight, renderer->readPixels());
      ++pngFiles;
    };
    // The checkpoint, replaced each time (written whole under a temporary name, then renamed).
    std::uint64_t checkpointStep = 0;
    bool checkpointWritten = false;
    auto writeCheckpoint = [&]() {
      sim.writeCheckpoint(out / "checkpoint.hemo");
      checkpointStep = sim.steps();
      checkpointWritten = true;
    };
    auto writeOutputs = [&](const hemo::sim::Progress& p) {
      if (vtkEvery && p.steps % vtkEvery == 0) writeVtk(p);
      if (surfaceEvery && p.steps % surfaceEvery == 0) writeSurface(p);
      if (pngEvery && p.steps % pngEvery == 0) writePng(p);
      // (after the files above: a checkpoint holds the state after their passes, which change
      // nothing a later step reads)
      if (checkpointEvery && p.steps % checkpointEvery == 0 && p.steps > firstStep) writeCheckpoint();
    };
    if (vtkEvery || surfaceEvery || pngEvery || checkpointEvery) {
      std::uint32_t every = 0;
      for (std::uint32_t e : {vtkEvery, surfaceEvery, pngEvery, checkpointEvery}) {
        if (e) every = every ? std::gcd(every, e) : e;
      }
      options.outputEvery = every;
      options.onOutput = writeOutputs;
      hemo::sim::Progress start;
      start.steps = firstStep;
      start.firstStep = firstStep;
      start.time = sim.time();
      writeOutputs(start);
    }
    hemo::sim::RunResult result;
    bool finite = true;
    try {
      result = sim.run(options);
    } catch (const hemo::sim::SimulationError& e) {
      finite = false;
      failure = e.what();
      code = 2;
    }
    if (tty) std::fprintf(stderr, "\n");
    if (csvFile) csvFile->commit();  // the steps up to the end, or up to the blow-up
    if (toolFile) toolFile->commit();
    if (finite) {
      hemo::sim::Progress p;
      p.steps = sim.steps();
      p.time = sim.time();
      if (vtkEvery && sim.steps() % vtkEvery != 0) writeVtk(p);
      if (surfaceEvery && sim.steps() % surfaceEvery != 0) writeSurface(p);
      if (pngEvery && sim.steps() % pngEvery != 0) writePng(p);
      if (checkpointEvery && (sim.steps() % checkpointEvery != 0 || sim.steps() == firstStep)) writeCheckpoint();
    }
    const double wall = result.wallSeconds;
    const std::uint32_t rebuilds = sim.solver().readRebuilds();
    nlohmann::json stageMs = nlohmann::json::object(), rebuildMs = nlohmann::json::object();
    if (finite && profileSteps > 0) {
      // Extra steps after the run, timed stage by stage; they count in steps and sim_time_s.
      // First steps as they come (most reuse the neighbour list), then steps forced to
      // rebuild it, whose grid and list stages show what a rebuild costs.
      for (const auto& [stage, ms] : sim.profileStep(static_cast<int>(profileSteps))) stageMs[stage] = ms;
      for (const auto& [stage, ms] : sim.profileStep(static_cast<int>(profileSteps), true)) rebuildMs[stage] = ms;
    }
    summary = {{"scene", scene.name},
               {"device", ctx.info().name},
               {"driver", ctx.driver()},
               {"host_cpu", hemo::cli::hostCpu()},
               {"fluid_particles", sim.fluidParticles()},
               {"boundary_particles", sim.boundaryParticles()},
               {"wall_particles", sim.wallParticles()},
               {"springs", sim.springs()},
               {"broken_springs", sim.brokenSprings()},
               {"detached_particles", sim.detachedParticles()},
               {"escaped_particles", sim.escapedParticles()},
               {"lost_particles", sim.lostParticles()},
               {"steps", sim.steps()},
               {"neighbour_rebuilds", rebuilds},
               // commands the solver recorded per step (a step's latency on a GPU at small N)
               {"dispatches_per_step", sim.dispatchesPerStep()},
               {"barriers_per_step", sim.barriersPerStep()},
               {"sim_time_s", sim.time()},
               {"wall_time_s", wall},
               {"steps_per_s", wall > 0 ? double(result.steps) / wall : 0.0},
               // fluid particles times steps per wall second: throughput across scene sizes
               {"fluid_particle_steps_per_s", wall > 0 ? double(result.steps) * sim.fluidParticles() / wall : 0.0},
               // simulated seconds per wall-clock second of the run (1: keeps up with the clock)
               {"real_time_factor", wall > 0 ? result.simTime / wall : 0.0},
               // the most device memory hemo's buffers held (device-local heaps), and per particle
               {"gpu_memory_bytes", ctx.peakDeviceMemoryBytes()},
               // how the pair passes found neighbours: "list", or "cells" (no list)
               {"neighbour_search", sim.solver().walksCells() ? "cells" : "list"},
               {"bytes_per_particle", double(ctx.peakDeviceMemoryBytes()) /
                                          std::max(1u, sim.fluidParticles() + sim.boundaryParticles() + sim.wallParticles())},
               {"finite", finite}};
    summary["solver"] = sim.solver().solvesPressure() ? "dfsph" : "wcsph";
    if (sim.openEnds()) {
      // Open ends: the lumen's mass balance (kg), from the GPU's crossing counts.
      const auto o = sim.openCounts();
      const double m = scene.sph.particleMass();
      summary["open_fluid_particles_now"] = sim.activeFluidParticles();
      summary["open_mass_in_kg"] = m * (double(o.in) - double(o.inBack));
      summary["open_mass_out_kg"] = m * (double(o.out) - double(o.outBack));
      summary["open_particles_parked"] = o.parkedEnd + o.parkedStart;
      summary["open_particles_spawned"] = o.spawned;
      nlohmann::json outlets = nlohmann::json::array();  // (each outlet's, in the scene's order)
      for (std::size_t e = 1; e < o.ends.size(); ++e) outlets.push_back(m * (double(o.ends[e].enter) - double(o.ends[e].leave)));
      summary["open_outlet_mass_out_kg"] = outlets;
    }
    if (!scene.tools.empty()) {
      summary["tools_file"] = "tools.csv";
      nlohmann::json names = nlohmann::json::array();
      for (const auto& t : scene.tools) names.push_back(t.name);
      summary["tools"] = names;
      // the force signal: steps delivered per wall second, batches (host updates) per second,
      // and the mean and longest time from a batch's submission to its rows in host memory
      const hemo::sim::ToolFeedback& f = sim.toolFeedback();
      if (f.batches > 0 && f.seconds > 0.0) {
        summary["tool_feedback_rate_hz"] = double(f.samples) / f.seconds;
        summary["tool_feedback_updates_hz"] = double(f.batches) / f.seconds;
        summary["tool_feedback_latency_ms"] = 1e3 * f.latencySeconds / double(f.batches);
        summary["tool_feedback_latency_max_ms"] = 1e3 * f.maxLatency;
      }
    }
    if (const auto* springs = sim.solver().wall()) {
      summary["wall_substeps"] = springs->substeps();
      summary["wall_step_limit_s"] = springs->springTimeStepLimit() * springs->substeps();
    }
    if (sim.solver().solvesPressure()) {
      // what the pressure solves did (sph/dfsph_reduce.comp's counts, this run and its resumed part)
      // the density solve's, and the divergence solve's as solver_divergence_*
      const hemo::sim::PressureSolveStats st = sim.solver().readPressureSolveStats();
      const hemo::sim::PressureSolveStats div = sim.solver().readPressureSolveStats(true);
      summary["solver_tolerance"] = scene.sph.solverTolerance;
      summary["solver_compressible"] = scene.sph.solverCompressible;
      summary["solver_max_iterations"] = scene.sph.solverMaxIterations;
      summary["solver_iterations_mean"] = st.meanIterations();
      summary["solver_iterations_max"] = st.maxIterations;
      summary["solver_cap_hits"] = st.capHits;
      summary["solver_final_error_max"] = st.worstError;
      summary["solver_divergence_iterations_mean"] = div.meanIterations();
      summary["solver_divergence_iterations_max"] = div.maxIterations;
      summary["solver_divergence_cap_hits"] = div.capHits;
      summary["solver_recorded_iterations_per_step"] = sim.recordedSolveIterationsPerStep();
      summary["solver_redone_batches"] = sim.redoneBatches();
      for (const auto& [name, s] : {std::pair{"pressure", st}, std::pair{"divergence", div}}) {
        if (s.capHits == 0) continue;
        std::cerr << "hemo-run: warning: in " << s.capHits << " of " << s.solves << " steps the " << name
                  << " solve stopped at its cap of " << scene.sph.solverMaxIterations << " iterations above the tolerance "
                  << scene.sph.solverTolerance << " (largest mean error left: " << s.worstError
                  << "; raise fluid.solver_max_iterations or lower time.cfl_acoustic)\n";
      }
    }
    if (rupture) summary["rupture_pressure_estimate_Pa"] = rupture->pressure;
    if (resumed) summary["resumed_from_step"] = firstStep;
    if (checkpointWritten) {
      summary["checkpoint_file"] = (out / "checkpoint.hemo").string();
      summary["checkpoint_step"] = checkpointStep;
    }
    if (profileSteps > 0) {
      summary["stage_ms"] = stageMs;
      summary["rebuild_stage_ms"] = rebuildMs;
    }
    if (pngFiles > 0) summary["png_files"] = pngFiles;
    if (vtkFiles > 0) summary["vtk_files"] = vtkFiles;
    if (surfaceFiles > 0) {
      summary["surface_files"] = surfaceFiles;
      summary["surface_triangles"] = lastSurface.triangles;
    }
    if (!finite) summary["error"] = failure;
    if (hemo::cli::validationProblems(ctx, "hemo-run")) return 3;
  } catch (const hemo::scene::SceneError& e) {
    std::cerr << "hemo-run: " << e.what() << "\n";
    return 1;
  } catch (const hemo::io::CheckpointError& e) {
    std::cerr << "hemo-run: " << e.what() << "\n";
    return 1;
  } catch (const hemo::gpu::OutOfDeviceMemory& e) {
    std::cerr << "hemo-run: the scene does not fit the device: " << e.what() << "\n";
    return 3;
  } catch (const hemo::gpu::GpuError& e) {
    std::cerr << "hemo-run: GPU error: " << e.what() << "\n";
    return 3;
  } catch (const hemo::io::WriteError& e) {  // an output that cannot be written (a full disk...)
    std::cerr << "hemo-run: " << e.what() << "\n";
    return 4;
  } catch (const std::exception& e) {
    std::cerr << "hemo-run: " << e.what() << "\n";
    return 1;
  }

  try {
    hemo::io::AtomicFile file(out / "summary.json");
    file.stream() << summary.dump(2) << "\n";
    file.commit();
  } catch (const hemo::io::WriteError& e) {
    std::cerr << "hemo-run: " << e.what() << "\n";
    return 4;
  }
  std::printf("%s\n", summary.dump(2).c_str());
  if (code == 2) std::cerr << "hemo-run: " << failure << "\n";
  return code;
}
