// Scenes of a million particles and more: the path a large scene takes (the neighbour list in
// pages where one buffer would pass a binding limit, cell walks where the device's memory would
// not hold the list, the device memory hemo holds) on whatever device runs the suite.
#include "gpu_test.hpp"
#include "run_state.hpp"
#include "hemo/gpu/context.hpp"
#include "hemo/scene/scene.hpp"
#include "hemo/sim/simulation.hpp"

#include <glm/vec4.hpp>

#include <cmath>
#include <cstring>
#include <string>
#include <vector>

namespace hemo::test {
namespace {

class ScaleTest : public GpuTest {};

// A 3D dam break of 1.06M particles (SPHERIC benchmark 2's column, 0.787M fluid, in a tank of
// three layers of boundary particles; the geometry of hemo-bench scale), h/dp = 1.3.
constexpr const char* kMillion = R"({
  "scene": "dam_break_3d_1m",
  "particles": { "spacing_m": 0.0095, "smoothing_ratio": 1.3, "list_skin": 0.1, "neighbour_capacity": 136 },
  "fluid": { "density_kg_m3": 1000.0, "viscosity_pa_s": 0.001, "expected_max_speed_m_s": 3.5,
             "blocks": [ { "min_m": [0.0, 0.0, 0.0], "max_m": [1.228, 1.0, 0.55] } ] },
  "boundary": { "tanks": [ { "min_m": [0.0, 0.0, 0.0], "max_m": [3.22, 1.0, 0.6], "layers": 3, "open_top": true } ] },
  "forces": { "gravity_m_s2": [0.0, 0.0, -9.81] },
  "time": { "integrator": "symplectic_euler", "cfl_acoustic": 0.3, "max_dt_s": 0.0005, "steps_per_batch": 4 },
  "domain": { "min_m": [-0.1, -0.1, -0.1], "max_m": [3.32, 1.1, 1.0] }
})";

// The scene above at another particle spacing (m).
std::string damBreak3d(const char* spacing) {
  std::string text = kMillion;
  const std::string from = "\"spacing_m\": 0.0095";
  text.replace(text.find(from), from.size(), std::string("\"spacing_m\": ") + spacing);
  return text;
}

// A million particles run a few steps, finite and all inside the domain, their list in pages
// where the device's buffer limits ask for it (lavapipe: 128 MiB a storage buffer, so about
// eight pages), and a rerun is bit-identical. hemo's device memory stays within the device's.
TEST_F(ScaleTest, MillionParticleRunIsBitIdenticalWhenRerun) {
  const scene::Scene scene = scene::parseScene(kMillion, "scale test");
  auto run = [&]() {
    sim::Simulation sim(ctx(), scene);
    const std::uint64_t total = std::uint64_t(sim.fluidParticles()) + sim.boundaryParticles();
    EXPECT_GE(total, 1000000u);
    const std::uint64_t listBytes = total * scene.sph.neighbourCapacity * 4;
    if (listBytes > ctx().limits().maxStorageBufferRange) {
      EXPECT_GT(sim.solver().listPages(), 1u) << listBytes << " bytes of list";
    }
    EXPECT_LE(ctx().deviceMemoryBytes(), ctx().deviceMemoryCapacity());
    sim::RunOptions opt;
    opt.steps = 4;
    sim.run(opt);
    EXPECT_EQ(sim.lostParticles(), 0u);
    EXPECT_EQ(sim.escapedParticles(), 0u);
    EXPECT_GT(sim.time(), 0.0);
    return positionsAndVelocities(sim);
  };
  const auto first = run();
  const auto second = run();
  ASSERT_EQ(first.size(), second.size());
  for (const glm::vec4& v : first) {
    ASSERT_TRUE(std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z));
  }
  EXPECT_EQ(0, std::memcmp(first.data(), second.data(), first.size() * sizeof(glm::vec4))) << "the rerun differs";
}

