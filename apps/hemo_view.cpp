// hemo-view SCENE.json [--device SEL] [--size WxH] [--steps-per-frame K] [--frames N]
//                      [--tool KIND] [--tool-speed V] [--script FILE] [--screenshot FILE.png]
// Runs a scene live in a window: the simulation advances K steps per frame (one submit, one
// wait per frame), then the blood surface is extracted and everything is drawn offscreen,
// the panel (Dear ImGui) over it, and presented. The user drives the tools by hand (each
// frame a short keyframed path from where a tool is to where the hand wants it, uploaded
// between batches) and changes the lumen pressure, the inflow and the wall's stiffness live.
// --script replays input from a file (CI runs it under Xvfb); --frames N quits after N
// presented frames and prints a summary.
// Exit codes as hemo-run: 0 ok, 1 bad input, 2 the simulation failed, 3 no display/device.
#include "cli.hpp"
#include "hemo/render/renderer.hpp"
#include "hemo/render/swapchain.hpp"
#include "hemo/render/tool_drive.hpp"
#include "hemo/scene/scene.hpp"
#include "hemo/sim/simulation.hpp"

#define GLFW_INCLUDE_VULKAN
#include <GLFW/glfw3.h>
#include <backends/imgui_impl_glfw.h>
#include <backends/imgui_impl_vulkan.h>
#include <imgui.h>

#include <glm/geometric.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <map>
#include <memory>
#include <sstream>
#include <iterator>
#include <string>
#include <tuple>
#include <vector>

