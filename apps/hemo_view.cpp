// hemo-view SCENE.json [--device SEL] [--size WxH] [--steps-per-frame K] [--frames N]
// Runs a scene live in a window: the simulation advances K steps per frame (one submit, one
// wait per frame), then the blood surface is extracted and everything is drawn offscreen and
// presented. Mouse: drag to orbit, wheel to zoom. Keys: Space pause, N one frame's steps while
// paused, S surface, P fluid particles, W wall, L springs as lines, B rigid boundary,
// C cutaway, Esc/Q quit.
// --frames N quits after N presented frames (CI runs it under Xvfb) and prints a summary.
// Exit codes as hemo-run: 0 ok, 1 bad input, 2 the simulation failed, 3 no display/device.
#include "cli.hpp"
#include "hemo/render/renderer.hpp"
#include "hemo/render/swapchain.hpp"
#include "hemo/scene/scene.hpp"
#include "hemo/sim/simulation.hpp"

#define GLFW_INCLUDE_VULKAN
#include <GLFW/glfw3.h>

#include <glm/geometric.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <memory>
#include <tuple>

namespace {

const char* kUsage =
    "usage: hemo-view SCENE.json [--device SEL] [--size WxH] [--steps-per-frame K] [--frames N]\n"
    "  --size WxH          window size (default 1280x720)\n"
    "  --steps-per-frame K simulation steps between frames (default 8)\n"
    "  --frames N          quit after N presented frames (default: run until closed)\n"
    "mouse: drag to orbit, wheel to zoom; keys: Space pause, N step, S surface, P particles,\n"
    "W wall, L springs, B boundary, C cutaway, Esc/Q quit\n"
    "hemo-view --help prints this text\n";

struct ViewState {
  bool paused = false;
  bool stepOnce = false;
  bool surface = true;
  bool quit = false;
  hemo::render::FrameOptions frame;
  float yaw = -1.5708f, pitch = 0.42f, distance = 1.0f;  // orbit around the target (rad, rad, m)
  bool dragging = false;
  double lastX = 0.0, lastY = 0.0;
};

void onKey(GLFWwindow* window, int key, int, int action, int) {
  if (action != GLFW_PRESS) return;
  auto* s = static_cast<ViewState*>(glfwGetWindowUserPointer(window));
  switch (key) {
    case GLFW_KEY_SPACE: s->paused = !s->paused; break;
    case GLFW_KEY_N: s->stepOnce = true; break;
    case GLFW_KEY_S: s->surface = !s->surface; break;
    case GLFW_KEY_P: s->frame.fluid = !s->frame.fluid; break;
    case GLFW_KEY_W: s->frame.wall = !s->frame.wall; break;
    case GLFW_KEY_B: s->frame.boundary = !s->frame.boundary; break;
    case GLFW_KEY_C: s->frame.cutaway = !s->frame.cutaway; break;
    case GLFW_KEY_L: s->frame.springs = !s->frame.springs; break;
    case GLFW_KEY_ESCAPE:
    case GLFW_KEY_Q: s->quit = true; break;
    default: break;
  }
}

void onButton(GLFWwindow* window, int button, int action, int) {
  auto* s = static_cast<ViewState*>(glfwGetWindowUserPointer(window));
  if (button == GLFW_MOUSE_BUTTON_LEFT) {
    s->dragging = action == GLFW_PRESS;
    glfwGetCursorPos(window, &s->lastX, &s->lastY);
  }
}

void onCursor(GLFWwindow* window, double x, double y) {
  auto* s = static_cast<ViewState*>(glfwGetWindowUserPointer(window));
  if (!s->dragging) return;
  s->yaw -= float(x - s->lastX) * 0.008f;
  s->pitch = std::clamp(s->pitch + float(y - s->lastY) * 0.008f, -1.5f, 1.5f);
  s->lastX = x;
  s->lastY = y;
}

void onScroll(GLFWwindow* window, double, double dy) {
  auto* s = static_cast<ViewState*>(glfwGetWindowUserPointer(window));
  s->distance *= std::pow(0.9f, float(dy));
}

struct Glfw {
  Glfw() : ok(glfwInit() == GLFW_TRUE) {}
  ~Glfw() {
    if (ok) glfwTerminate();
  }
  bool ok;
};

}  // namespace

