#pragma once
// Drawing from the engine's GPU buffers on the same device: particles as shaded discs (fluid
// coloured by speed, wall particles by strain, optionally the rigid boundary), the wall's
// springs as lines coloured by strain (broken ones purple), the marching-cubes surface and
// the surgical tools, lit, with depth. The renderer only reads engine buffers (positions, velocities,
// the extractor's vertices and indirect draw arguments) and owns the one compute-to-graphics
// barrier. OffscreenRenderer draws into an image and copies it to host memory for PNG files
// and tests; nothing here needs a window.
#include "hemo/gpu/commands.hpp"
#include "hemo/sim/tools.hpp"
#include "hemo/surface/marching_cubes.hpp"

#include <glm/mat4x4.hpp>
#include <glm/vec3.hpp>
#include <glm/vec4.hpp>

#include <cstdint>
#include <filesystem>
#include <functional>
#include <map>
#include <tuple>
#include <utility>
#include <vector>

namespace hemo::render {

struct Camera {
  glm::vec3 eye{0.0f, -1.0f, 0.0f};  // m
  glm::vec3 target{0.0f};            // m
  glm::vec3 up{0.0f, 0.0f, 1.0f};
  float fovY = 0.6f;                 // vertical field of view (rad)
  float nearPlane = 1e-4f, farPlane = 10.0f;  // m

  // Looks at the centre of the box [lo, hi] from `direction` (target -> eye) from far enough
  // that the box's bounding sphere fits the view at this aspect ratio (width / height).
  static Camera framing(glm::vec3 lo, glm::vec3 hi, float aspect, glm::vec3 direction = {0.45f, -1.0f, 0.4f});
  glm::mat4 view() const;
  // Vulkan clip space: y down, depth 0 (near) .. 1 (far).
  glm::mat4 projection(float aspect) const;
};

// The camera hemo's frames and viewer start from: framing every finite particle; looking
// across the vessel's axis (+x) from -y and a little above when `vessel` (so a cutaway opens
// the vessel's whole length; from above, a little to -y, when the particles spread wider in y
// than in z, as a bifurcation's branches do), else from an oblique corner.
Camera defaultCamera(const std::vector<glm::vec4>& positions, float aspect, bool vessel);

struct FrameOptions {
  bool fluid = true;      // fluid particles
  bool wall = true;       // vessel wall particles
  bool boundary = false;  // rigid boundary particles (tank walls)
  bool cutaway = false;   // hide the wall and boundary particles between the camera and the
                          // plane through the target facing it
  float particleRadius = 0.0f;  // m (0: nothing drawn for particles)
  float speedScale = 1.0f;      // m/s at the red end of the fluid's colour scale
  float strainScale = 0.1f;     // spring strain at the red end of the wall's colour scale
  bool springs = false;         // the wall's springs as lines (with a SpringView)
  bool brokenSprings = true;    // broken springs drawn purple (else left out)
  float wallOpacity = 1.0f;     // the wall surface's (with a WallSurfaceView): 1 opaque, less
                                // lets the blood show through
  glm::vec4 background{0.95f, 0.95f, 0.96f, 1.0f};
  glm::vec3 surfaceColor{0.62f, 0.05f, 0.06f};
  glm::vec3 lightDirection{0.3f, -0.5f, 0.8f};  // towards the light
};

// The particle buffers to draw (a sim::ParticleStore's live arrays, in any order).
struct ParticleView {
  const gpu::Buffer* positions = nullptr;   // vec4 xyz m
  const gpu::Buffer* velocities = nullptr;  // vec4 xyz m/s, w kind
  std::uint32_t count = 0;
  // Optional: vec2 per slot (strain, broken fraction) from sim::MassSpring::recordShade.
  const gpu::Buffer* wallShade = nullptr;
};

// The wall's springs to draw as lines (sim::MassSpring::springs(), the grid's id -> slot map).
struct SpringView {
  const gpu::Buffer* positions = nullptr;  // vec4 per slot
  const gpu::Buffer* slotOfId = nullptr;   // uint per particle id
  const gpu::Buffer* springs = nullptr;    // sim::GpuSpring records
  std::uint32_t count = 0;
  glm::vec3 period{0.0f};                  // m on periodic axes, 0 elsewhere
};

// The wall as a shaded surface (sim::Simulation::enableWallSurface): its triangles, torn where
// springs broke, coloured by strain, drawn after everything else, as opaque as
// FrameOptions::wallOpacity.
struct WallSurfaceView {
  const gpu::Buffer* positions = nullptr;  // vec4 per slot
  const gpu::Buffer* slotOfId = nullptr;   // uint per particle id
  const gpu::Buffer* springs = nullptr;    // sim::GpuSpring records (their broken flags)
  const gpu::Buffer* triangles = nullptr;  // sim::kWallTriangleWords uints per triangle
  const gpu::Buffer* normals = nullptr;    // vec4 per slot (the wall's normals)
  const gpu::Buffer* shade = nullptr;      // vec2 per slot (sim::MassSpring::recordShade)
  std::uint32_t count = 0;                 // triangles
  glm::vec3 period{0.0f};                  // m on periodic axes, 0 elsewhere
  glm::vec3 origin{0.0f};                  // m: the domain's low corner (on periodic axes, the
                                           // surface is drawn inside [origin, origin + period))
};

// The tools to draw, at their poses at `time` (the keyframes as the solver holds them).
struct ToolView {
  const std::vector<sim::ToolSpec>* tools = nullptr;
  double time = 0.0;  // s
  glm::vec3 color{0.62f, 0.66f, 0.72f};
};

// The tools' surfaces at time t as triangles, three vertices each, every vertex two vec4:
// the position (m) and the outward normal. A probe or blade: its capsule. A grasper: its two
// jaws, each the box that bounds the rounded plate (capsules when it has no width).
// `segments` around a capsule's axis.
std::vector<glm::vec4> toolTriangles(const std::vector<sim::ToolSpec>& tools, double t, int segments = 24);

class OffscreenRenderer {
 public:
  OffscreenRenderer(gpu::Context& context, std::uint32_t width, std::uint32_t height);
  ~OffscreenRenderer();
  OffscreenRenderer(const OffscreenRenderer&) = delete;
  OffscreenRenderer& operator=(const OffscreenRenderer&) = delete;