namespace {

const char* kUsage =
    "usage: hemo-view SCENE.json [--device SEL] [--size WxH] [--steps-per-frame K] [--frames N]\n"
    "                 [--tool probe|grasper|blade|none] [--tool-speed V] [--script FILE]\n"
    "                 [--screenshot FILE.png] [--wall-map strain|wss|tawss|osi|pressure|broken]\n"
    "  --size WxH          window size (default 1280x720)\n"
    "  --steps-per-frame K simulation steps between frames (default 8)\n"
    "  --frames N          quit after N presented frames (default: run until closed)\n"
    "  --tool KIND         add a tool for the hand (default: a probe when the scene has no tools)\n"
    "  --tool-speed V      the fastest a hand-driven tool moves, m/s of simulated time (default 0.25)\n"
    "  --script FILE       replay input: lines 'FRAME ACTION ARGS' (docs/viewer.md)\n"
    "  --screenshot FILE   write the last frame, panel included, as a PNG when the viewer quits\n"
    "  --wall-map MAP      colour the wall from the start by spring strain (default), wall shear\n"
    "                      stress, its time average, the oscillatory shear index, pressure or the\n"
    "                      fraction of springs broken (M cycles through them)\n"
    "mouse: left drag orbits, wheel zooms, right drag moves the active tool on the plane facing\n"
    "the camera (a blade cuts while dragged), Shift+wheel or Up/Down moves it in depth;\n"
    "keys: Tab next tool, G close/open a grasper, Space pause, N step, R reset, S surface,\n"
    "T wall surface, P particles, W wall particles, L springs, B boundary, C cutaway, H panel,\n"
    "Esc/Q quit\n"
    "hemo-view --help prints this text\n";

// The wall maps, in the order of hemo::sim::MassSpring::ShadeBy: --wall-map's names and the
// panel's labels.
const char* kWallMapNames[] = {"strain", "wss", "tawss", "osi", "pressure", "broken"};
const char* kWallMapLabels[] = {"spring strain", "wall shear stress", "time-averaged WSS", "oscillatory shear index",
                                "pressure", "springs broken"};
static_assert(std::size(kWallMapNames) == hemo::sim::MassSpring::kShadeModes);
int wallMapIndex(const std::string& name) {
  for (std::size_t k = 0; k < std::size(kWallMapNames); ++k) {
    if (name == kWallMapNames[k]) return int(k);
  }
  return -1;
}
// The maps made from the wall shear stress (WCSPH only).
bool wallMapNeedsShear(int map) {
  using By = hemo::sim::MassSpring::ShadeBy;
  return map == int(By::WallShear) || map == int(By::MeanWallShear) || map == int(By::OscillatoryShear);
}

// The hand's hold on one tool.
struct Hand {
  bool held = false;  // the tool follows the hand (its scene keys are left behind)
  hemo::render::HandTarget target;
  float openJaws = 0.0f;  // m: a grasper's opening when "open" (its opening when first taken)
  bool closed = false;
  double travelled = 0.0;  // m: the tip's path while held
  glm::vec3 last{0.0f};
  double peakForce = 0.0;  // N: the largest force on it over the run
};

struct ViewState {
  bool paused = false;
  bool stepOnce = false;
  bool surface = true;
  bool panel = true;
  bool wallSurface = false;  // the wall as a shaded surface (T) ...
  bool wallParticles = true; // ... else as particles (W)
  // What the wall is coloured by (M cycles): spring strain, the wall shear stress, or its time
  // average since the map was turned on (sim::MassSpring::ShadeBy); the shear's red end (Pa).
  int wallMap = 0;        // hemo::sim::MassSpring::ShadeBy (kWallMapNames)
  bool wallMaps = false;  // the scene can have them (a wall)
  bool shearMaps = false; // ... and the wall shear's (WCSPH)
  float shearRange = 10.0f;
  float pressureRange = 1000.0f;  // Pa: red
  float strainRange = 0.1f;
  bool quit = false;
  bool reset = false;
  hemo::render::FrameOptions frame;
  float yaw = -1.5708f, pitch = 0.42f, distance = 1.0f;  // orbit around the target (rad, rad, m)
  bool orbiting = false, driving = false;
  double lastX = 0.0, lastY = 0.0;
  glm::vec3 grabOffset{0.0f};  // tip minus the cursor's point when the drag began (m)
  hemo::render::Camera camera;
  glm::vec2 viewSize{1.0f};
  // Tools
  std::uint32_t active = 0;
  std::vector<Hand> hands;
  std::vector<hemo::sim::ToolSpec> tools;  // as the solver holds them now
  double now = 0.0;                        // simulated s at the frame
  glm::vec3 domainMin{0.0f}, domainMax{0.0f};
  float depthStep = 1e-3f;  // m per wheel notch or key press
  // m: a grasper's gap when closed: a few particle spacings, so that the jaws pinch the wall's
  // two sides together rather than crush the blood between them to nothing
  float closedJaws = 0.0f;
};

bool haveTools(const ViewState& s) { return s.active < s.tools.size(); }

// The value the wall's colour reaches red at, for its map: the strain's and the shear's and
// the pressure's ranges, the oscillatory shear index's largest 1/2, all springs broken.
float wallMapScale(const ViewState& s) {
  using By = hemo::sim::MassSpring::ShadeBy;
  switch (By(s.wallMap)) {
    case By::Strain: return s.strainRange;
    case By::WallShear:
    case By::MeanWallShear: return s.shearRange;
    case By::OscillatoryShear: return 0.5f;
    case By::Pressure: return s.pressureRange;
    case By::BrokenFraction: return 1.0f;
  }
  return s.strainRange;
}

// Takes the active tool into the hand (its target starts where it is now).
Hand& grab(ViewState& s) {
  Hand& hand = s.hands[s.active];
  if (!hand.held) {
    const hemo::sim::ToolSpec& tool = s.tools[s.active];
    const std::vector<hemo::sim::ToolKey> pose = hemo::render::handKeys(tool, s.now, 0.0, {}, 0.0f);
    hand.held = true;
    hand.target.position = pose[0].position;
    hand.target.jawOpening = pose[0].jawOpening;
    hand.openJaws = std::max(pose[0].jawOpening, 1e-6f);
    hand.closed = false;
    hand.last = pose[0].position;
  }
  return hand;
}

void moveInDepth(ViewState& s, float notches) {
  if (!haveTools(s)) return;
  Hand& hand = grab(s);
  const glm::vec3 forward = glm::normalize(s.camera.target - s.camera.eye);
  hand.target.position = glm::clamp(hand.target.position - notches * s.depthStep * forward, s.domainMin, s.domainMax);
}

void handleKey(ViewState& s, int key) {
  switch (key) {
    case GLFW_KEY_SPACE: s.paused = !s.paused; break;
    case GLFW_KEY_N: s.stepOnce = true; break;
    case GLFW_KEY_R: s.reset = true; break;
    case GLFW_KEY_S: s.surface = !s.surface; break;
    case GLFW_KEY_P: s.frame.fluid = !s.frame.fluid; break;
    case GLFW_KEY_W: s.wallParticles = !s.wallParticles; break;
    case GLFW_KEY_B: s.frame.boundary = !s.frame.boundary; break;
    case GLFW_KEY_C: s.frame.cutaway = !s.frame.cutaway; break;
    case GLFW_KEY_L: s.frame.springs = !s.frame.springs; break;
    case GLFW_KEY_H: s.panel = !s.panel; break;
    case GLFW_KEY_T: s.wallSurface = !s.wallSurface; break;
    case GLFW_KEY_M:
      if (s.wallMaps) {
        do {
          s.wallMap = (s.wallMap + 1) % int(hemo::sim::MassSpring::kShadeModes);
        } while (!s.shearMaps && wallMapNeedsShear(s.wallMap));
      }
      break;
    case GLFW_KEY_TAB:
      if (!s.tools.empty()) s.active = (s.active + 1) % std::uint32_t(s.tools.size());
      break;
    case GLFW_KEY_G:
      if (haveTools(s) && s.tools[s.active].kind == hemo::sim::ToolKind::Grasper) {
        Hand& hand = grab(s);
        hand.closed = !hand.closed;
        hand.target.jawOpening = hand.closed ? s.closedJaws : hand.openJaws;
      }
      break;
    case GLFW_KEY_UP: moveInDepth(s, -1.0f); break;
    case GLFW_KEY_DOWN: moveInDepth(s, 1.0f); break;
    case GLFW_KEY_ESCAPE:
    case GLFW_KEY_Q: s.quit = true; break;
    default: break;
  }
}

void handleButton(ViewState& s, int button, bool pressed, double x, double y) {
  s.lastX = x;
  s.lastY = y;
  if (button == GLFW_MOUSE_BUTTON_LEFT) s.orbiting = pressed;
  if (button != GLFW_MOUSE_BUTTON_RIGHT || !haveTools(s)) return;
  s.driving = pressed;
  Hand& hand = grab(s);
  if (pressed) {
    s.grabOffset = hand.target.position - hemo::render::cursorOnPlane(s.camera, {float(x), float(y)}, s.viewSize,
                                                                      hand.target.position);
  }
  hand.target.cutting = pressed && s.tools[s.active].kind == hemo::sim::ToolKind::Blade;
}

void handleCursor(ViewState& s, double x, double y) {
  if (s.orbiting) {
    s.yaw -= float(x - s.lastX) * 0.008f;
    s.pitch = std::clamp(s.pitch + float(y - s.lastY) * 0.008f, -1.5f, 1.5f);
  }
  if (s.driving && haveTools(s)) {
    Hand& hand = s.hands[s.active];
    const glm::vec3 onPlane = hemo::render::cursorOnPlane(s.camera, {float(x), float(y)}, s.viewSize, hand.target.position);
    hand.target.position = glm::clamp(onPlane + s.grabOffset, s.domainMin, s.domainMax);
  }
  s.lastX = x;
  s.lastY = y;
}

void handleScroll(ViewState& s, double dy, bool shift) {
  if (shift) {
    moveInDepth(s, float(dy));
  } else {
    s.distance *= std::pow(0.9f, float(dy));
  }
}

ViewState* stateOf(GLFWwindow* window) { return static_cast<ViewState*>(glfwGetWindowUserPointer(window)); }

// GLFW's callbacks (ImGui's backend calls them after its own, and takes what lands on the panel).
void onKey(GLFWwindow* window, int key, int, int action, int) {
  if (action == GLFW_PRESS && !ImGui::GetIO().WantCaptureKeyboard) handleKey(*stateOf(window), key);
}
void onButton(GLFWwindow* window, int button, int action, int) {
  ViewState& s = *stateOf(window);
  if (action == GLFW_PRESS && ImGui::GetIO().WantCaptureMouse) return;
  double x = 0.0, y = 0.0;
  glfwGetCursorPos(window, &x, &y);
  handleButton(s, button, action == GLFW_PRESS, x, y);
}
void onCursor(GLFWwindow* window, double x, double y) { handleCursor(*stateOf(window), x, y); }
void onScroll(GLFWwindow* window, double, double dy) {
  if (ImGui::GetIO().WantCaptureMouse) return;
  const bool shift = glfwGetKey(window, GLFW_KEY_LEFT_SHIFT) == GLFW_PRESS || glfwGetKey(window, GLFW_KEY_RIGHT_SHIFT) == GLFW_PRESS;
  handleScroll(*stateOf(window), dy, shift);
}

// --script: "FRAME ACTION ARGS" per line (# starts a comment), run at the start of frame FRAME.
struct ScriptAction {
  std::uint64_t frame = 0;
  std::string action;
  std::vector<std::string> args;
  std::string where;  // FILE:LINE
};

const std::map<std::string, int>& scriptKeys() {
  static const std::map<std::string, int> keys{
      {"space", GLFW_KEY_SPACE}, {"n", GLFW_KEY_N},     {"r", GLFW_KEY_R},       {"s", GLFW_KEY_S},
      {"p", GLFW_KEY_P},         {"w", GLFW_KEY_W},     {"b", GLFW_KEY_B},       {"c", GLFW_KEY_C},
      {"l", GLFW_KEY_L},         {"h", GLFW_KEY_H},     {"tab", GLFW_KEY_TAB},   {"g", GLFW_KEY_G},
      {"up", GLFW_KEY_UP},       {"down", GLFW_KEY_DOWN}, {"q", GLFW_KEY_Q},    {"escape", GLFW_KEY_ESCAPE},
      {"t", GLFW_KEY_T},         {"m", GLFW_KEY_M}};
  return keys;
}

double scriptNumber(const ScriptAction& a, std::size_t k) {
  try {
    std::size_t used = 0;
    const double x = std::stod(a.args.at(k), &used);
    if (used == a.args[k].size() && std::isfinite(x)) return x;
  } catch (const std::exception&) {
  }
  throw hemo::cli::UsageError(a.where + ": '" + a.action + "' expects a number as argument " + std::to_string(k + 1));
}

std::vector<ScriptAction> loadScript(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw hemo::cli::UsageError("--script: cannot read " + path);
  // action -> (least, most) arguments
  const std::map<std::string, std::pair<std::size_t, std::size_t>> arity{
      {"press", {3, 3}}, {"release", {3, 3}}, {"move", {2, 2}}, {"wheel", {1, 2}}, {"key", {1, 1}},
      {"tool", {1, 1}},  {"aim", {3, 3}},     {"set", {2, 2}},  {"reset", {0, 0}}};
  std::vector<ScriptAction> script;
  std::string line;
  std::uint64_t previous = 0;
  for (int number = 1; std::getline(in, line); ++number) {
    line = line.substr(0, line.find('#'));
    std::istringstream words(line);
    ScriptAction a;
    a.where = path + ":" + std::to_string(number);
    std::string frame;
    if (!(words >> frame)) continue;
    try {
      std::size_t used = 0;
      a.frame = std::stoull(frame, &used);
      if (used != frame.size() || frame[0] == '-') throw std::invalid_argument(frame);
    } catch (const std::exception&) {
      throw hemo::cli::UsageError(a.where + ": expected a frame number, got '" + frame + "'");
    }
    if (a.frame < previous) throw hemo::cli::UsageError(a.where + ": frame " + frame + " comes before the previous line's");
    previous = a.frame;
    if (!(words >> a.action)) throw hemo::cli::UsageError(a.where + ": expected an action after the frame number");
    for (std::string w; words >> w;) a.args.push_back(w);
    const auto it = arity.find(a.action);
    if (it == arity.end()) {
      throw hemo::cli::UsageError(a.where + ": unknown action '" + a.action +
                                  "' (press, release, move, wheel, key, tool, aim, set, reset)");
    }
    if (a.args.size() < it->second.first || a.args.size() > it->second.second) {
      throw hemo::cli::UsageError(a.where + ": '" + a.action + "' takes " + std::to_string(it->second.first) +
                                  (it->second.first == it->second.second ? "" : "-" + std::to_string(it->second.second)) +
                                  " arguments, got " + std::to_string(a.args.size()));
    }
    if ((a.action == "press" || a.action == "release") && a.args[0] != "left" && a.args[0] != "right") {
      throw hemo::cli::UsageError(a.where + ": the button is left or right, got '" + a.args[0] + "'");
    }
    if (a.action == "key" && !scriptKeys().count(a.args[0])) {
      throw hemo::cli::UsageError(a.where + ": unknown key '" + a.args[0] + "'");
    }
    if (a.action == "wheel" && a.args.size() == 2 && a.args[1] != "shift") {
      throw hemo::cli::UsageError(a.where + ": 'wheel' takes a second argument 'shift' only, got '" + a.args[1] + "'");
    }
    if (a.action == "set" && a.args[0] != "lumen_pressure" && a.args[0] != "inflow_speed" && a.args[0] != "wall_stiffness") {
      throw hemo::cli::UsageError(a.where + ": 'set' takes lumen_pressure, inflow_speed or wall_stiffness, got '" +
                                  a.args[0] + "'");
    }
    // Numbers are checked now, not when the frame comes.
    const std::size_t firstNumber = a.action == "press" || a.action == "release" || a.action == "set" ? 1 : 0;
    if (a.action != "key") {
      for (std::size_t k = firstNumber; k < a.args.size() && !(a.action == "wheel" && k == 1); ++k) scriptNumber(a, k);
    }
    script.push_back(a);
  }
  return script;
}

struct Glfw {
  Glfw() : ok(glfwInit() == GLFW_TRUE) {}
  ~Glfw() {
    if (ok) glfwTerminate();
  }
  bool ok;
};

// Dear ImGui on the renderer's render pass (drawn as its overlay), with its own descriptor pool.
class Panel {
 public:
  Panel(hemo::gpu::Context& ctx, GLFWwindow* window, VkRenderPass renderPass) : ctx_(&ctx) {
    IMGUI_CHECKVERSION();
    ImGui::CreateContext();
    ImGui::GetIO().IniFilename = nullptr;  // nothing written next to the user's files
    ImGui::StyleColorsDark();
    ImGui::GetStyle().Alpha = 0.92f;
    ImGui_ImplGlfw_InitForVulkan(window, true);  // chains the callbacks installed before
    VkDescriptorPoolSize size{VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, 4};
    VkDescriptorPoolCreateInfo pool{VK_STRUCTURE_TYPE_DESCRIPTOR_POOL_CREATE_INFO};
    pool.flags = VK_DESCRIPTOR_POOL_CREATE_FREE_DESCRIPTOR_SET_BIT;
    pool.maxSets = 4;
    pool.poolSizeCount = 1;
    pool.pPoolSizes = &size;
    hemo::gpu::check(vkCreateDescriptorPool(ctx.device(), &pool, nullptr, &pool_), "vkCreateDescriptorPool");
    ImGui_ImplVulkan_InitInfo info{};
    info.Instance = ctx.instance();
    info.PhysicalDevice = ctx.physicalDevice();
    info.Device = ctx.device();
    info.QueueFamily = ctx.queueFamily();
    info.Queue = ctx.queue();
    info.DescriptorPool = pool_;
    info.MinImageCount = 2;
    info.ImageCount = 2;
    info.MSAASamples = VK_SAMPLE_COUNT_1_BIT;
    info.CheckVkResultFn = [](VkResult r) { hemo::gpu::check(r, "Dear ImGui's Vulkan backend"); };
    ImGui_ImplVulkan_Init(&info, renderPass);
    hemo::gpu::CommandRecorder rec(ctx);
    rec.begin();
    ImGui_ImplVulkan_CreateFontsTexture(rec.handle());
    rec.end();
    rec.submitAndWait();
    ImGui_ImplVulkan_DestroyFontUploadObjects();
  }
  ~Panel() {
    vkDeviceWaitIdle(ctx_->device());
    ImGui_ImplVulkan_Shutdown();
    ImGui_ImplGlfw_Shutdown();
    ImGui::DestroyContext();
    vkDestroyDescriptorPool(ctx_->device(), pool_, nullptr);
  }
  Panel(const Panel&) = delete;
  Panel& operator=(const Panel&) = delete;
  void begin() {
    ImGui_ImplVulkan_NewFrame();
    ImGui_ImplGlfw_NewFrame();
    ImGui::NewFrame();
  }
  static void draw(VkCommandBuffer cmd) { ImGui_ImplVulkan_RenderDrawData(ImGui::GetDrawData(), cmd); }

