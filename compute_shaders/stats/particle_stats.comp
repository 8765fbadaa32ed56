#version 450
// Per-slot inputs of the step statistics: the speed and the density error of fluid particles
// (0 for boundary and wall particles), reduced to their maxima by the min/max reduction.
#extension GL_GOOGLE_include_directive : require
#include "interface/sph.h"
#include "interface/stats.h"
#include "common/index.glsl"
#include "common/sph_params.glsl"

layout(std430, binding = HEMO_PSTATS_BINDING_VELOCITIES) readonly buffer Velocities { vec4 velocities[]; };
layout(std430, binding = HEMO_PSTATS_BINDING_STATE) readonly buffer State { vec4 state[]; };
HEMO_SPH_PARAMS_UNIFORM(HEMO_PSTATS_BINDING_PARAMS);
layout(std430, binding = HEMO_PSTATS_BINDING_SPEED) writeonly buffer Speed { float speed[]; };
layout(std430, binding = HEMO_PSTATS_BINDING_DENSITY_ERROR) writeonly buffer DensityError { float densityError[]; };
layout(push_constant) uniform Push { uint n; } pc;

void main() {
  const uint i = hemo_global_index();
  if (i >= pc.n) {
    return;
  }
  const vec4 v = velocities[i];
  const bool fluid = uint(v.w) == HEMO_KIND_FLUID;
  speed[i] = fluid ? length(v.xyz) : 0.0;
  densityError[i] = fluid ? abs(state[i].x / params.rho0 - 1.0) : 0.0;
}