  // Records one frame after the compute work that produced the buffers (same recorder): the
  // tools' triangles copied from host memory, the compute-to-graphics barrier, clear,
  // particles, the surface (drawn with the extractor's indirect arguments; nullptr: no
  // surface), the tools, the wall's surface, the overlay, and the copy of the image to host
  // memory. The previous frame must
  // have completed (the tools' buffers are reused).
  void record(gpu::CommandRecorder& rec, const Camera& camera, const FrameOptions& options,
              const ParticleView& particles, const surface::MarchingCubes* surface,
              const SpringView* springs = nullptr, const ToolView* tools = nullptr,
              const WallSurfaceView* wall = nullptr);
  // Drawn over each frame, last inside its render pass (hemo-view's panel): called with the
  // command buffer being recorded. Its pipelines must be made for renderPass() (subpass 0: one
  // RGBA8 colour attachment and a depth attachment, one sample). Empty: nothing.
  void setOverlay(std::function<void(VkCommandBuffer)> overlay) { overlay_ = std::move(overlay); }
  VkRenderPass renderPass() const { return renderPass_; }
  // RGBA8 pixels of the last recorded frame (after its submission completed), top row first.
  std::vector<std::uint8_t> readPixels() const;
  // The rendered image (TRANSFER_SRC_OPTIMAL after a frame), for presenting (Swapchain).
  VkImage colorImage() const { return color_; }
  VkExtent2D extent() const { return {width_, height_}; }
  std::uint32_t width() const { return width_; }
  std::uint32_t height() const { return height_; }

 private:
  VkShaderModule module(const char* name);
  // A descriptor set of three storage buffers at bindings 0-2 (particles and springs share
  // the layout), made once per distinct triple.
  VkDescriptorSet storageSet(const gpu::Buffer& b0, const gpu::Buffer& b1, const gpu::Buffer& b2);
  void createTargets();
  void createPipelines();

  gpu::Context* context_;
  std::uint32_t width_, height_;
  VkFormat depthFormat_ = VK_FORMAT_UNDEFINED;
  VkImage color_ = VK_NULL_HANDLE, depth_ = VK_NULL_HANDLE;
  VkDeviceMemory colorMemory_ = VK_NULL_HANDLE, depthMemory_ = VK_NULL_HANDLE;
  VkImageView colorView_ = VK_NULL_HANDLE, depthView_ = VK_NULL_HANDLE;
  VkRenderPass renderPass_ = VK_NULL_HANDLE;
  VkFramebuffer framebuffer_ = VK_NULL_HANDLE;
  VkDescriptorSetLayout particleLayout_ = VK_NULL_HANDLE;
  VkDescriptorPool pool_ = VK_NULL_HANDLE;
  VkPipelineLayout particlePipelineLayout_ = VK_NULL_HANDLE, surfacePipelineLayout_ = VK_NULL_HANDLE;
  VkPipeline particlePipeline_ = VK_NULL_HANDLE, surfacePipeline_ = VK_NULL_HANDLE;
  VkPipelineLayout springPipelineLayout_ = VK_NULL_HANDLE;
  VkPipeline springPipeline_ = VK_NULL_HANDLE;
  VkPipelineLayout wallPipelineLayout_ = VK_NULL_HANDLE;
  VkPipeline wallOpaquePipeline_ = VK_NULL_HANDLE, wallBlendPipeline_ = VK_NULL_HANDLE;
  std::vector<VkShaderModule> modules_;
  std::map<std::tuple<VkBuffer, VkBuffer, VkBuffer>, VkDescriptorSet> storageSets_;
  gpu::Buffer pixels_;
  gpu::Buffer noShade_;  // bound when a view has no wall shade (never read then)
  std::function<void(VkCommandBuffer)> overlay_;
  gpu::Buffer toolStaging_, toolVertices_;  // the tools' triangles (host-written, and for drawing)
};

// Writes RGBA8 pixels (top row first) as an 8-bit RGBA PNG. Throws std::runtime_error naming
// the file if it cannot be written.
void writePng(const std::filesystem::path& path, std::uint32_t width, std::uint32_t height,
              const std::vector<std::uint8_t>& rgba);

}  // namespace hemo::render