 private:
  hemo::gpu::Context* ctx_;
  VkDescriptorPool pool_ = VK_NULL_HANDLE;
};

// What the panel shows, refreshed from the batches' reports (and every few frames from the
// counters, which are readbacks).
// A volume in mL for the panel, three significant digits.
std::string formatVolume(double millilitres) {
  char text[32];
  std::snprintf(text, sizeof text, "%.3g", millilitres);
  return text;
}

struct Readout {
  double fps = 0.0, stepsPerSecond = 0.0;
  std::uint32_t broken = 0, escaped = 0;
  // Open ends: the net volume of blood in through the inlet and out through each outlet since
  // the start (mL; from the GPU's crossing counts)
  double openIn = 0.0;
  std::vector<double> openOut;
  std::vector<glm::vec3> toolForce;  // N, the last step's, per tool
};

// The readout's open-end volumes as the panel and the summary print them:
// "blood in V mL, out V1 + V2 mL" (three significant digits).
std::string openEndsLine(const Readout& r) {
  std::string outlets;
  for (double v : r.openOut) outlets += (outlets.empty() ? "" : " + ") + formatVolume(v);
  return "blood in " + formatVolume(r.openIn) + " mL, out " + outlets + " mL";
}

// Open ends: the readout's volumes (mL) from the GPU's counts (a readback, every few frames).
void readOpenEnds(const hemo::sim::Simulation& sim, const hemo::scene::Scene& scene, Readout& r) {
  if (!sim.openEnds()) return;
  const auto o = sim.openCounts();
  const double particle = 1e6 * double(scene.sph.particleMass()) / scene.sph.restDensity;
  r.openIn = particle * (double(o.in) - double(o.inBack));
  r.openOut.clear();
  for (std::size_t e = 1; e < o.ends.size(); ++e) r.openOut.push_back(particle * (double(o.ends[e].enter) - double(o.ends[e].leave)));
}

}  // namespace

