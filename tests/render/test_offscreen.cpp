// The offscreen renderer: a known surface and known particles drawn where the camera maths
// says, in the colours the options say, the background everywhere else.
#include "gpu_test.hpp"
#include "hemo/render/renderer.hpp"
#include "hemo/sim/particles.hpp"
#include "hemo/scene/scene.hpp"
#include "hemo/sim/simulation.hpp"
#include "hemo/sim/wall.hpp"

#include <glm/geometric.hpp>

#include <cmath>
#include <filesystem>
#include <fstream>

namespace hemo::test {
namespace {

struct Rgb {
  int r, g, b;
};

Rgb pixel(const std::vector<std::uint8_t>& rgba, std::uint32_t width, std::uint32_t x, std::uint32_t y) {
  const std::size_t i = (std::size_t(y) * width + x) * 4;
  return {rgba[i], rgba[i + 1], rgba[i + 2]};
}

// Pixel coordinates of a world point (the renderer's camera maths, applied here).
glm::vec2 project(const render::Camera& camera, glm::vec3 p, std::uint32_t width, std::uint32_t height) {
  const glm::vec4 clip = camera.projection(float(width) / float(height)) * camera.view() * glm::vec4(p, 1.0f);
  const glm::vec2 ndc = glm::vec2(clip) / clip.w;
  return {(ndc.x + 1.0f) * 0.5f * float(width), (ndc.y + 1.0f) * 0.5f * float(height)};
}

class RenderTest : public GpuTest {};

TEST_F(RenderTest, SphereSurfaceCoversItsSilhouette) {
  const double R = 1.0e-3;
  const std::uint32_t n = 65;
  const double voxel = 2.4 * R / (n - 1);
  std::vector<double> values(std::size_t(n) * n * n);
  for (std::uint32_t k = 0; k < n; ++k) {
    for (std::uint32_t j = 0; j < n; ++j) {
      for (std::uint32_t i = 0; i < n; ++i) {
        const glm::dvec3 x = glm::dvec3(-1.2 * R) + voxel * glm::dvec3(i, j, k);
        values[i + n * (j + std::size_t(n) * k)] = 1.0 - glm::length(x) / R;
      }
    }
  }
  surface::MarchingCubes mc(ctx(), 64);
  mc.uploadField(glm::dvec3(-1.2 * R), voxel, glm::uvec3(n), values, 0.0f);

  const std::uint32_t W = 320, H = 240;
  render::OffscreenRenderer renderer(ctx(), W, H);
  render::Camera camera;
  camera.eye = glm::vec3(0.0f, -5.0e-3f, 0.0f);
  camera.target = glm::vec3(0.0f);
  camera.nearPlane = 1e-3f;
  camera.farPlane = 1e-2f;
  render::FrameOptions options;
  gpu::CommandRecorder rec(ctx());
  rec.begin();
  mc.record(rec);
  renderer.record(rec, camera, options, {}, &mc);
  rec.end();
  rec.submitAndWait();
  const auto rgba = renderer.readPixels();

  const Rgb background = pixel(rgba, W, 0, 0);
  EXPECT_EQ(background.r, int(std::lround(options.background.r * 255.0f)));
  std::size_t covered = 0;
  for (std::uint32_t y = 0; y < H; ++y) {
    for (std::uint32_t x = 0; x < W; ++x) {
      const Rgb p = pixel(rgba, W, x, y);
      if (p.r != background.r || p.g != background.g || p.b != background.b) {
        ++covered;
        ASSERT_GT(p.r, p.g) << "surface pixels are red (" << x << ", " << y << ")";
        ASSERT_GT(p.r, p.b);
      }
    }
  }
  // The silhouette of a sphere seen from distance d: a disc of angular radius asin(R / d).
  const double d = 5.0e-3;
  const double radiusPx = std::tan(std::asin(R / d)) / std::tan(0.5 * camera.fovY) * (H / 2.0);
  const double expected = 3.14159265358979 * radiusPx * radiusPx;
  std::printf("sphere: %zu pixels covered, %.0f expected\n", covered, expected);
  EXPECT_NEAR(double(covered) / expected, 1.0, 0.03);
  const Rgb centre = pixel(rgba, W, W / 2, H / 2);
  EXPECT_GT(centre.r, 2 * centre.g);
  EXPECT_GT(centre.r, 2 * centre.b);
  // Lit from above (the default light points up): the top of the disc is brighter.
  const Rgb top = pixel(rgba, W, W / 2, std::uint32_t(H / 2 - 0.8 * radiusPx));
  const Rgb bottom = pixel(rgba, W, W / 2, std::uint32_t(H / 2 + 0.8 * radiusPx));
  EXPECT_GT(top.r, bottom.r);
}

// The tools drawn at their poses: a probe's capsule covers its silhouette (a 2r x L rectangle
// and a disc of radius r, seen side on), in the tools' grey; a grasper's two jaws stand either
// side of its axis with the keyed gap between them, and move with the time given.
TEST_F(RenderTest, ToolsAreDrawnAtTheirPoses) {
  const std::uint32_t W = 320, H = 240;
  render::OffscreenRenderer renderer(ctx(), W, H);
  render::Camera camera;
  camera.eye = glm::vec3(0.0f, -0.02f, 0.0005f);
  camera.target = glm::vec3(0.0f, 0.0f, 0.0005f);
  camera.nearPlane = 1e-3f;
  camera.farPlane = 0.1f;
  render::FrameOptions options;
  auto draw = [&](const std::vector<sim::ToolSpec>& tools, double t) {
    const render::ToolView view{&tools, t};
    gpu::CommandRecorder rec(ctx());
    rec.begin();
    renderer.record(rec, camera, options, {}, nullptr, nullptr, &view);
    rec.end();
    rec.submitAndWait();
    return renderer.readPixels();
  };
  const Rgb background{int(std::lround(options.background.r * 255.0f)), int(std::lround(options.background.g * 255.0f)),
                       int(std::lround(options.background.b * 255.0f))};
  auto covered = [&](const std::vector<std::uint8_t>& rgba, std::uint32_t x, std::uint32_t y) {
    const Rgb p = pixel(rgba, W, x, y);
    return p.r != background.r || p.g != background.g || p.b != background.b;
  };

  sim::ToolSpec probe;
  probe.name = "probe";
  probe.radius = 0.0004f;
  probe.length = 0.001f;
  probe.keys = {{0.0, {0.0f, 0.0f, 0.0f}, glm::quat(1, 0, 0, 0)}};
  const auto rgba = draw({probe}, 0.0);
  std::size_t count = 0;
  for (std::uint32_t y = 0; y < H; ++y) {
    for (std::uint32_t x = 0; x < W; ++x) {
      if (!covered(rgba, x, y)) continue;
      ++count;
      const Rgb p = pixel(rgba, W, x, y);
      ASSERT_LT(std::abs(p.r - p.b), 60) << "tool pixels are grey (" << x << ", " << y << ")";
    }
  }
  // seen side on from 20 mm: the silhouette's area in pixels (the near side is r closer: the
  // projection grows by about r / d = 2%)
  const double scale = (H / 2.0) / (0.02 * std::tan(0.5 * camera.fovY));
  const double expected = (2.0 * probe.radius * probe.length + 3.14159265358979 * probe.radius * probe.radius) * scale * scale;
  std::printf("probe: %zu pixels covered, %.0f expected\n", count, expected);
  EXPECT_NEAR(double(count) / expected, 1.02, 0.05);
  const glm::vec2 mid = project(camera, glm::vec3(0.0f, 0.0f, 0.0005f), W, H);
  EXPECT_TRUE(covered(rgba, std::uint32_t(mid.x), std::uint32_t(mid.y)));

  // a grasper whose jaws (x = +-(opening / 2 + r)) open from 2 to 4 mm over a second
  sim::ToolSpec grasper;
  grasper.name = "grasper";
  grasper.kind = sim::ToolKind::Grasper;
  grasper.radius = 0.0002f;
  grasper.length = 0.001f;
  grasper.jawWidth = 0.0004f;
  grasper.keys = {{0.0, {0.0f, 0.0f, 0.0f}, glm::quat(1, 0, 0, 0), false, 0.002f},
                  {1.0, {0.0f, 0.0f, 0.0f}, glm::quat(1, 0, 0, 0), false, 0.004f}};
  for (const double t : {0.0, 1.0}) {
    const auto img = draw({grasper}, t);
    const float c = float(0.5 * (0.002 + 0.002 * t)) + grasper.radius;
    for (const float side : {c, -c}) {
      const glm::vec2 jaw = project(camera, glm::vec3(side, 0.0f, 0.0005f), W, H);
      EXPECT_TRUE(covered(img, std::uint32_t(jaw.x), std::uint32_t(jaw.y))) << "jaw at x = " << side << " m, t = " << t;
    }
    const glm::vec2 gap = project(camera, glm::vec3(0.5f * c, 0.0f, 0.0005f), W, H);
    EXPECT_FALSE(covered(img, std::uint32_t(gap.x), std::uint32_t(gap.y))) << "the gap, t = " << t;
  }
}

TEST_F(RenderTest, ParticlesAreDrawnInTheirKindsColours) {
  // A slow and a fast fluid particle, a wall particle, and a boundary particle (hidden by
  // default), side by side along x.
  const std::vector<glm::vec4> positions = {{-3e-3f, 0.0f, 0.0f, 1.0f}, {3e-3f, 0.0f, 0.0f, 1.0f},
                                            {0.0f, 0.0f, 0.0f, 1.0f}, {0.0f, 0.0f, 2.5e-3f, 1.0f}};
  const std::vector<glm::vec4> velocities = {{0.0f, 0.0f, 0.0f, 0.0f}, {2.0f, 0.0f, 0.0f, 0.0f},
                                             {0.0f, 0.0f, 0.0f, 2.0f}, {0.0f, 0.0f, 0.0f, 1.0f}};
  sim::ParticleStore store(ctx(), 4);
  store.upload(positions, velocities);
  const std::uint32_t W = 320, H = 200;
  render::OffscreenRenderer renderer(ctx(), W, H);
  const render::Camera camera = render::Camera::framing(glm::vec3(-4e-3f, -1e-3f, -1e-3f), glm::vec3(4e-3f, 1e-3f, 3e-3f),
                                                        float(W) / H, glm::vec3(0.0f, -1.0f, 0.0f));
  render::FrameOptions options;
  options.particleRadius = 0.8e-3f;
  options.speedScale = 2.0f;
  gpu::CommandRecorder rec(ctx());
  const auto draw = [&] {
    rec.begin();
    renderer.record(rec, camera, options, {&store.live().positions, &store.live().velocities, 4}, nullptr);
    rec.end();
    rec.submitAndWait();
    return renderer.readPixels();
  };
  auto rgba = draw();
  const auto at = [&](int k) {
    const glm::vec2 p = project(camera, glm::vec3(positions[k]), W, H);
    return pixel(rgba, W, std::uint32_t(p.x), std::uint32_t(p.y));
  };
  const Rgb slow = at(0), fast = at(1), wall = at(2), boundary = at(3), background = pixel(rgba, W, 0, 0);
  EXPECT_GT(slow.b, slow.r + 60) << "fluid at rest: blue";
  EXPECT_GT(fast.r, fast.b + 60) << "fluid at the top of the scale: red";
  EXPECT_GT(wall.r, wall.b + 30) << "wall: tan";
  EXPECT_GT(wall.g, wall.b + 15);
  EXPECT_EQ(boundary.r, background.r) << "rigid boundary hidden by default";
  EXPECT_EQ(boundary.g, background.g);

  options.boundary = true;
  rgba = draw();
  const Rgb shown = at(3);
  EXPECT_NE(shown.r, background.r) << "rigid boundary shown on request";
  EXPECT_EQ(shown.r, shown.g) << "grey";

  // Wall shade: a stretched wall particle turns red, one whose springs all broke purple.
  gpu::Buffer shade(ctx(), 4 * 8, gpu::MemoryUse::Device, "test wall shade");
  const auto drawShaded = [&](glm::vec2 wallShade) {
    shade.upload(std::vector<glm::vec2>{glm::vec2(0.0f), glm::vec2(0.0f), wallShade, glm::vec2(0.0f)});
    rec.begin();
    renderer.record(rec, camera, options, {&store.live().positions, &store.live().velocities, 4, &shade}, nullptr);
    rec.end();
    rec.submitAndWait();
    rgba = renderer.readPixels();
    return at(2);
  };
  const Rgb plain = drawShaded(glm::vec2(0.0f));
  EXPECT_EQ(plain.r, wall.r) << "no strain: the plain wall colour";
  EXPECT_EQ(plain.g, wall.g);
  const Rgb stretched = drawShaded(glm::vec2(0.2f, 0.0f));
  EXPECT_GT(stretched.r, stretched.g + 80) << "strain beyond the scale: red";
  const Rgb torn = drawShaded(glm::vec2(0.0f, 1.0f));
  EXPECT_GT(torn.b, torn.g + 30) << "all springs broken: purple";
  EXPECT_GT(torn.r, torn.g);

  // PNG output: a valid signature and the image's size in the header.
  const auto path = std::filesystem::temp_directory_path() / "hemo_test_particles.png";
  render::writePng(path, W, H, rgba);
  std::ifstream in(path, std::ios::binary);
  unsigned char head[24];
  in.read(reinterpret_cast<char*>(head), 24);
  ASSERT_TRUE(in);
  EXPECT_EQ(head[1], 'P');
  EXPECT_EQ(head[2], 'N');
  EXPECT_EQ(head[3], 'G');
  EXPECT_EQ((head[16] << 24 | head[17] << 16 | head[18] << 8 | head[19]), int(W));
  EXPECT_EQ((head[20] << 24 | head[21] << 16 | head[22] << 8 | head[23]), int(H));
  std::filesystem::remove(path);
  EXPECT_THROW(render::writePng(path, W, H, std::vector<std::uint8_t>(7)), std::invalid_argument);
}

// Springs as lines: at rest length tan, stretched past the strain scale red, broken purple
// (or left out on request).
TEST_F(RenderTest, SpringsAreDrawnByStrainAndBrokenOnesMarked) {
  const float L = 2e-3f;
  const std::vector<glm::vec4> positions = {{-L, 0.0f, 1.5e-3f, 1.0f}, {L, 0.0f, 1.5e-3f, 1.0f},
                                            {-L, 0.0f, 0.0f, 1.0f},    {L, 0.0f, 0.0f, 1.0f},
                                            {-L, 0.0f, -1.5e-3f, 1.0f}, {L, 0.0f, -1.5e-3f, 1.0f}};
  const std::vector<glm::vec4> velocities(6, glm::vec4(0.0f, 0.0f, 0.0f, 2.0f));
  sim::ParticleStore store(ctx(), 6);
  store.upload(positions, velocities);
  gpu::Buffer slotOfId(ctx(), 6 * 4, gpu::MemoryUse::Device, "test slot of id");
  slotOfId.upload(std::vector<std::uint32_t>{0, 1, 2, 3, 4, 5});
  // At rest; stretched by 20% (rest 2L / 1.2); broken.
  const std::vector<sim::GpuSpring> springs = {{0, 1, 2 * L, 1.0f, 0.0f, 1.0f, 0u, 0u},
                                               {2, 3, 2 * L / 1.2f, 1.0f, 0.0f, 1.0f, 0u, 0u},
                                               {4, 5, 2 * L, 1.0f, 0.0f, 1.0f, 1u, 0u}};
  gpu::Buffer springBuffer(ctx(), springs.size() * sizeof(sim::GpuSpring), gpu::MemoryUse::Device, "test springs");
  springBuffer.upload(springs);
  const std::uint32_t W = 240, H = 180;
  render::OffscreenRenderer renderer(ctx(), W, H);
  const render::Camera camera = render::Camera::framing(glm::vec3(-L, -1e-3f, -2e-3f), glm::vec3(L, 1e-3f, 2e-3f),
                                                        float(W) / H, glm::vec3(0.0f, -1.0f, 0.0f));
  render::FrameOptions options;
  options.springs = true;
  options.strainScale = 0.1f;
  const render::SpringView view{&store.live().positions, &slotOfId, &springBuffer, 3, glm::vec3(0.0f)};
  gpu::CommandRecorder rec(ctx());
  std::vector<std::uint8_t> rgba;
  const auto draw = [&] {
    rec.begin();
    renderer.record(rec, camera, options, {}, nullptr, &view);
    rec.end();
    rec.submitAndWait();
    rgba = renderer.readPixels();
  };
  const Rgb background{int(std::lround(options.background.r * 255.0f)), int(std::lround(options.background.g * 255.0f)),
                       int(std::lround(options.background.b * 255.0f))};
  // The line's colour near the projected middle of spring k (background if nothing is drawn).
  const auto lineAt = [&](int k) {
    const glm::vec2 p = project(camera, 0.5f * glm::vec3(positions[2 * k] + positions[2 * k + 1]), W, H);
    for (int dy = -2; dy <= 2; ++dy) {
      const Rgb c = pixel(rgba, W, std::uint32_t(p.x), std::uint32_t(int(p.y) + dy));
      if (c.r != background.r || c.g != background.g || c.b != background.b) return c;
    }
    return background;
  };
  draw();
  const Rgb rest = lineAt(0), stretched = lineAt(1), broken = lineAt(2);
  EXPECT_GT(rest.r, rest.g);
  EXPECT_GT(rest.g, rest.b + 20) << "at rest: tan";
  EXPECT_GT(stretched.r, stretched.g + 100) << "stretched past the scale: red";
  EXPECT_GT(broken.b, broken.g + 40) << "broken: purple";
  options.brokenSprings = false;
  draw();
  const Rgb hidden = lineAt(2);
  EXPECT_EQ(hidden.r, background.r) << "broken springs left out on request";
  EXPECT_EQ(hidden.b, background.b);
  EXPECT_NE(lineAt(0).r, background.r) << "the others still drawn";
}

// The wall's surface (sim::Simulation::enableWallSurface, render/shaders/wall_surface.*): a
// periodic tube seen side on covers its silhouette to its ends (the seam's triangles are drawn
// a period apart and kept inside the domain), nothing beyond it; with every spring in its
// middle third broken, the background shows through there (near and far sides torn) and the
// outer thirds stay covered.
TEST_F(RenderTest, WallSurfaceCoversTheTubeAndTearsWhereSpringsBroke) {
  const scene::Scene scene = scene::parseScene(R"({
    "scene": "wall_surface",
    "particles": { "spacing_m": 5e-4 },
    "fluid": { "density_kg_m3": 1060.0, "viscosity_pa_s": 0.0035, "expected_max_speed_m_s": 0.5 },
    "vessel": { "shape": "tube", "length_m": 0.012, "radius_m": 0.002, "point_mass_kg": 2e-5,
                "stiffness_N_m": 200.0, "damping_N_s_m": 0.01 },
    "forces": { "gravity_m_s2": [0, 0, 0] },
    "domain": { "min_m": [0.0, -0.004, -0.004], "max_m": [0.012, 0.004, 0.004], "periodic": ["x"] }
  })", "wall_surface");
  sim::Simulation sim(ctx(), scene);  // drawn before its first step: the slots of the upload
  const gpu::Buffer& triangles = sim.enableWallSurface();
  ASSERT_GT(sim.wallTriangleCount(), 0u);
  const std::uint32_t W = 400, H = 240;
  render::OffscreenRenderer renderer(ctx(), W, H);
  render::Camera camera;
  camera.eye = glm::vec3(0.006f, -0.06f, 0.0f);
  camera.target = glm::vec3(0.006f, 0.0f, 0.0f);
  camera.fovY = 0.2f;
  camera.nearPlane = 1e-3f;
  camera.farPlane = 1.0f;
  render::FrameOptions options;
  options.particleRadius = 0.0f;
  options.wallOpacity = 1.0f;
  const render::WallSurfaceView view{&sim.store().live().positions, &sim.solver().grid().slotOfId(),
                                     &sim.solver().wall()->springs(), &triangles, &sim.store().live().normals,
                                     sim.wallShade(), sim.wallTriangleCount(), sim.solver().grid().spec().period,
                                     sim.solver().grid().spec().origin};
  auto draw = [&]() {
    gpu::CommandRecorder rec(ctx());
    rec.begin();
    sim.recordWallShade(rec);
    renderer.record(rec, camera, options, {}, nullptr, nullptr, nullptr, &view);
    rec.end();
    rec.submitAndWait();
    return renderer.readPixels();
  };
  const Rgb background{int(std::lround(options.background.r * 255.0f)), int(std::lround(options.background.g * 255.0f)),
                       int(std::lround(options.background.b * 255.0f))};
  // The outer layer's radius and the spacing of its rings along x.
  const sim::Snapshot state = sim.snapshot();
  double rOuter = 0.0;
  for (std::size_t i = 0; i < state.positions.size(); ++i) {
    if (state.velocities[i].w != 0.0f) rOuter = std::max(rOuter, std::hypot(double(state.positions[i].y), double(state.positions[i].z)));
  }
  const float L = 0.012f, dx = 5e-4f;
  // The share of sample points (x, 0, z), x in [x0, x1], |z| in [z0, z1], whose pixel shows
  // the wall (not the background).
  auto covered = [&](const std::vector<std::uint8_t>& rgba, float x0, float x1, float z0, float z1) {
    int hit = 0, all = 0;
    for (float x = x0; x <= x1; x += 1e-4f)
      for (float z = z0; z <= z1; z += 1e-4f)
        for (float sign : {-1.0f, 1.0f}) {
          const glm::vec2 p = project(camera, glm::vec3(x, 0.0f, sign * z), W, H);
          const Rgb c = pixel(rgba, W, std::uint32_t(p.x), std::uint32_t(p.y));
          hit += c.r != background.r || c.g != background.g || c.b != background.b;
          ++all;
        }
    return double(hit) / all;
  };
  const float inside = float(0.85 * rOuter), outside = float(1.15 * rOuter);
  std::vector<std::uint8_t> rgba = draw();
  EXPECT_EQ(covered(rgba, 0.05f * dx, L - 0.05f * dx, 0.0f, inside), 1.0) << "the tube's silhouette, seams included";
  EXPECT_EQ(covered(rgba, 0.05f * dx, L - 0.05f * dx, outside, 1.6f * outside), 0.0) << "beyond the tube";
  const glm::vec2 mid = project(camera, glm::vec3(0.3f * L, 0.0f, 0.0f), W, H);
  const Rgb tissue = pixel(rgba, W, std::uint32_t(mid.x), std::uint32_t(mid.y));
  EXPECT_GT(tissue.r, tissue.g + 20) << "tissue coloured";

