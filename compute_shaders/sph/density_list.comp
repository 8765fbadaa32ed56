#version 450
// Summation density and Tait pressure of fluid particles from the neighbour list built by
// density.comp (same terms in the same order, so at unchanged positions the result is
// bit-identical). Boundary particles are left to boundary_pressure.comp.
#extension GL_GOOGLE_include_directive : require
#include "interface/sph.h"
#include "common/index.glsl"
#include "common/kernel.glsl"
#include "common/sph_params.glsl"
#include "common/tait.glsl"

layout(std430, binding = HEMO_DLIST_BINDING_POSITIONS) readonly buffer Positions { vec4 positions[]; };
layout(std430, binding = HEMO_DLIST_BINDING_VELOCITIES) readonly buffer Velocities { vec4 velocities[]; };
layout(std430, binding = HEMO_DLIST_BINDING_PARAMS) readonly buffer Params { SphParams params; };
layout(std430, binding = HEMO_DLIST_BINDING_STATE) writeonly buffer State { vec4 state[]; };
layout(std430, binding = HEMO_DLIST_BINDING_NCOUNT) readonly buffer Counts { uint neighbourCount[]; };
layout(std430, binding = HEMO_DLIST_BINDING_NLIST) readonly buffer List { uint neighbourList[]; };
layout(push_constant) uniform Push { uint n; } pc;

void main() {
  const uint i = hemo_global_index();
  if (i >= pc.n || uint(velocities[i].w) != HEMO_KIND_FLUID) {
    return;
  }
  const vec4 pi = positions[i];
  const float support2 = params.supportRadius * params.supportRadius;
  float rho = pi.w * hemo_kernel_w(0.0, params.h, params.kernelNorm);
  const uint count = neighbourCount[i];
  const uint listBase = i * params.neighbourCapacity;
  for (uint k = 0u; k < count; ++k) {
    const vec4 pj = positions[neighbourList[listBase + k]];
    const vec3 d = pi.xyz - pj.xyz;
    const float r2 = dot(d, d);
    if (r2 < support2) {
      rho += pj.w * hemo_kernel_w(sqrt(r2), params.h, params.kernelNorm);
    }
  }
  state[i] = vec4(rho, hemo_tait_pressure(rho, params), 0.0, 0.0);
}
