// Driving a tool by hand (hemo/render/tool_drive.hpp), hemo-view's mouse and keys: the cursor's
// point on the plane facing the camera, the keyframes that take a tool from where it is
// towards the hand's target at a capped speed, and the tools the viewer adds to a scene.
#include "hemo/render/tool_drive.hpp"

#include <gtest/gtest.h>

#include <glm/geometric.hpp>
#include <glm/gtc/quaternion.hpp>

#include <cmath>
#include <random>
#include <string>

namespace hemo::test {
namespace {

TEST(ToolDrive, CursorPointsLieOnThePlaneUnderTheirPixel) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  const glm::vec2 size(640.0f, 360.0f);
  for (int trial = 0; trial < 200; ++trial) {
    render::Camera camera;
    camera.target = 0.01f * glm::vec3(u(rng), u(rng), u(rng));
    glm::vec3 away(u(rng), u(rng), 0.6f * u(rng));
    if (glm::length(away) < 0.2f) away = glm::vec3(0.0f, -1.0f, 0.3f);
    camera.eye = camera.target + 0.05f * glm::normalize(away);
    camera.nearPlane = 1e-3f;
    camera.farPlane = 1.0f;
    const glm::vec3 forward = glm::normalize(camera.target - camera.eye);
    const glm::vec3 through = camera.target + 0.01f * glm::vec3(u(rng), u(rng), u(rng));
    // The view's centre looks along the axis: the plane's point there is on the axis.
    const glm::vec3 centre = render::cursorOnPlane(camera, 0.5f * size, size, through);
    const glm::vec3 onAxis = camera.eye + glm::dot(through - camera.eye, forward) * forward;
    EXPECT_LT(glm::length(centre - onAxis), 1e-7f) << "trial " << trial;
    // Any pixel: the point is on the plane and appears at that pixel.
    const glm::vec2 pixel((0.5f + 0.45f * u(rng)) * size.x, (0.5f + 0.45f * u(rng)) * size.y);
    const glm::vec3 p = render::cursorOnPlane(camera, pixel, size, through);
    EXPECT_LT(std::abs(glm::dot(p - through, forward)), 1e-7f) << "trial " << trial;
    const glm::vec2 back = render::pixelOf(camera, size, p);
    EXPECT_LT(glm::length(back - pixel), 1e-3f) << "trial " << trial;
    // Down the window is down the screen: with z up, a pixel lower in the window is lower in z
    // (the camera's up is +z and it is not looking straight down).
    const glm::vec3 lower = render::cursorOnPlane(camera, pixel + glm::vec2(0.0f, 10.0f), size, through);
    if (std::abs(forward.z) < 0.9f) {
      EXPECT_LT(lower.z, p.z) << "trial " << trial;
    }
  }
}

sim::ToolSpec movingGrasper() {
  sim::ToolSpec tool;
  tool.name = std::string("moving grasper");
  tool.kind = sim::ToolKind::Grasper;
  tool.radius = 2e-4f;
  tool.length = 3e-3f;
  sim::ToolKey a, b;
  a.time = 0.0;
  a.position = glm::vec3(0.0f, 0.0f, 1e-3f);
  a.jawOpening = 2e-3f;
  b.time = 0.01;
  b.position = glm::vec3(4e-3f, 0.0f, 1e-3f);
  b.jawOpening = 1e-3f;
  tool.keys = {a, b};
  return tool;
}

TEST(ToolDrive, HandKeysStartAtThePoseAndReachTheTargetNoFasterThanAllowed) {
  const sim::ToolSpec tool = movingGrasper();
  const double now = 0.005, lead = 1e-3;
  const float speed = 0.5f;  // 0.5 mm in the lead time
  // Half-way along its scene path: x = 2 mm, jaws 1.5 mm.
  render::HandTarget near;
  near.position = glm::vec3(2.3e-3f, 0.1e-3f, 1e-3f);  // 0.32 mm away: reached
  near.jawOpening = 1.2e-3f;                           // 0.3 mm closer: reached
  std::vector<sim::ToolKey> keys = render::handKeys(tool, now, lead, near, speed);
  ASSERT_EQ(keys.size(), 2u);
  EXPECT_DOUBLE_EQ(keys[0].time, now);
  EXPECT_DOUBLE_EQ(keys[1].time, now + lead);
  EXPECT_NEAR(keys[0].position.x, 2e-3f, 1e-9f);
  EXPECT_NEAR(keys[0].jawOpening, 1.5e-3f, 1e-9f);
  EXPECT_LT(glm::length(keys[1].position - near.position), 1e-9f);
  EXPECT_NEAR(keys[1].jawOpening, 1.2e-3f, 1e-9f);
  EXPECT_FALSE(keys[0].cutting);
  sim::ToolSpec driven = tool;
  driven.keys = keys;
  EXPECT_NO_THROW(driven.validate());

  render::HandTarget far;
  far.position = glm::vec3(2e-3f, 3e-3f, 5e-3f);  // 5 mm away: 0.5 mm of it
  far.jawOpening = 0.0f;                          // 1.5 mm to close: 0.5 mm of it
  keys = render::handKeys(tool, now, lead, far, speed);
  ASSERT_EQ(keys.size(), 2u);
  const glm::vec3 step = keys[1].position - keys[0].position;
  EXPECT_NEAR(glm::length(step), 0.5e-3f, 1e-8f);
  EXPECT_NEAR(glm::dot(glm::normalize(step), glm::vec3(0.0f, 0.6f, 0.8f)), 1.0f, 1e-5f);
  EXPECT_NEAR(keys[1].jawOpening, 1.0e-3f, 1e-8f);
  EXPECT_EQ(keys[0].orientation, keys[1].orientation);
  // No lead: one key, the pose now.
  keys = render::handKeys(tool, now, 0.0, far, speed);
  ASSERT_EQ(keys.size(), 1u);
  EXPECT_NEAR(keys[0].position.x, 2e-3f, 1e-9f);
}

TEST(ToolDrive, OnlyABladeCutsAndOnlyOnItsWay) {
  sim::ToolSpec blade = movingGrasper();
  blade.kind = sim::ToolKind::Blade;
  for (sim::ToolKey& k : blade.keys) k.jawOpening = 0.0f;
  render::HandTarget target;
  target.position = glm::vec3(0.0f);
  target.cutting = true;
  target.jawOpening = 1e-3f;  // ignored: a blade has no jaws
  const std::vector<sim::ToolKey> keys = render::handKeys(blade, 0.002, 1e-3, target, 1.0f);
  ASSERT_EQ(keys.size(), 2u);
  EXPECT_TRUE(keys[0].cutting);
  EXPECT_FALSE(keys[1].cutting);
  EXPECT_EQ(keys[1].jawOpening, 0.0f);
  blade.keys = keys;
  EXPECT_NO_THROW(blade.validate());
  sim::ToolSpec probe = movingGrasper();
  probe.kind = sim::ToolKind::Probe;
  for (sim::ToolKey& k : probe.keys) k.jawOpening = 0.0f;
  const std::vector<sim::ToolKey> pk = render::handKeys(probe, 0.002, 1e-3, target, 1.0f);
  EXPECT_FALSE(pk[0].cutting);
  EXPECT_EQ(pk[1].jawOpening, 0.0f);
  probe.keys = pk;
  EXPECT_NO_THROW(probe.validate());
}

TEST(ToolDrive, HandToolsStartOutsideTheParticlesAndInsideTheDomain) {
  const float dp = 2e-4f;
  const glm::vec3 lo(0.0f, -2e-3f, -2e-3f), hi(1e-2f, 2e-3f, 5e-3f);
  const glm::vec3 dmin(0.0f, -4e-3f, -3e-3f), dmax(1e-2f, 4e-3f, 8e-3f);
  for (sim::ToolKind kind : {sim::ToolKind::Probe, sim::ToolKind::Blade}) {
    const sim::ToolSpec tool = render::handTool(kind, dp, lo, hi, dmin, dmax);
    EXPECT_NO_THROW(tool.validate());
    ASSERT_EQ(tool.keys.size(), 1u);
    EXPECT_GT(tool.keys[0].position.z - tool.radius, hi.z);
    EXPECT_LE(tool.keys[0].position.z, dmax.z);
  }
  const sim::ToolSpec grasper = render::handTool(sim::ToolKind::Grasper, dp, lo, hi, dmin, dmax);
  EXPECT_NO_THROW(grasper.validate());
  const sim::ToolKey& key = grasper.keys[0];
  // Jaws side by side across y, open wider than the particles, spanning them in z.
  const glm::vec3 side = key.orientation * glm::vec3(1.0f, 0.0f, 0.0f);
  EXPECT_NEAR(std::abs(side.y), 1.0f, 1e-6f);
  EXPECT_GT(key.jawOpening - 2.0f * grasper.radius, hi.y - lo.y);
  EXPECT_LT(key.position.z, lo.z);
  EXPECT_GT(key.position.z + grasper.length, hi.z);
  EXPECT_GE(key.position.z, dmin.z);
  // A particle box at the domain's top: the tip is kept inside the domain.
  const sim::ToolSpec top = render::handTool(sim::ToolKind::Probe, dp, lo, dmax, dmin, dmax);
  EXPECT_LE(top.keys[0].position.z, dmax.z);
}

}  // namespace
}  // namespace hemo::test
