#version 450
// The wall's substeps (interface/wall.h, HEMO_SUBSTEP_*): N substeps of dt / N per fluid step
// for the wall particles in the slots [first, n), the fluid's force held for the step.
//   ADVANCE  v += a h, x += v h (h = dt / N; the settling damping as the integrator's; periodic
//            positions wrapped), for free wall particles of the spring network
//   FORCE    a = (the unbroken springs at the current positions and velocities) / m + held,
//            with rupture; a particle whose last spring breaks is marked for detachment in
//            accel.w, counted once (a mark from an earlier substep stays)
// Anchored particles stay put (a = 0). Other slots are left alone.
#extension GL_GOOGLE_include_directive : require
#include "interface/sph.h"
#include "interface/wall.h"
#include "common/index.glsl"
#include "common/sph_params.glsl"
#include "common/clock.glsl"
#include "common/step_dt.glsl"
#include "wall/spring.glsl"

layout(std430, binding = HEMO_SUBSTEP_BINDING_POSITIONS) buffer Positions { vec4 positionsW[]; };
layout(std430, binding = HEMO_SUBSTEP_BINDING_VELOCITIES) buffer Velocities { vec4 velocitiesW[]; };
layout(binding = HEMO_SUBSTEP_BINDING_POSITIONS_IN) uniform samplerBuffer positionsT;
layout(binding = HEMO_SUBSTEP_BINDING_VELOCITIES_IN) uniform samplerBuffer velocitiesT;
layout(binding = HEMO_SUBSTEP_BINDING_IDS) uniform usamplerBuffer idsT;
layout(binding = HEMO_SUBSTEP_BINDING_SLOT_OF_ID) uniform usamplerBuffer slotOfIdT;
layout(binding = HEMO_SUBSTEP_BINDING_SPRINGS) uniform usamplerBuffer springsT;
layout(binding = HEMO_SUBSTEP_BINDING_FIRST) uniform usamplerBuffer firstT;
layout(binding = HEMO_SUBSTEP_BINDING_SPRINGS_OF) uniform usamplerBuffer springsOfT;
layout(binding = HEMO_SUBSTEP_BINDING_WALL_INFO) uniform samplerBuffer wallInfoT;
layout(std430, binding = HEMO_SUBSTEP_BINDING_ACCEL) buffer Accel { vec4 accel[]; };  // own record
layout(binding = HEMO_SUBSTEP_BINDING_HELD) uniform samplerBuffer heldT;
layout(std430, binding = HEMO_SUBSTEP_BINDING_SPRINGS_RW) buffer SpringsRW { Spring springsRW[]; };
layout(std430, binding = HEMO_SUBSTEP_BINDING_COUNTERS) buffer Counters { uint counters[]; };
HEMO_SPH_PARAMS_UNIFORM(HEMO_SUBSTEP_BINDING_PARAMS);
layout(std140, binding = HEMO_SUBSTEP_BINDING_DT) uniform Dt { vec2 dtMinMax; };
layout(std140, binding = HEMO_SUBSTEP_BINDING_CLOCK) uniform Clock { ClockRecord clocks[2]; };
layout(push_constant) uniform Push {
  uint n;
  uint first;     // the slots [first, n)
  uint idCount;   // ids of the spring network
  uint substeps;  // N
  uint mode;      // HEMO_SUBSTEP_MODE_*
  uint clockIn;   // the record this step reads
  float endTime;  // s (the integrator's)
} pc;

#define positions(k) texelFetch(positionsT, int(k))
#define velocities(k) texelFetch(velocitiesT, int(k))
#include "wall/spring_gather.glsl"

void main() {
  const uint slot = pc.first + hemo_global_index();
  if (slot >= pc.n || uint(texelFetch(velocitiesT, int(slot)).w) != HEMO_KIND_WALL) {
    return;
  }
  const uint id = texelFetch(idsT, int(slot)).x;
  if (id >= pc.idCount || texelFetch(wallInfoT, int(id)).y != 0.0) {
    return;  // not part of the spring network, or anchored
  }
  if (pc.mode == HEMO_SUBSTEP_MODE_FORCE) {
    float stiffness;
    uint intact, total;
    const vec3 springs = hemo_spring_gather(slot, id, stiffness, intact, total);
    float marker = accel[slot].w;  // a detachment marked earlier in this step stays
    if (marker >= 0.0 && intact == 0u && total > 0u && positions(slot).w != 0.0) {
      marker = -1.0;
      atomicAdd(counters[HEMO_WALL_COUNTER_DETACHED], 1u);
    }
    accel[slot] = vec4(springs / texelFetch(wallInfoT, int(id)).x + texelFetch(heldT, int(slot)).xyz, marker);
    return;
  }
  const ClockRecord clock = clocks[pc.clockIn];
  const float dt = hemo_step_dt(clock, pc.endTime, dtMinMax.x, params.dtMax);
  if (!(dt > 0.0)) {
    return;  // the run has ended (the integrator then moves nothing either)
  }
  const float h = dt / float(pc.substeps);
  vec3 v = velocitiesW[slot].xyz + accel[slot].xyz * h;
  if (clock.time < params.dampingUntil) {
    v /= 1.0 + params.dampingRate * h;  // the settling phase, as the integrator's
  }
  velocitiesW[slot].xyz = v;
  positionsW[slot].xyz = hemo_wrap_position(positionsW[slot].xyz + v * h);
}