int main(int argc, char** argv) {
  if (hemo::cli::printUsageIfAsked(argc, argv, kUsage)) return 0;
  hemo::cli::Args args;
  std::uint32_t width = 1280, height = 720, stepsPerFrame = 8;
  std::uint64_t maxFrames = 0;
  float toolSpeed = 0.25f;
  std::string handKind, wallMapName;
  std::vector<ScriptAction> script;
  hemo::scene::Scene scene;
  try {
    args = hemo::cli::parse(argc, argv,
                            {"--device", "--size", "--steps-per-frame", "--frames", "--tool", "--tool-speed", "--script",
                             "--screenshot", "--wall-map"});
    if (args.positional.size() != 1) throw hemo::cli::UsageError("expected exactly one SCENE.json");
    std::tie(width, height) = args.size("--size", {1280, 720});
    stepsPerFrame = static_cast<std::uint32_t>(args.count("--steps-per-frame", 8, 0, 100000));
    maxFrames = args.count("--frames", 0, 1, 1000000000);
    toolSpeed = float(args.number("--tool-speed", 0.25, 1e-6, 1e3));
    handKind = args.text("--tool", "");
    if (!handKind.empty() && handKind != "probe" && handKind != "grasper" && handKind != "blade" && handKind != "none") {
      throw hemo::cli::UsageError("--tool expects probe, grasper, blade or none, got '" + handKind + "'");
    }
    wallMapName = args.text("--wall-map", "strain");
    if (wallMapIndex(wallMapName) < 0) {
      throw hemo::cli::UsageError("--wall-map expects strain, wss, tawss, osi, pressure or broken, got '" + wallMapName + "'");
    }
    if (args.has("--script")) script = loadScript(args.text("--script"));
    scene = hemo::scene::loadScene(args.positional[0]);
    if (wallMapName != "strain" && !scene.vessel) throw hemo::cli::UsageError("--wall-map " + wallMapName + " needs a vessel wall");
    if (wallMapNeedsShear(wallMapIndex(wallMapName)) && scene.sph.pressureSolver == hemo::sim::PressureSolver::Dfsph) {
      throw hemo::cli::UsageError("--wall-map " + wallMapName + " needs a vessel wall under WCSPH (fluid.solver \"wcsph\")");
    }
    if (toolSpeed > 0.5f * scene.sph.soundSpeed) {
      throw hemo::cli::UsageError("--tool-speed must stay below half the scene's speed of sound (" +
                                  std::to_string(scene.sph.soundSpeed) + " m/s)");
    }
  } catch (const hemo::cli::UsageError& e) {
    std::cerr << "hemo-view: " << e.what() << "\n" << kUsage;
    return 1;
  } catch (const hemo::scene::SceneError& e) {
    std::cerr << "hemo-view: " << e.what() << "\n";
    return 1;
  }
  if (handKind.empty()) handKind = scene.tools.empty() ? "probe" : "none";

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
  state.viewSize = glm::vec2(float(width), float(height));
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

    // The hand's tool joins the scene's (placed from the particles the scene builds).
    if (handKind != "none") {
      const hemo::scene::SceneBuild built = hemo::scene::buildScene(scene);
      glm::vec3 lo(3e38f), hi(-3e38f);
      for (const auto& p : built.particles.positions) {
        lo = glm::min(lo, glm::vec3(p));
        hi = glm::max(hi, glm::vec3(p));
      }
      const hemo::sim::ToolKind kind = handKind == "probe"   ? hemo::sim::ToolKind::Probe
                                       : handKind == "blade" ? hemo::sim::ToolKind::Blade
                                                             : hemo::sim::ToolKind::Grasper;
      hemo::sim::ToolSpec hand =
          hemo::render::handTool(kind, scene.sph.spacing, lo, hi, scene.domain.min, scene.domain.max);
      if (kind == hemo::sim::ToolKind::Grasper && scene.vessel) hand.gripStiffness = scene.vessel->stiffness;
      scene.tools.push_back(hand);
    }

    auto sim = std::make_unique<hemo::sim::Simulation>(ctx, scene);
    std::fprintf(stderr, "hemo-view: %s on %s: %u fluid + %u boundary + %u wall particles, %zu tools\n",
                 scene.name.c_str(), ctx.info().name.c_str(), sim->fluidParticles(), sim->boundaryParticles(),
                 sim->wallParticles(), scene.tools.size());
    auto renderer = std::make_unique<hemo::render::OffscreenRenderer>(ctx, width, height);
    hemo::render::Swapchain swapchain(ctx, {width, height});
    hemo::gpu::CommandRecorder rec(ctx);
    Panel panel(ctx, window, renderer->renderPass());

    hemo::render::SpringView springView;
    Readout readout;
    auto attach = [&]() {  // what follows the simulation (again after a reset)
      springView = {};
      if (const auto* wall = sim->solver().wall()) {
        springView = {&sim->store().live().positions, &sim->solver().grid().slotOfId(), &wall->springs(),
                      sim->springs(), sim->solver().grid().spec().period};
      }
      state.tools = sim->solver().tools() ? sim->solver().tools()->tools() : std::vector<hemo::sim::ToolSpec>{};
      std::vector<Hand> hands(state.tools.size());
      for (std::size_t k = 0; k < hands.size() && k < state.hands.size(); ++k) hands[k].peakForce = state.hands[k].peakForce;
      state.hands = hands;
      state.active = state.tools.empty() ? 0 : std::uint32_t(state.tools.size() - 1);  // the hand's, if any
      readout.toolForce.assign(state.tools.size(), glm::vec3(0.0f));
      readout.broken = sim->brokenSprings();
      readout.escaped = sim->escapedParticles();
      readOpenEnds(*sim, scene, readout);
    };
    attach();

    // Orbit camera around the particles' box, starting where hemo-run's frames look from.
    // (the snapshot's positions: without an open vessel's parked slots, far outside the domain)
    const hemo::render::Camera framed = hemo::render::defaultCamera(sim->snapshot().positions, float(width) / float(height),
                                                                    sim->wallParticles() > 0);
    const glm::vec3 toEye = framed.eye - framed.target;
    state.distance = glm::length(toEye);
    state.yaw = std::atan2(toEye.y, toEye.x);
    state.pitch = std::asin(toEye.z / state.distance);
    state.frame.fluid = false;
    state.frame.boundary = true;
    // With a wall: drawn as a translucent tissue surface, the blood showing through (T: as
    // particles, cut away on the camera's side).
    state.wallSurface = sim->wallParticles() > 0 && sim->springs() > 0;
    state.frame.cutaway = !state.wallSurface;
    state.frame.wallOpacity = 0.5f;
    // The wall maps (the wall shear's where the solver makes them: WCSPH); the shear's colour
    // scale ends at 8 mu U / R (four times Poiseuille's wall shear at the mean speed U / 2, for
    // the scene's expected speed U and the vessel's radius R), the pressure's at twice the
    // lumen's background pressure and rho U^2 (at least 100 Pa).
    state.wallMaps = sim->springs() > 0;
    state.shearMaps = state.wallMaps && !sim->solver().solvesPressure();
    state.wallMap = wallMapIndex(wallMapName);
    state.pressureRange = std::max(100.0f, 2.0f * (std::max(scene.sph.backgroundPressure, 0.0f) +
                                                   scene.sph.restDensity * scene.expectedMaxSpeed * scene.expectedMaxSpeed));
    state.strainRange = state.frame.strainScale;
    if (scene.vessel && scene.vessel->radius > 0.0f) {
      state.shearRange = std::max(0.01f, 8.0f * scene.sph.viscosity * std::max(scene.expectedMaxSpeed, 1e-3f) / scene.vessel->radius);
    }
    state.frame.particleRadius = 0.5f * scene.sph.spacing;
    state.frame.speedScale = std::max(scene.expectedMaxSpeed, 1e-3f);
    state.domainMin = scene.domain.min;
    state.domainMax = scene.domain.max;
    state.depthStep = 2.0f * scene.sph.spacing;
    state.closedJaws = 3.0f * scene.sph.spacing;
    // The panel's sliders: the scene's values and ranges around them.
    const float scenePressure = sim->lumenPressure(), sceneInflow = sim->inflowSpeed();
    const float pressureMax = std::max(4.0f * std::abs(scenePressure), 1000.0f);
    const float inflowMax = std::max(4.0f * std::abs(sceneInflow), 0.5f);
    double lead = sim->designTimeStep() * stepsPerFrame;  // simulated s per frame, as last measured

    auto camera = [&]() {
      hemo::render::Camera c = framed;
      c.eye = framed.target + state.distance * glm::vec3(std::cos(state.pitch) * std::cos(state.yaw),
                                                         std::cos(state.pitch) * std::sin(state.yaw), std::sin(state.pitch));
      c.nearPlane = std::max(state.distance * 0.02f, 1e-6f);
      c.farPlane = state.distance * 4.0f + 4.0f * glm::length(framed.eye - framed.target);
      return c;
    };
    // The panel's and the script's controls.
    auto setControl = [&](const std::string& name, float value) {
      if (name == "lumen_pressure") sim->setLumenPressure(value);
      if (name == "inflow_speed" && sim->hasInflow()) sim->setInflowSpeed(value);
      if (name == "wall_stiffness" && sim->wallParticles() > 0) sim->setWallStiffnessScale(std::clamp(value, 0.05f, 20.0f));
    };

    const auto t0 = std::chrono::steady_clock::now();
    auto tFps = t0;
    std::uint64_t frames = 0, fpsFrames = 0, fpsSteps = 0, runSteps = 0;
    std::size_t nextAction = 0;
    // The simulated time, read once here and after a reset; each run's result carries it on
    // (the clock's readback would be a copy, a submission and a wait per frame on a discrete GPU).
    state.now = sim->time();
    while (!glfwWindowShouldClose(window) && !state.quit && (maxFrames == 0 || frames < maxFrames)) {
      glfwPollEvents();
      state.camera = camera();
      for (; nextAction < script.size() && script[nextAction].frame <= frames; ++nextAction) {
        const ScriptAction& a = script[nextAction];
        if (a.action == "press" || a.action == "release") {
          handleButton(state, a.args[0] == "left" ? GLFW_MOUSE_BUTTON_LEFT : GLFW_MOUSE_BUTTON_RIGHT, a.action == "press",
                       scriptNumber(a, 1), scriptNumber(a, 2));
        } else if (a.action == "move") {
          handleCursor(state, scriptNumber(a, 0), scriptNumber(a, 1));
        } else if (a.action == "wheel") {
          handleScroll(state, scriptNumber(a, 0), a.args.size() == 2);
        } else if (a.action == "key") {
          handleKey(state, scriptKeys().at(a.args[0]));
        } else if (a.action == "tool") {
          const double k = scriptNumber(a, 0);
          if (!(k >= 0.0 && k < double(state.tools.size()) && k == std::floor(k))) {
            throw hemo::cli::UsageError(a.where + ": no tool " + a.args[0] + " (the scene has " +
                                        std::to_string(state.tools.size()) + ")");
          }
          state.active = std::uint32_t(k);
        } else if (a.action == "aim") {
          if (haveTools(state)) {
            grab(state).target.position = glm::clamp(
                glm::vec3(float(scriptNumber(a, 0)), float(scriptNumber(a, 1)), float(scriptNumber(a, 2))),
                state.domainMin, state.domainMax);
          }
        } else if (a.action == "set") {
          setControl(a.args[0], float(scriptNumber(a, 1)));
        } else if (a.action == "reset") {
          state.reset = true;
        }
      }
      if (state.reset) {
        state.reset = false;
        vkDeviceWaitIdle(ctx.device());
        renderer.reset();  // its descriptor sets name the old simulation's buffers
        sim.reset();
        sim = std::make_unique<hemo::sim::Simulation>(ctx, scene);
        renderer = std::make_unique<hemo::render::OffscreenRenderer>(ctx, width, height);
        attach();
        state.now = sim->time();
        state.driving = false;
      }

      // The panel.
      panel.begin();
      if (state.panel) {
        ImGui::SetNextWindowPos(ImVec2(8, 8), ImGuiCond_FirstUseEver);
        ImGui::SetNextWindowSize(ImVec2(350, 0), ImGuiCond_FirstUseEver);
        ImGui::Begin("hemo");
        ImGui::Text("%.1f frames/s   %.0f steps/s", readout.fps, readout.stepsPerSecond);
        ImGui::Text("t = %.5f s   step %llu", state.now, static_cast<unsigned long long>(sim->steps()));
        if (sim->wallParticles() > 0) ImGui::Text("broken springs %u of %u", readout.broken, sim->springs());
        ImGui::Text("escaped blood %u particles (%.3g mL)", readout.escaped,
                    1e6 * double(readout.escaped) * scene.sph.particleMass() / scene.sph.restDensity);
        if (sim->openEnds()) ImGui::TextUnformatted(openEndsLine(readout).c_str());
        ImGui::Checkbox("pause (Space)", &state.paused);
        ImGui::SameLine();
        if (ImGui::Button("step (N)")) state.stepOnce = true;
        ImGui::SameLine();
        if (ImGui::Button("reset (R)")) state.reset = true;
        float pressure = sim->lumenPressure();
        if (ImGui::SliderFloat("lumen Pa", &pressure, 0.0f, pressureMax, "%.0f")) setControl("lumen_pressure", pressure);
        if (sim->hasInflow()) {
          float inflow = sim->inflowSpeed();
          if (ImGui::SliderFloat("inflow m/s", &inflow, -inflowMax, inflowMax, "%.3f")) setControl("inflow_speed", inflow);
        }
        if (sim->springs() > 0) {
          ImGui::Checkbox("wall surface (T)", &state.wallSurface);
          ImGui::SameLine();
          ImGui::SetNextItemWidth(110.0f);
          ImGui::SliderFloat("opacity", &state.frame.wallOpacity, 0.05f, 1.0f, "%.2f");
        }
        if (state.wallMaps) {
          const int before = state.wallMap;
          ImGui::Combo("wall colour (M)", &state.wallMap, kWallMapLabels, int(hemo::sim::MassSpring::kShadeModes));
          if (!state.shearMaps && wallMapNeedsShear(state.wallMap)) state.wallMap = before;  // (not under DFSPH)
          if (wallMapNeedsShear(state.wallMap) && state.wallMap != int(hemo::sim::MassSpring::ShadeBy::OscillatoryShear)) {
            ImGui::SliderFloat("red at (Pa)", &state.shearRange, 0.01f, 1000.0f, "%.3g", ImGuiSliderFlags_Logarithmic);
          } else if (state.wallMap == int(hemo::sim::MassSpring::ShadeBy::Pressure)) {
            ImGui::SliderFloat("red at (Pa)", &state.pressureRange, 1.0f, 1.0e5f, "%.3g", ImGuiSliderFlags_Logarithmic);
          }
        }
        if (sim->wallParticles() > 0) {
          float stiffness = sim->wallStiffnessScale();
          if (ImGui::SliderFloat("stiffness x", &stiffness, 0.1f, 4.0f, "%.2f", ImGuiSliderFlags_Logarithmic)) {
            setControl("wall_stiffness", stiffness);
          }
        }
        if (haveTools(state)) {
          ImGui::Separator();
          const hemo::sim::ToolSpec& tool = state.tools[state.active];
          ImGui::Text("tool %u of %zu (Tab): %s%s", state.active + 1, state.tools.size(), tool.name.c_str(),
                      state.hands[state.active].held ? " (in hand)" : "");
          const glm::vec3 f = readout.toolForce[state.active];
          ImGui::Text("force %.3e N  (%.2e, %.2e, %.2e)", double(glm::length(f)), double(f.x), double(f.y), double(f.z));
          if (tool.kind == hemo::sim::ToolKind::Grasper) {
            if (ImGui::Button(state.hands[state.active].held && state.hands[state.active].closed ? "open jaws (G)" : "close jaws (G)")) {
              handleKey(state, GLFW_KEY_G);
            }
          }
          ImGui::TextDisabled("right drag: move   Shift+wheel: depth");
        }
        ImGui::End();
      }
      ImGui::Render();

      // The hand's tools: a short path from where each is to its target, for this frame's steps.
      if (auto* tools = sim->solver().tools()) {
        for (std::uint32_t k = 0; k < state.hands.size(); ++k) {
          Hand& hand = state.hands[k];
          if (!hand.held) continue;
          tools->setKeys(k, hemo::render::handKeys(tools->tools()[k], state.now, lead, hand.target, toolSpeed));
        }
        state.tools = tools->tools();
      }

      if ((!state.paused || state.stepOnce) && stepsPerFrame > 0) {
        hemo::sim::RunOptions run;
        run.steps = stepsPerFrame;
        if (!state.tools.empty()) {
          run.onToolLog = [&](const std::vector<hemo::sim::ToolLogRow>& rows) {
            for (const hemo::sim::ToolLogRow& row : rows) {
              if (row.tool >= readout.toolForce.size()) continue;
              const glm::vec3 f(row.sample.force);
              readout.toolForce[row.tool] = f;
              state.hands[row.tool].peakForce = std::max(state.hands[row.tool].peakForce, double(glm::length(f)));
            }
          };
        }
        try {
          const double before = state.now;
          const hemo::sim::RunResult result = sim->run(run);
          runSteps += result.steps;
          fpsSteps += result.steps;
          const double after = result.simTime;
          if (after > before) lead = after - before;
          state.now = after;
        } catch (const hemo::sim::SimulationError& e) {
          std::cerr << "hemo-view: " << e.what() << "\n";
          code = 2;
          break;
        }
        state.stepOnce = false;
      }
      for (std::uint32_t k = 0; k < state.hands.size(); ++k) {
        Hand& hand = state.hands[k];
        if (!hand.held) continue;
        const glm::vec3 tip = hemo::render::handKeys(state.tools[k], state.now, 0.0, {}, 0.0f)[0].position;
        hand.travelled += glm::length(tip - hand.last);
        hand.last = tip;
      }
      if (frames % 15 == 0) {
        readout.broken = sim->brokenSprings();
        readout.escaped = sim->escapedParticles();
        readOpenEnds(*sim, scene, readout);
      }

      rec.begin();
      if (state.surface) sim->recordSurface(rec);
      if (wallMapNeedsShear(state.wallMap) && !sim->wallShearEnabled()) sim->enableWallShear();  // (again after a reset)
      sim->recordWallShade(rec, hemo::sim::MassSpring::ShadeBy(state.wallMap));
      state.frame.strainScale = wallMapScale(state);
      const hemo::render::ToolView tools{state.tools.empty() ? nullptr : &state.tools, state.now};
      hemo::render::WallSurfaceView wallView;
      if (state.wallSurface) {
        wallView = {&sim->store().live().positions, &sim->solver().grid().slotOfId(), &sim->solver().wall()->springs(),
                    &sim->enableWallSurface(), &sim->store().live().normals, sim->wallShade(), sim->wallTriangleCount(),
                    sim->solver().grid().spec().period, sim->solver().grid().spec().origin};
      }
      state.frame.wall = !state.wallSurface && state.wallParticles;
      renderer->setOverlay(state.panel ? Panel::draw : std::function<void(VkCommandBuffer)>{});
      renderer->record(rec, state.camera, state.frame,
                       {&sim->store().live().positions, &sim->store().live().velocities, sim->store().count(),
                        sim->wallShade()},
                       state.surface ? sim->surfaceExtractor() : nullptr, &springView, &tools,
                       state.wallSurface ? &wallView : nullptr);
      rec.end();
      rec.submitAndWait();
      if (!swapchain.present(renderer->colorImage(), renderer->extent())) swapchain.recreate({width, height});
      ++frames;
      ++fpsFrames;
      const auto tNow = std::chrono::steady_clock::now();
      const double span = std::chrono::duration<double>(tNow - tFps).count();
      if (span > 0.5) {
        readout.fps = double(fpsFrames) / span;
        readout.stepsPerSecond = double(fpsSteps) / span;
        fpsFrames = fpsSteps = 0;
        tFps = tNow;
      }
    }
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    std::printf("hemo-view: presented %llu frames (%llu to the swapchain), %llu steps, t = %.6g s, %.1f frames/s\n",
                static_cast<unsigned long long>(frames), static_cast<unsigned long long>(swapchain.presentedFrames()),
                static_cast<unsigned long long>(runSteps), sim->time(), frames / std::max(seconds, 1e-9));
    if (sim->wallParticles() > 0 || sim->fluidParticles() > 0) {
      std::printf("hemo-view: %u springs broken, %u particles escaped\n", sim->brokenSprings(), sim->escapedParticles());
      if (sim->openEnds()) {
        readOpenEnds(*sim, scene, readout);
        std::printf("hemo-view: open ends: %s\n", openEndsLine(readout).c_str());
      }
      if (sim->wallShearEnabled()) {
        const hemo::sim::Simulation::WallShearMaps maps = sim->readWallShear();
        double sum = 0.0, most = 0.0;
        for (float t : maps.tawss) sum += t, most = std::max(most, double(t));
        std::printf("hemo-view: wall maps over %.4g s: time-averaged wall shear stress %.4g Pa on average, %.4g Pa at most\n",
                    maps.seconds, maps.tawss.empty() ? 0.0 : sum / double(maps.tawss.size()), most);
      }
    }
    for (std::size_t k = 0; k < state.tools.size(); ++k) {
      std::printf("hemo-view: tool \"%s\"%s: moved %.3g mm by hand, largest force %.3g N\n", state.tools[k].name.c_str(),
                  state.hands[k].held ? " (in hand)" : "", 1e3 * state.hands[k].travelled, state.hands[k].peakForce);
    }
    if (args.has("--screenshot") && frames > 0) {
      hemo::render::writePng(args.text("--screenshot"), width, height, renderer->readPixels());
    }
    if (hemo::cli::validationProblems(ctx, "hemo-view")) code = 3;
  } catch (const hemo::cli::UsageError& e) {
    std::cerr << "hemo-view: " << e.what() << "\n";
    code = 1;
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
