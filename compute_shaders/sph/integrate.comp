#version 450
// Symplectic Euler: v += a dt, x += v dt for fluid particles, with dt = min(reduced
// per-particle limits, dtMax) read from the GPU (the host never sees dt inside a batch).
// Invocation 0 advances the clock (Kahan-compensated float sum) and logs (t, dt).
// A particle that becomes non-finite records the step in the status buffer.
#extension GL_GOOGLE_include_directive : require
#include "interface/sph.h"
#include "common/index.glsl"
#include "common/sph_params.glsl"

layout(std430, binding = HEMO_INTEGRATE_BINDING_POSITIONS) buffer Positions { vec4 positions[]; };
layout(std430, binding = HEMO_INTEGRATE_BINDING_VELOCITIES) buffer Velocities { vec4 velocities[]; };
layout(std430, binding = HEMO_INTEGRATE_BINDING_ACCEL) readonly buffer Accel { vec4 accel[]; };
layout(std430, binding = HEMO_INTEGRATE_BINDING_PARAMS) readonly buffer Params { SphParams params; };
layout(std430, binding = HEMO_INTEGRATE_BINDING_DT) readonly buffer Dt { vec2 dtMinMax; };
layout(std430, binding = HEMO_INTEGRATE_BINDING_CLOCK) buffer Clock { float time; float compensation; float lastDt; uint steps; } clock;
layout(std430, binding = HEMO_INTEGRATE_BINDING_STATUS) buffer Status { uint status[]; };
layout(std430, binding = HEMO_INTEGRATE_BINDING_LOG) writeonly buffer Log { vec2 stepLog[]; };
layout(push_constant) uniform Push { uint n; uint step; uint logIndex; uint pad; } pc;

void main() {
  const uint i = hemo_global_index();
  const float dt = min(dtMinMax.x, params.dtMax);
  if (i == 0u) {
    const float y = dt - clock.compensation;
    const float t = clock.time + y;
    clock.compensation = (t - clock.time) - y;
    clock.time = t;
    clock.lastDt = dt;
    clock.steps += 1u;
    stepLog[pc.logIndex] = vec2(t, dt);
  }
  if (i >= pc.n) {
    return;
  }
  vec4 v = velocities[i];
  if (uint(v.w) != HEMO_KIND_FLUID) {
    return;
  }
  vec4 x = positions[i];
  v.xyz += accel[i].xyz * dt;
  x.xyz += v.xyz * dt;
  if (any(isnan(x.xyz)) || any(isinf(x.xyz)) || any(isnan(v.xyz)) || any(isinf(v.xyz))) {
    atomicMin(status[HEMO_STATUS_FIRST_BAD_STEP], pc.step);
    atomicAdd(status[HEMO_STATUS_NONFINITE], 1u);
  }
  velocities[i] = v;
  positions[i] = x;
}