int main(int argc, char** argv) {
  if (hemo::cli::printUsageIfAsked(argc, argv, kUsage)) return 0;
  hemo::cli::Args args;
  std::uint32_t width = 1280, height = 720, stepsPerFrame = 8;
  std::uint64_t maxFrames = 0;
  hemo::scene::Scene scene;
  try {
    args = hemo::cli::parse(argc, argv, {"--device", "--size", "--steps-per-frame", "--frames"});
    if (args.positional.size() != 1) throw hemo::cli::UsageError("expected exactly one SCENE.json");
    std::tie(width, height) = args.size("--size", {1280, 720});
    stepsPerFrame = static_cast<std::uint32_t>(args.count("--steps-per-frame", 8, 0, 100000));
    maxFrames = args.count("--frames", 0, 1, 1000000000);
    scene = hemo::scene::loadScene(args.positional[0]);
  } catch (const hemo::cli::UsageError& e) {
    std::cerr << "hemo-view: " << e.what() << "\n" << kUsage;
    return 1;
  } catch (const hemo::scene::SceneError& e) {
    std::cerr << "hemo-view: " << e.what() << "\n";
    return 1;
  }

  Glfw glfw;
  if (!glfw.ok) {
    std::cerr << "hemo-view: cannot open a window (no display? run under xvfb-run for a virtual one)\n";
    return 3;
  }
  if (!glfwVulkanSupported()) {
    std::cerr << "hemo-view: GLFW finds no Vulkan loader for windows\n";
    return 3;
  }
  glfwWindowHint(GLFW_CLIENT_API, GLFW_NO_API);
  glfwWindowHint(GLFW_RESIZABLE, GLFW_FALSE);
  GLFWwindow* window = glfwCreateWindow(int(width), int(height), ("hemo-view: " + scene.name).c_str(), nullptr, nullptr);
  if (!window) {
    std::cerr << "hemo-view: cannot create a window\n";
    return 3;
  }
  ViewState state;
  glfwSetWindowUserPointer(window, &state);
  glfwSetKeyCallback(window, onKey);
  glfwSetMouseButtonCallback(window, onButton);
  glfwSetCursorPosCallback(window, onCursor);
  glfwSetScrollCallback(window, onScroll);

  int code = 0;
  try {
    hemo::gpu::ContextOptions options;
    options.device = args.text("--device");
    std::uint32_t extensionCount = 0;
    const char** extensions = glfwGetRequiredInstanceExtensions(&extensionCount);
    for (std::uint32_t i = 0; i < extensionCount; ++i) options.instanceExtensions.emplace_back(extensions[i]);
    options.createSurface = [window](VkInstance instance) {
      VkSurfaceKHR surface = VK_NULL_HANDLE;
      return glfwCreateWindowSurface(instance, window, nullptr, &surface) == VK_SUCCESS ? surface : VK_NULL_HANDLE;
    };
    hemo::gpu::Context ctx(options);
    hemo::sim::Simulation sim(ctx, scene);
    std::fprintf(stderr, "hemo-view: %s on %s: %u fluid + %u boundary + %u wall particles\n", scene.name.c_str(),
                 ctx.info().name.c_str(), sim.fluidParticles(), sim.boundaryParticles(), sim.wallParticles());
    hemo::render::OffscreenRenderer renderer(ctx, width, height);
    hemo::render::Swapchain swapchain(ctx, {width, height});
    hemo::gpu::CommandRecorder rec(ctx);
    // The wall's springs (drawn as lines when toggled on with L).
    hemo::render::SpringView springView;
    if (const auto* wall = sim.solver().wall()) {
      springView = {&sim.store().live().positions, &sim.solver().grid().slotOfId(), &wall->springs(), sim.springs(),
                    sim.solver().grid().spec().period};
    }

    // Orbit camera around the particles' box, starting where hemo-run's frames look from.
    const hemo::render::Camera framed =
        hemo::render::defaultCamera(sim.store().readPositions(), float(width) / float(height), sim.wallParticles() > 0);
    const glm::vec3 toEye = framed.eye - framed.target;
    state.distance = glm::length(toEye);
    state.yaw = std::atan2(toEye.y, toEye.x);
    state.pitch = std::asin(toEye.z / state.distance);
    state.frame.fluid = false;
    state.frame.boundary = true;
    state.frame.cutaway = true;
    state.frame.particleRadius = 0.5f * scene.sph.spacing;
    state.frame.speedScale = std::max(scene.expectedMaxSpeed, 1e-3f);

    const auto t0 = std::chrono::steady_clock::now();
    std::uint64_t frames = 0;
    while (!glfwWindowShouldClose(window) && !state.quit && (maxFrames == 0 || frames < maxFrames)) {
      glfwPollEvents();
      if ((!state.paused || state.stepOnce) && stepsPerFrame > 0) {
        hemo::sim::RunOptions run;
        run.steps = stepsPerFrame;
        try {
          sim.run(run);
        } catch (const hemo::sim::SimulationError& e) {
          std::cerr << "hemo-view: " << e.what() << "\n";
          code = 2;
          break;
        }
        state.stepOnce = false;
      }
      hemo::render::Camera camera = framed;
      camera.eye = framed.target + state.distance * glm::vec3(std::cos(state.pitch) * std::cos(state.yaw),
                                                              std::cos(state.pitch) * std::sin(state.yaw),
                                                              std::sin(state.pitch));
      camera.nearPlane = std::max(state.distance * 0.02f, 1e-6f);
      camera.farPlane = state.distance * 4.0f + 4.0f * glm::length(framed.eye - framed.target);
      rec.begin();
      if (state.surface) sim.recordSurface(rec);
      sim.recordWallShade(rec);
      const hemo::render::ToolView tools{sim.solver().tools() ? &sim.solver().tools()->tools() : nullptr, sim.time()};
      renderer.record(rec, camera, state.frame,
                      {&sim.store().live().positions, &sim.store().live().velocities, sim.store().count(),
                       sim.wallShade()},
                      state.surface ? sim.surfaceExtractor() : nullptr, &springView, &tools);
      rec.end();
      rec.submitAndWait();
      if (!swapchain.present(renderer.colorImage(), renderer.extent())) swapchain.recreate({width, height});
      ++frames;
      if (frames % 30 == 0) {
        const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        char title[200];
        std::snprintf(title, sizeof title, "hemo-view: %s  step %llu  t = %.4g s  %.1f fps%s", scene.name.c_str(),
                      static_cast<unsigned long long>(sim.steps()), sim.time(), frames / seconds,
                      state.paused ? "  (paused)" : "");
        glfwSetWindowTitle(window, title);
      }
    }
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    std::printf("hemo-view: presented %llu frames (%llu to the swapchain), %llu steps, t = %.6g s, %.1f frames/s\n",
                static_cast<unsigned long long>(frames), static_cast<unsigned long long>(swapchain.presentedFrames()),
                static_cast<unsigned long long>(sim.steps()), sim.time(), frames / std::max(seconds, 1e-9));
    if (hemo::cli::validationProblems(ctx, "hemo-view")) code = 3;
  } catch (const hemo::scene::SceneError& e) {
    std::cerr << "hemo-view: " << e.what() << "\n";
    code = 1;
  } catch (const hemo::gpu::GpuError& e) {
    std::cerr << "hemo-view: GPU error: " << e.what() << "\n";
    code = 3;
  } catch (const std::exception& e) {
    std::cerr << "hemo-view: " << e.what() << "\n";
    code = 1;
  }
  glfwDestroyWindow(window);
  return code;
}
