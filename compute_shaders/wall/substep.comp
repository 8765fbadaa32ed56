#version 450
// The wall's substeps (interface/wall.h, HEMO_SUBSTEP_*): N substeps of dt / N per fluid step
// for the wall particles in the slots [first, n), the fluid's force held for the step. Each
// reads the wall's positions and velocities from one pair of buffers (texel bindings) and
// writes them to the other (storage bindings): the step's live arrays and a scratch pair,
// alternated so that the last substep writes the live ones (MassSpring::recordSubsteps).
//   ADVANCE  the first substep, with the acceleration the wall pass left:
//            v += a h, x += v h (h = dt / N; the settling damping as the integrator's;
//            periodic positions wrapped), for free wall particles of the spring network
//   STEP     every later one: a = (the unbroken springs at the positions and velocities read)
//            / m + held, with rupture (a particle whose last spring breaks is marked for
//            detachment in accel.w, counted once; a mark from an earlier substep stays), then
//            advanced as ADVANCE does
// Anchored particles, wall particles outside the network and every particle once the run has
// ended (dt = 0) are copied as they are. Other slots are left alone.
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
// (the scratch pair holds wall records only, of this step: a slot's kind comes from the live array)
layout(binding = HEMO_SUBSTEP_BINDING_KINDS) uniform samplerBuffer kindsT;
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
  if (slot >= pc.n || uint(texelFetch(kindsT, int(slot)).w) != HEMO_KIND_WALL) {
    return;
  }
  const vec4 x = positions(slot);
  const vec4 u = velocities(slot);
  const uint id = texelFetch(idsT, int(slot)).x;
  if (id >= pc.idCount || texelFetch(wallInfoT, int(id)).y != 0.0) {
    positionsW[slot] = x;  // not part of the spring network, or anchored: as it is
    velocitiesW[slot] = u;
    return;
  }
  vec3 a = accel[slot].xyz;
  if (pc.mode == HEMO_SUBSTEP_MODE_STEP) {
    float stiffness;
    uint intact, total;
    const vec3 springs = hemo_spring_gather(slot, id, stiffness, intact, total);
    float marker = accel[slot].w;  // a detachment marked earlier in this step stays
    if (marker >= 0.0 && intact == 0u && total > 0u && x.w != 0.0) {
      marker = -1.0;
      atomicAdd(counters[HEMO_WALL_COUNTER_DETACHED], 1u);
    }
    const vec4 next = vec4(springs / texelFetch(wallInfoT, int(id)).x + texelFetch(heldT, int(slot)).xyz, marker);
    accel[slot] = next;
    a = next.xyz;
  }
  const ClockRecord clock = clocks[pc.clockIn];
  const float dt = hemo_step_dt(clock, pc.endTime, dtMinMax.x, params.dtMax);
  if (!(dt > 0.0)) {
    positionsW[slot] = x;  // the run has ended (the integrator then moves nothing either)
    velocitiesW[slot] = u;
    return;
  }
  const float h = dt / float(pc.substeps);
  vec3 v = u.xyz + a * h;
  if (clock.time < params.dampingUntil) {
    v /= 1.0 + params.dampingRate * h;  // the settling phase, as the integrator's
  }
  velocitiesW[slot] = vec4(v, u.w);
  positionsW[slot] = vec4(hemo_wrap_position(x.xyz + v * h), x.w);
}
