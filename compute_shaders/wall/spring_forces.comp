#version 450
// Spring forces on wall particles, gathered per particle over its springs (CSR adjacency by
// particle id; no atomics): a = sum of the forces of the unbroken springs / mass + gravity,
// zero for anchored particles; and the particle's time-step limit
// min(C sqrt(mass / sum of its unbroken stiffnesses), C_a h / (c0 + |v|)) (the first bounds
// the phase error of its fastest oscillation; C is push.timeStepFactor; the second is the
// fluid's acoustic limit, which the neighbour-list look-ahead relies on). Other particle kinds are left alone.
#extension GL_GOOGLE_include_directive : require
#include "interface/sph.h"
#include "interface/wall.h"
#include "common/index.glsl"
#include "wall/spring.glsl"

layout(std430, binding = HEMO_SPRINGF_BINDING_POSITIONS) readonly buffer Positions { vec4 positions[]; };
layout(std430, binding = HEMO_SPRINGF_BINDING_VELOCITIES) readonly buffer Velocities { vec4 velocities[]; };
layout(std430, binding = HEMO_SPRINGF_BINDING_IDS) readonly buffer Ids { uint ids[]; };
layout(std430, binding = HEMO_SPRINGF_BINDING_SLOT_OF_ID) readonly buffer SlotOfId { uint slotOfId[]; };
layout(std430, binding = HEMO_SPRINGF_BINDING_SPRINGS) readonly buffer Springs { Spring springs[]; };
layout(std430, binding = HEMO_SPRINGF_BINDING_FIRST) readonly buffer First { uint first[]; };
layout(std430, binding = HEMO_SPRINGF_BINDING_SPRINGS_OF) readonly buffer SpringsOf { uint springsOf[]; };
layout(std430, binding = HEMO_SPRINGF_BINDING_WALL_INFO) readonly buffer WallInfo { vec4 wallInfo[]; };
layout(std430, binding = HEMO_SPRINGF_BINDING_ACCEL) writeonly buffer Accel { vec4 accel[]; };
layout(std430, binding = HEMO_SPRINGF_BINDING_DT_LIMIT) writeonly buffer DtLimit { float dtLimit[]; };
layout(push_constant) uniform Push {
  vec4 gravity;
  uint n;
  uint idCount;
  float timeStepFactor;
  float acousticLength;  // C_a h (m): the fluid's acoustic limit C_a h / (c0 + |v|) applies too
  float c0;
} pc;

void main() {
  const uint slot = hemo_global_index();
  if (slot >= pc.n || uint(velocities[slot].w) != HEMO_KIND_WALL) {
    return;
  }
  const uint id = ids[slot];
  if (id >= pc.idCount) {
    return;  // not part of the spring network
  }
  const vec4 info = wallInfo[id];
  if (info.y != 0.0) {
    accel[slot] = vec4(0.0);  // anchored
    dtLimit[slot] = 3.0e38;
    return;
  }
  vec3 force = vec3(0.0);
  float stiffness = 0.0;
  const uint end = first[id + 1u];
  for (uint e = first[id]; e < end; ++e) {
    const Spring s = springs[springsOf[e]];
    if (s.broken != 0u) {
      continue;
    }
    const uint sa = slotOfId[s.a];
    const uint sb = slotOfId[s.b];
    float tension;
    const vec3 fa = hemo_spring_force_on_a(positions[sa].xyz, positions[sb].xyz, velocities[sa].xyz,
                                           velocities[sb].xyz, s.restLength, s.stiffness, s.damping, tension);
    force += id == s.a ? fa : -fa;
    stiffness += s.stiffness;
  }
  accel[slot] = vec4(force / info.x + pc.gravity.xyz, 0.0);
  const float acoustic = pc.acousticLength / (pc.c0 + length(velocities[slot].xyz));
  dtLimit[slot] = stiffness > 0.0 ? min(acoustic, pc.timeStepFactor * sqrt(info.x / stiffness)) : acoustic;
}
