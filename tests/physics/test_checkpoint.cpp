// Checkpoints (hemo/io/checkpoint.hpp, sim::Simulation::writeCheckpoint and resume): a run
// resumed from a checkpoint in a freshly built simulation is bit for bit the uninterrupted
// run at every later point compared, on each path whose state differs (cluster lists, SPS with
// continuity density and RK2, the cell walk, the wall with its inflow, the list in pages); a
// simulation can be rewound to a checkpoint it wrote; and a checkpoint of another scene,
// device or build is refused before anything changes.
#include "file_bytes.hpp"
#include "gpu_test.hpp"
#include "run_state.hpp"

#include "hemo/io/checkpoint.hpp"
#include "hemo/scene/scene.hpp"
#include "hemo/sim/simulation.hpp"

#include <cstring>
#include <filesystem>
#include <fstream>
#include <optional>
#include <random>

#include <unistd.h>

namespace hemo::test {
namespace {

namespace fs = std::filesystem;

class CheckpointTest : public GpuTest {
 protected:
  void SetUp() override {
    GpuTest::SetUp();
    dir_ = fs::temp_directory_path() / ("hemo-checkpoint-" + std::to_string(::getpid()));
    fs::create_directories(dir_);
  }
  void TearDown() override {
    std::error_code ignored;
    fs::remove_all(dir_, ignored);
    GpuTest::TearDown();
  }
  fs::path dir_;
};

scene::Scene shipped(const char* name) { return scene::loadScene(std::string(HEMO_SOURCE_DIR) + "/scenes/" + name); }

struct State {
  std::vector<glm::vec4> particles;
  double time;
  std::uint64_t steps;
  std::uint32_t rebuilds, broken;
};

State stateOf(sim::Simulation& sim) {
  return State{positionsAndVelocities(sim), sim.time(), sim.steps(), sim.solver().readRebuilds(), sim.brokenSprings()};
}

void run(sim::Simulation& sim, std::uint64_t steps) {
  sim::RunOptions opt;
  opt.steps = steps;
  sim.run(opt);
}

void expectSame(const State& a, const State& b, const char* what) {
  SCOPED_TRACE(what);
  EXPECT_EQ(a.steps, b.steps);
  EXPECT_EQ(a.time, b.time);
  EXPECT_EQ(a.rebuilds, b.rebuilds);
  EXPECT_EQ(a.broken, b.broken);
  ASSERT_EQ(a.particles.size(), b.particles.size());
  EXPECT_EQ(0, std::memcmp(a.particles.data(), b.particles.data(), a.particles.size() * sizeof(glm::vec4)))
      << "the resumed run's particles differ from the uninterrupted run's";
}

std::string refusal(sim::Simulation& sim, const fs::path& path) {
  try {
    sim.resume(path);
  } catch (const io::CheckpointError& e) {
    return e.what();
  }
  return "(resumed without an error)";
}

TEST_F(CheckpointTest, ResumedRunIsBitIdenticalToTheUninterruptedOne) {
  struct Case {
    const char* name;
    scene::Scene scene;
    std::uint64_t before, after;  // steps to the checkpoint (odd: the clock's other record), then twice `after`
    std::optional<gpu::LimitOverrides> limits;
  };
  std::vector<Case> cases;
  {
    scene::Scene s = shipped("dam_break.json");
    s.sph.listSkin = 0.01f;  // a thin skin: the list is rebuilt after the checkpoint too
    cases.push_back({"dam break (lists as the device prefers)", s, 41, 30, {}});
    s.sph.listLayout = sim::ListLayout::Contiguous;
    s.sph.sps = true;
    s.sph.densityMethod = sim::DensityMethod::Continuity;
    s.sph.integrator = sim::Integrator::Rk2Midpoint;
    cases.push_back({"dam break, SPS, continuity density, RK2", s, 31, 20, {}});
    s = shipped("dam_break.json");
    s.sph.listSkin = 0.01f;
    s.sph.neighbourSearch = sim::NeighbourSearch::Cells;
    cases.push_back({"dam break walking cells", s, 41, 30, {}});
    // (the solves' stiffnesses, stats and gate; a list rebuilt every step or two, so a rebuild
    // is pending at the checkpoint)
    cases.push_back({"dam break, DFSPH", shipped("dam_break_dfsph.json"), 21, 15, {}});
  }
  {
    scene::Scene s = shipped("aneurysm.json");
    s.sph.listSkin = 0.01f;
    cases.push_back({"aneurysm (wall, inflow)", s, 61, 60, {}});
    s.sph.listLayout = sim::ListLayout::Contiguous;
    gpu::LimitOverrides pages;
    pages.maxStorageBufferRange = 2048 * s.sph.neighbourCapacity * 4 + 4096;
    cases.push_back({"aneurysm, list in pages", s, 61, 40, pages});
    // (the wall's share of the solve, and its substeps with the force they hold)
    s = shipped("aneurysm.json");
    s.sph.pressureSolver = sim::PressureSolver::Dfsph;
    s.sph.solverMaxIterations = 10;
    s.sph.listLayout = sim::ListLayout::Contiguous;
    s.vessel->substeps = 4;
    cases.push_back({"aneurysm, DFSPH, the wall in 4 substeps", s, 21, 15, {}});
  }
  for (const Case& c : cases) {
    SCOPED_TRACE(c.name);
    std::unique_ptr<gpu::Context> own;
    if (c.limits) {
      gpu::ContextOptions options;
      options.validation = true;
      options.limits = *c.limits;
      own = std::make_unique<gpu::Context>(options);
    }
    gpu::Context& context = own ? *own : ctx();
    // Uninterrupted, compared after `after` and 2 `after` steps past the checkpoint's.
    sim::Simulation whole(context, c.scene);
    if (c.limits) {
      EXPECT_GE(whole.solver().listPages(), 3u);
    }
    run(whole, c.before + c.after);
    const State first = stateOf(whole);
    run(whole, c.after);
    const State second = stateOf(whole);
    // Interrupted: a run to the checkpoint, and one built afresh that resumes from it.
    const fs::path file = dir_ / "run.hemo";
    std::uint32_t rebuildsBefore = 0;
    {
      sim::Simulation writer(context, c.scene);
      run(writer, c.before);
      writer.writeCheckpoint(file);
      rebuildsBefore = writer.solver().readRebuilds();
    }
    sim::Simulation resumed(context, c.scene);
    resumed.resume(file);
    EXPECT_EQ(resumed.steps(), c.before);
    run(resumed, c.after);
    expectSame(first, stateOf(resumed), "first comparison");
    run(resumed, c.after);
    expectSame(second, stateOf(resumed), "second comparison");
    // The same simulation rewound to the checkpoint runs the same steps again.
    resumed.resume(file);
    run(resumed, c.after);
    expectSame(first, stateOf(resumed), "after rewinding");
    EXPECT_GT(second.rebuilds, rebuildsBefore) << "the list was rebuilt after the checkpoint";
    std::printf("%s: %u rebuilds to the checkpoint, %u in all\n", c.name, rebuildsBefore, second.rebuilds);
    if (own) {
      for (const auto& m : own->takeValidationMessages()) ADD_FAILURE() << m;
    }
  }
}

// A checkpoint of another scene (or of this one with other settings), of another device or of
// another build's buffers is refused with a CheckpointError naming it, and leaves the
// simulation as it was: its run is then that of a simulation never asked to resume.
TEST_F(CheckpointTest, ForeignCheckpointsAreRefusedAndLeaveTheSimulationAsItWas) {
  const scene::Scene tiny = scene::loadScene(std::string(HEMO_SOURCE_DIR) + "/tests/cli/tiny_tank.json");
  const fs::path file = dir_ / "tiny.hemo", edited = dir_ / "edited.hemo";
  State reference;
  {
    sim::Simulation writer(ctx(), tiny);
    run(writer, 10);
    writer.writeCheckpoint(file);
    run(writer, 10);
    reference = stateOf(writer);
  }
  auto expectRefused = [&](sim::Simulation& sim, const fs::path& path, const std::string& words) {
    const std::string message = refusal(sim, path);
    EXPECT_NE(message.find("checkpoint '" + path.string() + "'"), std::string::npos) << message;
    EXPECT_NE(message.find(words), std::string::npos) << "expected '" << words << "' in: " << message;
  };
  {
    scene::Scene thicker = tiny;
    thicker.sph.viscosity *= 2.0f;
    sim::Simulation sim(ctx(), thicker);
    expectRefused(sim, file, "was written for scene 'tiny_tank' as it was then: the particles, springs or settings");
  }
  {
    sim::Simulation sim(ctx(), shipped("dam_break.json"));
    expectRefused(sim, file, "was written for scene 'tiny_tank': the particles, springs or settings of scene 'dam_break'");
  }
  {
    scene::Scene batches = tiny;
    batches.stepsPerBatch = 7;  // its step log is of another size
    sim::Simulation sim(ctx(), batches);
    expectRefused(sim, file, "does not fit this simulation's buffers");
  }
  sim::Simulation sim(ctx(), tiny);
  {  // the device's name changed (a deliberate edit: the checksum matches)
    std::vector<char> bytes = readAll(file);
    const std::string name = ctx().info().name;
    auto at = std::search(bytes.begin(), bytes.end(), name.begin(), name.end());
    ASSERT_NE(at, bytes.end());
    *at = *at == 'X' ? 'Y' : 'X';
    reseal(bytes);
    writeAll(edited, bytes);
    expectRefused(sim, edited, "a checkpoint resumes on the device and driver that wrote it");
  }
  {  // damaged
    std::vector<char> bytes = readAll(file);
    bytes[bytes.size() / 2] ^= 1;
    writeAll(edited, bytes);
    expectRefused(sim, edited, "is damaged: its checksum does not match");
    bytes.resize(bytes.size() / 3);
    writeAll(edited, bytes);
    expectRefused(sim, edited, "is truncated");
  }
  run(sim, 20);
  expectSame(reference, stateOf(sim), "the simulation that refused them");
  // ... and the checkpoint itself resumes.
  sim.resume(file);
  run(sim, 10);
  expectSame(reference, stateOf(sim), "resumed");
}

// Mutants of a checkpoint's header and record table with the checksum made to match again (a
// damaged file is refused by its checksum alone): each resumes or is refused with a
// CheckpointError, never another exception or a crash. The seed is fixed.
TEST_F(CheckpointTest, EditedHeadersResumeOrAreRefusedWithACheckpointError) {
  const scene::Scene tiny = scene::loadScene(std::string(HEMO_SOURCE_DIR) + "/tests/cli/tiny_tank.json");
  const fs::path file = dir_ / "tiny.hemo", mutant = dir_ / "mutant.hemo";
  sim::Simulation sim(ctx(), tiny);
  run(sim, 5);
  sim.writeCheckpoint(file);
  const std::vector<char> original = readAll(file);
  std::mt19937 rng(1128);
  int resumed = 0, refused = 0;
  for (int m = 0; m < 120; ++m) {
    std::vector<char> bytes = original;
    for (int e = std::uniform_int_distribution<int>(1, 3)(rng); e > 0; --e) {
      const std::size_t at = std::uniform_int_distribution<std::size_t>(0, 400)(rng);
      bytes[at] = static_cast<char>(bytes[at] ^ (1 << std::uniform_int_distribution<int>(0, 7)(rng)));
    }
    reseal(bytes);
    writeAll(mutant, bytes);
    try {
      sim.resume(mutant);
      ++resumed;
    } catch (const io::CheckpointError& e) {
      ASSERT_NE(std::string(e.what()).find(mutant.string()), std::string::npos) << e.what();
      ++refused;
    } catch (const std::exception& e) {
      FAIL() << "mutant " << m << " threw something other than a CheckpointError: " << e.what();
    }
  }
  EXPECT_GT(refused, 60);
  std::printf("120 edited headers: %d resumed, %d refused\n", resumed, refused);
}

}  // namespace
}  // namespace hemo::test
