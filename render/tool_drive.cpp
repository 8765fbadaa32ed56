// Driving a tool by hand (tool_drive.hpp).
#include "hemo/render/tool_drive.hpp"

#include "hemo/reference/tools.hpp"

#include <glm/geometric.hpp>
#include <glm/gtc/quaternion.hpp>
#include <glm/mat4x4.hpp>

#include <algorithm>
#include <cmath>

namespace hemo::render {

namespace {

glm::dmat4 viewProjection(const Camera& camera, glm::vec2 viewSize) {
  return glm::dmat4(camera.projection(viewSize.x / viewSize.y)) * glm::dmat4(camera.view());
}

}  // namespace

glm::vec3 cursorOnPlane(const Camera& camera, glm::vec2 pixel, glm::vec2 viewSize, glm::vec3 through) {
  // Vulkan's clip space: x right, y down, both -1..1 across the view; depth 0 near, 1 far.
  const glm::dmat4 inverse = glm::inverse(viewProjection(camera, viewSize));
  const double nx = 2.0 * double(pixel.x) / viewSize.x - 1.0, ny = 2.0 * double(pixel.y) / viewSize.y - 1.0;
  const glm::dvec4 nearPoint = inverse * glm::dvec4(nx, ny, 0.0, 1.0), farPoint = inverse * glm::dvec4(nx, ny, 1.0, 1.0);
  const glm::dvec3 a = glm::dvec3(nearPoint) / nearPoint.w, b = glm::dvec3(farPoint) / farPoint.w;
  const glm::dvec3 normal = glm::normalize(glm::dvec3(camera.target) - glm::dvec3(camera.eye));
  const glm::dvec3 ray = b - a;
  const double along = glm::dot(ray, normal);
  if (std::abs(along) < 1e-300) return through;  // cannot happen for a perspective camera
  const double s = glm::dot(glm::dvec3(through) - a, normal) / along;
  return glm::vec3(a + s * ray);
}

glm::vec2 pixelOf(const Camera& camera, glm::vec2 viewSize, glm::vec3 point) {
  const glm::dvec4 clip = viewProjection(camera, viewSize) * glm::dvec4(glm::dvec3(point), 1.0);
  return glm::vec2(float((clip.x / clip.w + 1.0) * 0.5 * viewSize.x), float((clip.y / clip.w + 1.0) * 0.5 * viewSize.y));
}

std::vector<sim::ToolKey> handKeys(const sim::ToolSpec& tool, double now, double lead, const HandTarget& target,
                                   float maxSpeed) {
  const reference::RefToolPose pose = reference::toolPose(tool, now);
  sim::ToolKey from;
  from.time = now;
  from.position = glm::vec3(pose.position);
  from.orientation = glm::normalize(glm::quat(pose.orientation));
  from.jawOpening = tool.kind == sim::ToolKind::Grasper ? float(pose.opening) : 0.0f;
  if (!(lead > 0.0)) return {from};
  from.cutting = tool.kind == sim::ToolKind::Blade && target.cutting;
  sim::ToolKey to = from;
  to.time = now + lead;
  to.cutting = false;
  const double reach = double(std::max(maxSpeed, 0.0f)) * lead;
  glm::dvec3 move = glm::dvec3(target.position) - glm::dvec3(from.position);
  const double distance = glm::length(move);
  if (distance > reach) move *= reach / distance;
  to.position = glm::vec3(glm::dvec3(from.position) + move);
  if (tool.kind == sim::ToolKind::Grasper) {
    const double change = std::clamp(double(std::max(target.jawOpening, 0.0f)) - double(from.jawOpening), -reach, reach);
    to.jawOpening = std::max(float(double(from.jawOpening) + change), 0.0f);
  }
  return {from, to};
}

sim::ToolSpec handTool(sim::ToolKind kind, float spacing, glm::vec3 lo, glm::vec3 hi, glm::vec3 domainMin,
                       glm::vec3 domainMax) {
  sim::ToolSpec tool;
  tool.kind = kind;
  const glm::vec3 centre = 0.5f * (lo + hi);
  sim::ToolKey key;
  if (kind == sim::ToolKind::Grasper) {
    tool.name = "hand grasper";
    tool.radius = 0.75f * spacing;
    tool.jawWidth = 2.0f * spacing;
    const float below = lo.z - 2.0f * tool.radius;
    tool.length = (hi.z + 2.0f * tool.radius) - below;
    // The jaws side by side across y: the tool's frame turned a quarter about z (x -> y).
    key.orientation = glm::angleAxis(0.5f * 3.14159265f, glm::vec3(0.0f, 0.0f, 1.0f));
    key.position = glm::vec3(centre.x, centre.y, below);
    key.jawOpening = (hi.y - lo.y) + 4.0f * spacing;
  } else {
    tool.name = kind == sim::ToolKind::Blade ? "hand blade" : "hand probe";
    tool.radius = kind == sim::ToolKind::Blade ? 0.25f * spacing : 1.5f * spacing;
    tool.length = kind == sim::ToolKind::Blade ? 6.0f * spacing : 12.0f * spacing;
    key.position = glm::vec3(centre.x, centre.y, hi.z + tool.radius + 2.0f * spacing);
  }
  key.position = glm::clamp(key.position, domainMin, domainMax);
  tool.keys = {key};
  return tool;
}

}  // namespace hemo::render
