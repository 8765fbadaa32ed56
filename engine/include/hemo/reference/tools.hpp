#pragma once
// CPU double-precision twin of the tools' contact (tool/contact.comp, tool/reduce.comp).
#include "hemo/sim/tools.hpp"

#include <glm/gtc/quaternion.hpp>
#include <glm/vec3.hpp>

#include <vector>

namespace hemo::reference {

struct RefToolPose {
  glm::dvec3 position{0.0};     // m: the tip
  glm::dquat orientation{1.0, 0.0, 0.0, 0.0};
  glm::dvec3 axis{0.0, 0.0, 1.0};  // the shaft's direction
  glm::dvec3 side{1.0, 0.0, 0.0};  // the jaws' direction
  double opening = 0.0;            // m: a grasper's jaw opening
  double speed = 0.0;           // m/s: the bound on the surface's speed between the keys around t
  glm::dvec3 velocity{0.0};     // m/s: of the tip
  glm::dvec3 spin{0.0};         // rad/s: the angular velocity
  bool cutting = false;         // a blade whose last key at or before t cuts
};

// The tool's pose at time t (s): held before the first key and after the last, else
// interpolated between the two keys around t (interface/tool.h).
RefToolPose toolPose(const sim::ToolSpec& tool, double t);

// The push a tool at `pose` gives a particle at x (m/s^2): along the surface normal,
// psi (1 - q) / sqrt(q), q = max(gap / 2h, 1e-3), where the gap to the capsule's surface is
// below the contact distance; else 0. `arm` gets x - position (minimum image on axes with
// a non-zero period).
// `squeezed`, if given, gets whether x lies within the contact distance of both of a
// grasper's jaws.
glm::dvec3 toolAcceleration(const sim::ToolSpec& tool, const RefToolPose& pose, double psi, double h,
                            const glm::dvec3& x, const glm::dvec3& period, glm::dvec3* arm = nullptr,
                            bool* squeezed = nullptr);

struct RefToolContact {
  std::vector<glm::dvec3> accel;   // per particle: the sum of the tools' pushes (m/s^2)
  std::vector<glm::dvec3> force;   // per tool: -sum m a (N)
  std::vector<glm::dvec3> torque;  // per tool: about its position (N m)
  std::vector<RefToolPose> poses;
};

// Grasping (interface/tool.h, "Grasping"), per particle.
struct RefGrips {
  std::vector<bool> grippable;       // a free wall point of the spring network
  std::vector<glm::dvec3> velocity;  // m/s
  std::vector<glm::dvec4> record;    // its grip record (a, b, 0, tool + 1), read and updated
  double timeStepFactor = 0.1;       // the wall's C
  std::vector<double> limit;         // out: a gripped point's C sqrt(m / k_grip), else 0
};

// Every tool against every particle; a particle of mass 0 is left alone (rigid boundary
// particles and anchored wall points). psi_k = contactScale_k psiPerScale. With `grips`,
// graspers also grip the grippable points they squeeze (pull added to accel, the reaction to
// the tool's force and torque).
RefToolContact toolContact(const std::vector<sim::ToolSpec>& tools, double t, const std::vector<glm::dvec3>& x,
                           const std::vector<double>& mass, double psiPerScale, double h,
                           const glm::dvec3& period = glm::dvec3(0.0), RefGrips* grips = nullptr);

// Whether the segment from p to q crosses the surface an edge swept from (a0, b0) to
// (a1, b1), taken as the triangles (a0, b0, b1) and (a0, b1, a1) (tool/cut.comp). `margin`, if
// given, gets how far the crossing (or the nearest miss) lies from the tests' boundaries in
// their parameters (barycentric and along the segment; 0 on a boundary), so a caller can leave
// out cases that float rounding may decide either way.
bool sweptEdgeCrosses(const glm::dvec3& a0, const glm::dvec3& b0, const glm::dvec3& a1, const glm::dvec3& b1,
                      const glm::dvec3& p, const glm::dvec3& q, double* margin = nullptr);

}  // namespace hemo::reference
