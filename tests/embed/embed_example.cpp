// An application that embeds hemo: opens a Vulkan device, loads a scene, advances it in
// batches of its own choosing, reads the particles back between batches and extracts the
// blood surface once at the end. docs/embedding.md walks through it.
//
//   embed_example SCENE.json STEPS
#include <hemo/gpu/context.hpp>
#include <hemo/scene/scene.hpp>
#include <hemo/sim/simulation.hpp>
#include <hemo/surface/marching_cubes.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <limits>
#include <string>

int main(int argc, char** argv) {
  if (argc != 3) {
    std::fprintf(stderr, "usage: embed_example SCENE.json STEPS\n");
    return 1;
  }
  char* end = nullptr;
  const long steps = std::strtol(argv[2], &end, 10);
  if (end == argv[2] || *end != '\0' || steps <= 0) {
    std::fprintf(stderr, "embed_example: STEPS must be a positive whole number, got '%s'\n", argv[2]);
    return 1;
  }
  try {
    // HEMO_DEVICE picks the device and HEMO_VALIDATION=1 turns the validation layer on, as
    // for hemo's own programs; both may also be set here in ContextOptions.
    hemo::gpu::Context context;
    const hemo::scene::Scene scene = hemo::scene::loadScene(argv[1]);
    hemo::sim::Simulation sim(context, scene);
    std::printf("device %s; scene %s: %u fluid, %u boundary, %u wall particles\n", context.info().name.c_str(),
                scene.name.c_str(), sim.fluidParticles(), sim.boundaryParticles(), sim.wallParticles());

    // Two batches with a look at the fluid in between: the application decides when to read
    // back; within a run the host never waits for the GPU.
    hemo::sim::RunOptions options;
    options.steps = static_cast<std::uint64_t>(steps / 2);
    for (int batch = 0; batch < 2; ++batch) {
      if (batch == 1) options.steps = static_cast<std::uint64_t>(steps - steps / 2);
      sim.run(options);
      const hemo::sim::Snapshot snap = sim.snapshot();
      float lowest = std::numeric_limits<float>::max(), fastest = 0.0f;
      for (std::uint32_t i = 0; i < sim.fluidParticles(); ++i) {
        lowest = std::min(lowest, snap.positions[i].z);
        const glm::vec4& v = snap.velocities[i];
        fastest = std::max(fastest, std::sqrt(v.x * v.x + v.y * v.y + v.z * v.z));
      }
      std::printf("after %llu steps, t = %.6f s: lowest fluid z %.5f m, fastest %.4f m/s\n",
                  static_cast<unsigned long long>(sim.steps()), sim.time(), lowest, fastest);
    }

    // The blood surface, built on first use (a run nobody looks at never builds one).
    const hemo::surface::SurfaceMesh mesh = sim.extractSurface();
    std::printf("surface: %u triangles\n", mesh.totals.triangles);

    if (context.validationEnabled() && context.validationMessageCount() > 0) {
      for (const std::string& m : context.takeValidationMessages()) std::fprintf(stderr, "%s\n", m.c_str());
      return 3;
    }
  } catch (const hemo::scene::SceneError& e) {  // the message names the file and field
    std::fprintf(stderr, "embed_example: %s\n", e.what());
    return 1;
  } catch (const hemo::sim::SimulationError& e) {  // non-finite state: step, time, particle
    std::fprintf(stderr, "embed_example: %s\n", e.what());
    return 2;
  } catch (const std::exception& e) {  // no usable device, or a device error
    std::fprintf(stderr, "embed_example: %s\n", e.what());
    return 3;
  }
  return 0;
}
