#version 450
// Summation density over fluid and boundary neighbours from the neighbour list (boundary
// particles act as virtual fluid particles so the density does not drop at walls), and the
// Tait pressure (Monaghan 1994; Batchelor's gamma = 7):
//   rho_i = sum_j m_j W(|x_i - x_j|, h)   (j includes i)
//   p_i   = B ((rho_i / rho0)^7 - 1) + p_bg,  B = c0^2 rho0 / 7,  optionally clamped at 0
// with p_bg the (ramped) background pressure of common/tait.glsl.
// Fluid particles only; boundary particles get theirs from boundary_pressure.comp.
// Also copies each fluid particle's velocity and kind into the viscous velocities (interface/sph.h).
#extension GL_GOOGLE_include_directive : require
#include "interface/sph.h"
#include "common/index.glsl"
#include "common/kernel.glsl"
#include "common/sph_params.glsl"
#include "common/clock.glsl"
#include "common/tait.glsl"

layout(std430, binding = HEMO_DENSITY_BINDING_POSITIONS) readonly buffer Positions { vec4 positions[]; };
layout(std430, binding = HEMO_DENSITY_BINDING_VELOCITIES) readonly buffer Velocities { vec4 velocities[]; };
layout(std430, binding = HEMO_DENSITY_BINDING_PARAMS) readonly buffer Params { SphParams params; };
layout(std430, binding = HEMO_DENSITY_BINDING_STATE) writeonly buffer State { vec4 state[]; };
layout(std430, binding = HEMO_DENSITY_BINDING_NCOUNT) readonly buffer Counts { uint neighbourCount[]; };
layout(std430, binding = HEMO_DENSITY_BINDING_NLIST) readonly buffer List { uint neighbourList[]; };
layout(std430, binding = HEMO_DENSITY_BINDING_CLOCK) readonly buffer Clock { ClockRecord clocks[2]; };
layout(std430, binding = HEMO_DENSITY_BINDING_VISCOUS_VEL) writeonly buffer ViscousVel { vec4 viscousVel[]; };
layout(push_constant) uniform Push {
  uint n;
  uint clockIn;  // the record this step reads
} pc;

void main() {
  const uint i = hemo_global_index();
  if (i >= pc.n) {
    return;
  }
  const vec4 vi = velocities[i];
  if (uint(vi.w) != HEMO_KIND_FLUID) {
    return;
  }
  viscousVel[i] = vi;  // what the force pass gathers of a fluid neighbour: velocity and kind
  const vec4 pi = positions[i];
  const HemoPairParams pp = hemo_pair_params();
  float rho = pi.w * hemo_kernel_w(0.0, pp.h, pp.kernelNorm);
  const uint count = neighbourCount[i];
  for (uint k = 0u; k < count; ++k) {
    const vec4 pj = positions[neighbourList[hemo_list_slot(i, k, pp)]];
    const vec3 d = hemo_min_image(pi.xyz - pj.xyz, pp);
    const float r2 = dot(d, d);
    if (r2 < pp.support2) {
      rho += pj.w * hemo_kernel_w(sqrt(r2), pp.h, pp.kernelNorm);
    }
  }
  const float background = hemo_background_pressure(clocks[pc.clockIn].time, params);
  state[i] = vec4(rho, hemo_tait_pressure(rho, background, params), 0.0, 0.0);
}