  // Break every spring with both ends in the middle third.
  std::vector<sim::GpuSpring> springs = sim.solver().wall()->readSprings();
  std::size_t broken = 0;
  for (sim::GpuSpring& s : springs) {
    const float xa = state.positions[s.a].x, xb = state.positions[s.b].x;
    if (xa > L / 3 && xa < 2 * L / 3 && xb > L / 3 && xb < 2 * L / 3) s.broken = 1u, ++broken;
  }
  ASSERT_GT(broken, 100u);
  std::vector<gpu::Buffer*> buffers;
  sim.solver().wall()->checkpointBuffers(buffers);
  buffers.front()->upload(springs);  // the springs' records come first
  rgba = draw();
  EXPECT_EQ(covered(rgba, L / 3 + dx, 2 * L / 3 - dx, 0.0f, inside), 0.0) << "torn: the background shows through";
  EXPECT_EQ(covered(rgba, 0.05f * dx, L / 3 - 2 * dx, 0.0f, inside), 1.0) << "the first third stays";
  EXPECT_EQ(covered(rgba, 2 * L / 3 + 2 * dx, L - 0.05f * dx, 0.0f, inside), 1.0) << "the last third stays";
  std::printf("wall surface: %u triangles, %zu springs broken in the middle third\n", sim.wallTriangleCount(), broken);
}

}  // namespace
}  // namespace hemo::test
