// The tools' surfaces as triangles for drawing (renderer.hpp, toolTriangles), at the poses the
// GPU's contact pass uses (the double twin of tool/contact.comp's pose, reference/tools.hpp).
#include "hemo/reference/tools.hpp"
#include "hemo/render/renderer.hpp"

#include <glm/geometric.hpp>

#include <cmath>
#include <numbers>

namespace hemo::render {

namespace {

// Emits triangles into `out`, given points and normals in the tool's frame (x: the jaws'
// direction, y: across the jaws, z: the shaft), placed by the pose.
struct Emitter {
  const reference::RefToolPose& pose;
  std::vector<glm::vec4>& out;
  glm::dvec3 lateral() const { return glm::cross(pose.axis, pose.side); }
  glm::dvec3 place(const glm::dvec3& local) const {
    return pose.position + local.x * pose.side + local.y * lateral() + local.z * pose.axis;
  }
  glm::dvec3 turn(const glm::dvec3& local) const { return local.x * pose.side + local.y * lateral() + local.z * pose.axis; }
  void vertex(const glm::dvec3& p, const glm::dvec3& n) {
    out.emplace_back(glm::vec3(place(p)), 1.0f);
    out.emplace_back(glm::vec3(glm::normalize(turn(n))), 0.0f);
  }
  void quad(const glm::dvec3 p[4], const glm::dvec3 n[4]) {
    for (int i : {0, 1, 2, 0, 2, 3}) vertex(p[i], n[i]);
  }
};

// A capsule in the tool's frame: the segment from `base` along z (length `len`) grown by r.
void capsule(Emitter& e, const glm::dvec3& base, double len, double r, int segments) {
  const int half = segments / 4 + 1;  // rings per hemisphere
  // rings from the bottom pole up: latitude -pi/2..0 around z = 0, then 0..pi/2 around z = len
  std::vector<std::pair<double, double>> rings;  // (latitude, centre z)
  for (int i = 0; i <= half; ++i) rings.emplace_back(-0.5 * std::numbers::pi * (1.0 - double(i) / half), 0.0);
  for (int i = 0; i <= half; ++i) rings.emplace_back(0.5 * std::numbers::pi * double(i) / half, len);
  for (std::size_t k = 0; k + 1 < rings.size(); ++k) {
    for (int j = 0; j < segments; ++j) {
      glm::dvec3 p[4], n[4];
      const double a0 = 2.0 * std::numbers::pi * j / segments, a1 = 2.0 * std::numbers::pi * (j + 1) / segments;
      const std::pair<double, double> corners[4] = {rings[k], rings[k], rings[k + 1], rings[k + 1]};
      const double angles[4] = {a0, a1, a1, a0};
      for (int c = 0; c < 4; ++c) {
        const double lat = corners[c].first;
        n[c] = glm::dvec3(std::cos(lat) * std::cos(angles[c]), std::cos(lat) * std::sin(angles[c]), std::sin(lat));
        p[c] = base + glm::dvec3(0.0, 0.0, corners[c].second) + r * n[c];
      }
      e.quad(p, n);
    }
  }
}

// An axis-aligned box in the tool's frame, [lo, hi], with flat faces.
void box(Emitter& e, const glm::dvec3& lo, const glm::dvec3& hi) {
  for (int axis = 0; axis < 3; ++axis) {
    for (int sign : {-1, 1}) {
      glm::dvec3 n(0.0);
      n[axis] = sign;
      const int u = (axis + 1) % 3, v = (axis + 2) % 3;
      glm::dvec3 p[4], ns[4];
      const double uv[4][2] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
      for (int c = 0; c < 4; ++c) {  // (the renderer culls no faces: any winding)
        p[c][axis] = sign > 0 ? hi[axis] : lo[axis];
        p[c][u] = uv[c][0] > 0 ? hi[u] : lo[u];
        p[c][v] = uv[c][1] > 0 ? hi[v] : lo[v];
        ns[c] = n;
      }
      e.quad(p, ns);
    }
  }
}

}  // namespace

std::vector<glm::vec4> toolTriangles(const std::vector<sim::ToolSpec>& tools, double t, int segments) {
  std::vector<glm::vec4> out;
  segments = std::max(segments, 4);
  for (const sim::ToolSpec& tool : tools) {
    if (tool.keys.empty()) continue;
    const reference::RefToolPose pose = reference::toolPose(tool, t);
    Emitter e{pose, out};
    const double r = tool.radius, len = tool.length;
    if (tool.kind != sim::ToolKind::Grasper) {
      capsule(e, glm::dvec3(0.0), len, r, segments);
      continue;
    }
    const double centre = 0.5 * pose.opening + r, hw = 0.5 * double(tool.jawWidth);
    for (const double side : {centre, -centre}) {
      if (hw > 0.0) {
        box(e, glm::dvec3(side - r, -hw - r, -r), glm::dvec3(side + r, hw + r, len + r));
      } else {
        capsule(e, glm::dvec3(side, 0.0, 0.0), len, r, segments);
      }
    }
  }
  return out;
}

}  // namespace hemo::render