// The same dam break at 4.2M particles (dp = 5.8 mm) runs a few steps, finite and all inside
// the domain, within the device's memory: on a device whose memory would not hold its
// neighbour list (lavapipe: 2 GiB, where the list alone takes 4.6 GiB) the passes walk the
// grid's cells instead, at about 300 bytes a particle.
TEST_F(ScaleTest, FourMillionParticlesRunWithinTheDeviceMemory) {
  const scene::Scene scene = scene::parseScene(damBreak3d("0.0058"), "scale test");
  ASSERT_EQ(scene.sph.neighbourSearch, sim::NeighbourSearch::Auto);
  const std::uint64_t before = ctx().deviceMemoryBytes();
  sim::Simulation sim(ctx(), scene);
  const std::uint64_t total = std::uint64_t(sim.fluidParticles()) + sim.boundaryParticles();
  EXPECT_GE(total, 4000000u);
  const std::uint64_t listBytes = total * scene.sph.neighbourCapacity * 8;  // the list and the pairs
  if (listBytes > ctx().deviceMemoryCapacity()) {
    EXPECT_TRUE(sim.solver().walksCells()) << listBytes << " bytes of lists";
  }
  const std::uint64_t takes = ctx().deviceMemoryBytes() - before;
  EXPECT_LE(ctx().deviceMemoryBytes(), ctx().deviceMemoryCapacity());
  if (sim.solver().walksCells()) {
    EXPECT_LT(takes, total * 400) << double(takes) / double(total) << " bytes a particle";
  }
  sim::RunOptions opt;
  opt.steps = 3;
  sim.run(opt);
  EXPECT_EQ(sim.lostParticles(), 0u);
  EXPECT_EQ(sim.escapedParticles(), 0u);
  EXPECT_GT(sim.time(), 0.0);
  const auto s = sim.snapshot();
  for (std::size_t i = 0; i < s.positions.size(); ++i) {
    ASSERT_TRUE(std::isfinite(s.positions[i].x) && std::isfinite(s.positions[i].y) && std::isfinite(s.positions[i].z) &&
                std::isfinite(s.velocities[i].x) && std::isfinite(s.velocities[i].y) && std::isfinite(s.velocities[i].z))
        << "particle " << i;
  }
}

// On a device whose memory holds the dam break but not its neighbour list, NeighbourSearch::Auto
// walks cells, and the run is bit-identical to the list's on a device that holds both.
TEST_F(ScaleTest, AutoWalksCellsWhereTheListWouldNotFit) {
  scene::Scene scene = scene::loadScene(std::string(HEMO_SOURCE_DIR) + "/scenes/dam_break.json");
  scene.sph.listLayout = sim::ListLayout::Contiguous;
  const std::uint64_t before = ctx().deviceMemoryBytes();
  std::uint64_t takes = 0;
  auto run = [&](gpu::Context& context, bool cells) {
    sim::Simulation sim(context, scene);
    EXPECT_EQ(sim.solver().walksCells(), cells);
    if (&context == &ctx()) takes = ctx().deviceMemoryBytes() - before;
    sim::RunOptions opt;
    opt.steps = 60;
    sim.run(opt);
    return positionsAndVelocities(sim);
  };
  const auto list = run(ctx(), false);
  gpu::ContextOptions options;
  options.validation = true;
  options.limits.deviceMemoryBytes = takes / 2;  // the list is most of it
  gpu::Context small(options);
  const auto cells = run(small, true);
  ASSERT_EQ(list.size(), cells.size());
  EXPECT_EQ(0, std::memcmp(list.data(), cells.data(), list.size() * sizeof(glm::vec4)));
  for (const auto& m : small.takeValidationMessages()) ADD_FAILURE() << m;
}

// A scene that asks for the neighbour list, on a device whose memory holds three quarters of
// what the dam break needs with it (capped), is refused before its largest buffers are
// allocated, naming the lists and the memory the whole scene needs, within a few percent of
// what it takes on a device that holds it.
TEST_F(ScaleTest, SceneBeyondTheDeviceMemoryIsRefusedWithWhatItNeeds) {
  scene::Scene scene = scene::loadScene(std::string(HEMO_SOURCE_DIR) + "/scenes/dam_break.json");
  scene.sph.neighbourSearch = sim::NeighbourSearch::List;  // (Auto would walk cells)
  const std::uint64_t before = ctx().deviceMemoryBytes();
  std::uint64_t takes = 0;
  {
    sim::Simulation sim(ctx(), scene);
    takes = ctx().deviceMemoryBytes() - before;
  }
  gpu::ContextOptions options;
  options.validation = true;
  options.limits.deviceMemoryBytes = takes * 3 / 4;
  gpu::Context small(options);
  std::string message;
  std::uint64_t needed = 0;
  try {
    sim::Simulation sim(small, scene);
    ADD_FAILURE() << "expected the scene to be refused";
  } catch (const gpu::OutOfDeviceMemory& e) {
    message = e.what();
    needed = e.needed;
  }
  EXPECT_NE(message.find("the neighbour list and the interacting pairs of"), std::string::npos) << message;
  EXPECT_NE(message.find("the scene needs about"), std::string::npos) << message;
  EXPECT_LE(needed, takes);
  EXPECT_GE(double(needed), 0.97 * double(takes)) << "needs " << needed << " of the " << takes << " bytes it takes";
  EXPECT_EQ(small.deviceMemoryBytes(), 0u) << "everything the refused scene took is given back";
  for (const auto& m : small.takeValidationMessages()) ADD_FAILURE() << m;
}

}  // namespace
}  // namespace hemo::test
