#version 450
// Rupture: a spring whose tension exceeds its maximum force is flagged broken, for good
// (one invocation per spring; only that invocation writes the flag). The number of broken
// springs is counted with an integer atomic (order-independent).
#extension GL_GOOGLE_include_directive : require
#include "interface/sph.h"
#include "interface/wall.h"
#include "common/index.glsl"
#include "wall/spring.glsl"
#include "common/sph_params.glsl"

layout(std430, binding = HEMO_RUPTURE_BINDING_POSITIONS) readonly buffer Positions { vec4 positions[]; };
layout(std430, binding = HEMO_RUPTURE_BINDING_VELOCITIES) readonly buffer Velocities { vec4 velocities[]; };
layout(std430, binding = HEMO_RUPTURE_BINDING_SLOT_OF_ID) readonly buffer SlotOfId { uint slotOfId[]; };
layout(std430, binding = HEMO_RUPTURE_BINDING_SPRINGS) buffer Springs { Spring springs[]; };
layout(std430, binding = HEMO_RUPTURE_BINDING_COUNTERS) buffer Counters { uint counters[]; };
HEMO_SPH_PARAMS_UNIFORM(HEMO_RUPTURE_BINDING_PARAMS);
layout(push_constant) uniform Push { uint springCount; } pc;

void main() {
  const uint k = hemo_global_index();
  if (k >= pc.springCount) {
    return;
  }
  const Spring s = springs[k];
  if (s.broken != 0u) {
    return;
  }
  const uint sa = slotOfId[s.a];
  const uint sb = slotOfId[s.b];
  float tension;
  const vec3 delta = hemo_min_image(positions[sb].xyz - positions[sa].xyz, hemo_pair_params());
  hemo_spring_force_on_a(delta, velocities[sa].xyz, velocities[sb].xyz, s.restLength, s.stiffness, s.damping, tension);
  if (tension > s.maxForce) {
    springs[k].broken = 1u;
    atomicAdd(counters[HEMO_WALL_COUNTER_BROKEN], 1u);
  }
}
