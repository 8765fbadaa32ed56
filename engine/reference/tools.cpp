#include "hemo/reference/tools.hpp"

#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>

namespace hemo::reference {

namespace {
glm::dquat toDouble(const glm::quat& q) { return glm::dquat(q.w, q.x, q.y, q.z); }
double dot4(const glm::dquat& a, const glm::dquat& b) { return a.w * b.w + a.x * b.x + a.y * b.y + a.z * b.z; }
}  // namespace

RefToolPose toolPose(const sim::ToolSpec& tool, double t) {
  const auto& keys = tool.keys;
  std::size_t a = 0;
  for (std::size_t k = 1; k < keys.size(); ++k) {
    if (keys[k].time <= t) a = k;
  }
  const std::size_t b = std::min(a + 1, keys.size() - 1);
  const glm::dquat qa = glm::normalize(toDouble(keys[a].orientation));
  glm::dquat qb = glm::normalize(toDouble(keys[b].orientation));
  if (dot4(qa, qb) < 0.0) qb = -qb;
  const double span = keys[b].time - keys[a].time;
  const bool moving = b != a && t >= keys[a].time && t < keys[b].time && span > 0.0;
  const double s = moving ? std::clamp((t - keys[a].time) / span, 0.0, 1.0) : 0.0;
  RefToolPose p;
  const glm::dvec3 pa(keys[a].position), pb(keys[b].position);
  p.position = pa + s * (pb - pa);
  glm::dquat q(qa.w + s * (qb.w - qa.w), qa.x + s * (qb.x - qa.x), qa.y + s * (qb.y - qa.y), qa.z + s * (qb.z - qa.z));
  p.orientation = glm::normalize(q);
  if (moving) {
    p.velocity = (pb - pa) / span;
    // the derivative of q / |q| along the keys, and the spin 2 (dq/dt) q*
    const glm::dquat dm((qb.w - qa.w) / span, (qb.x - qa.x) / span, (qb.y - qa.y) / span, (qb.z - qa.z) / span);
    const glm::dquat& n = p.orientation;
    const double along = dot4(n, dm), len = std::sqrt(dot4(q, q));
    const glm::dquat dq((dm.w - n.w * along) / len, (dm.x - n.x * along) / len, (dm.y - n.y * along) / len,
                        (dm.z - n.z * along) / len);
    const glm::dquat w = dq * glm::conjugate(n);
    p.spin = 2.0 * glm::dvec3(w.x, w.y, w.z);
  }
  p.axis = p.orientation * glm::dvec3(0.0, 0.0, 1.0);
  p.side = p.orientation * glm::dvec3(1.0, 0.0, 0.0);
  const double oa = keys[a].jawOpening, ob = keys[b].jawOpening;
  p.opening = oa + s * (ob - oa);
  const double turn = 2.0 * std::acos(std::clamp(std::abs(dot4(qa, qb)), 0.0, 1.0));
  const bool grasper = tool.kind == sim::ToolKind::Grasper;
  const double reach = double(tool.radius) + tool.length +
                       (grasper ? 0.5 * std::max(oa, ob) + tool.radius + 0.5 * double(tool.jawWidth) : 0.0);
  p.speed = moving ? (glm::length(pb - pa) + 1.25 * turn * reach + 0.5 * std::abs(ob - oa)) / span : 0.0;
  p.cutting = tool.kind == sim::ToolKind::Blade && t >= keys[a].time && keys[a].cutting;
  return p;
}

namespace {
// Moeller and Trumbore's segment-triangle test in double; `margin` the least distance of the
// parameters from their bounds (negative when outside).
bool segmentMeetsTriangle(const glm::dvec3& p, const glm::dvec3& d, const glm::dvec3& v0, const glm::dvec3& v1,
                          const glm::dvec3& v2, double& margin) {
  const glm::dvec3 e1 = v1 - v0, e2 = v2 - v0;
  const glm::dvec3 pv = glm::cross(d, e2);
  const double det = glm::dot(e1, pv);
  if (det == 0.0) {
    margin = 0.0;
    return false;
  }
  const glm::dvec3 tv = p - v0;
  const double u = glm::dot(tv, pv) / det;
  const glm::dvec3 qv = glm::cross(tv, e1);
  const double v = glm::dot(d, qv) / det;
  const double s = glm::dot(e2, qv) / det;
  margin = std::min({u, v, 1.0 - u - v, s, 1.0 - s});
  return margin >= 0.0;
}
}  // namespace

bool sweptEdgeCrosses(const glm::dvec3& a0, const glm::dvec3& b0, const glm::dvec3& a1, const glm::dvec3& b1,
                      const glm::dvec3& p, const glm::dvec3& q, double* margin) {
  double m1 = 0.0, m2 = 0.0;
  const bool hit1 = segmentMeetsTriangle(p, q - p, a0, b0, b1, m1);
  const bool hit2 = segmentMeetsTriangle(p, q - p, a0, b1, a1, m2);
  // the two triangles share the diagonal a0-b1: a crossing on it counts once, and is far
  // from both tests' outer bounds
  if (margin) *margin = hit1 || hit2 ? std::max(m1, m2) : std::min(std::abs(m1), std::abs(m2));
  return hit1 || hit2;
}

namespace {
// The points within `radius` of the rectangle from `base` spanned by `axis` (length `len`)
// and `lateral` (half-width either side; 0: a capsule), as tool/contact.comp.
glm::dvec3 slabPush(const glm::dvec3& arm, const glm::dvec3& base, const glm::dvec3& axis, const glm::dvec3& lateral,
                    double len, double halfWidth, double radius, double reach, double psi, double h, double& gap) {
  const glm::dvec3 rel = arm - base;
  const double along = std::clamp(glm::dot(rel, axis), 0.0, len);
  const double across = std::clamp(glm::dot(rel, lateral), -halfWidth, halfWidth);
  const glm::dvec3 off = rel - along * axis - across * lateral;
  const double dist = glm::length(off);
  gap = dist - radius;
  if (!(gap < reach)) return glm::dvec3(0.0);
  glm::dvec3 normal;
  if (dist > 1e-6 * radius) {
    normal = off / dist;
  } else {
    const glm::dvec3 other = halfWidth > 0.0 ? lateral
                             : std::abs(axis.x) < 0.9 ? glm::dvec3(1.0, 0.0, 0.0)
                                                      : glm::dvec3(0.0, 1.0, 0.0);
    normal = glm::normalize(glm::cross(axis, other));
  }
  const double q = std::max(gap / (2.0 * h), 1e-3);
  return psi * (1.0 - q) / std::sqrt(q) * normal;
}
}  // namespace

glm::dvec3 toolAcceleration(const sim::ToolSpec& tool, const RefToolPose& pose, double psi, double h,
                            const glm::dvec3& x, const glm::dvec3& period, glm::dvec3* armOut, bool* squeezed) {
  glm::dvec3 arm = x - pose.position;
  for (int a = 0; a < 3; ++a) {
    if (period[a] > 0.0) arm[a] -= period[a] * std::round(arm[a] / period[a]);
  }
  if (armOut) *armOut = arm;
  if (squeezed) *squeezed = false;
  const double len = tool.length, radius = tool.radius, reach = tool.contactDistance;
  double gap = 0.0, other = 0.0;
  if (tool.kind != sim::ToolKind::Grasper) {
    return slabPush(arm, glm::dvec3(0.0), pose.axis, pose.side, len, 0.0, radius, reach, psi, h, gap);
  }
  const glm::dvec3 lateral = glm::cross(pose.axis, pose.side);
  const glm::dvec3 side = (0.5 * pose.opening + radius) * pose.side;
  const double halfWidth = 0.5 * double(tool.jawWidth);
  const glm::dvec3 push = slabPush(arm, side, pose.axis, lateral, len, halfWidth, radius, reach, psi, h, gap) +
                          slabPush(arm, -side, pose.axis, lateral, len, halfWidth, radius, reach, psi, h, other);
  if (squeezed) *squeezed = gap < reach && other < reach;
  return push;
}

RefToolContact toolContact(const std::vector<sim::ToolSpec>& tools, double t, const std::vector<glm::dvec3>& x,
                           const std::vector<double>& mass, double psiPerScale, double h, const glm::dvec3& period,
                           RefGrips* grips) {
  RefToolContact r;
  r.accel.assign(x.size(), glm::dvec3(0.0));
  r.force.assign(tools.size(), glm::dvec3(0.0));
  r.torque.assign(tools.size(), glm::dvec3(0.0));
  for (const sim::ToolSpec& tool : tools) r.poses.push_back(toolPose(tool, t));
  if (grips) grips->limit.assign(x.size(), 0.0);
  for (std::size_t i = 0; i < x.size(); ++i) {
    if (!(mass[i] > 0.0)) continue;
    const bool grippable = grips && grips->grippable[i];
    const std::size_t holder = grippable ? std::size_t(grips->record[i].w) : 0;  // tool + 1
    std::size_t gripper = 0;
    glm::dvec3 arm(0.0);  // from the gripper's tip
    for (std::size_t k = 0; k < tools.size(); ++k) {
      glm::dvec3 toTool;
      bool squeezed = false;
      const glm::dvec3 a = toolAcceleration(tools[k], r.poses[k], double(tools[k].contactScale) * psiPerScale, h, x[i],
                                            period, &toTool, &squeezed);
      r.accel[i] += a;
      r.force[k] -= mass[i] * a;
      r.torque[k] += glm::cross(toTool, -mass[i] * a);
      // the holder keeps it while it squeezes it, else the first grasper that squeezes it
      if (grippable && squeezed && tools[k].gripStiffness > 0.0f && (gripper == 0 || k + 1 == holder)) {
        gripper = k + 1;
        arm = toTool;
      }
    }
    if (!grippable) continue;
    if (gripper == 0) {
      grips->record[i] = glm::dvec4(0.0);
      continue;
    }
    const std::size_t k = gripper - 1;
    const RefToolPose& pose = r.poses[k];
    const glm::dvec3 lateral = glm::cross(pose.axis, pose.side);
    if (gripper != holder) grips->record[i] = glm::dvec4(glm::dot(arm, pose.axis), glm::dot(arm, lateral), 0.0, double(gripper));
    const glm::dvec4& anchor = grips->record[i];
    const double omega = std::sqrt(double(tools[k].gripStiffness) / mass[i]);
    const glm::dvec3 slip = pose.velocity + glm::cross(pose.spin, arm) - grips->velocity[i];
    const glm::dvec3 a =
        (omega * omega * (anchor.x - glm::dot(arm, pose.axis)) + 2.0 * omega * glm::dot(slip, pose.axis)) * pose.axis +
        (omega * omega * (anchor.y - glm::dot(arm, lateral)) + 2.0 * omega * glm::dot(slip, lateral)) * lateral;
    r.accel[i] += a;
    r.force[k] -= mass[i] * a;
    r.torque[k] += glm::cross(arm, -mass[i] * a);
    grips->limit[i] = grips->timeStepFactor * std::sqrt(mass[i] / tools[k].gripStiffness);
  }
  return r;
}

}  // namespace hemo::reference
