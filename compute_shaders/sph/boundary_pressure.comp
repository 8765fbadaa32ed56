#version 450
// Boundary particles take the pressure the fluid next to them implies (Adami, Hu & Adams
// 2012, "A generalized wall boundary condition for SPH", eq. 27), for a rigid wall at rest:
//   p_b = ( sum_f p_f W_bf + g . sum_f rho_f (x_b - x_f) W_bf ) / sum_f W_bf
// with g the gravity + body force, and the density from the inverse Tait equation,
//   rho_b = rho0 ((p_b - p_bg) / B + 1)^(1/7)   (p_bg: background pressure, common/tait.glsl).
// For the viscous term the boundary particle shows the no-slip velocity of the same paper
// (eq. 22-23): v = 2 v_wall - sum_f v_f W_bf / sum_f W_bf, so the shear across the wall is
// that of a velocity that vanishes at the wall (a zero velocity gives about half of it, and
// the fluid slips).
// Also writes the particle's pair data (interface/sph.h): pair position (x, V p) and viscous
// velocity (no-slip v, -V), V = m / rho.
// A boundary particle without fluid neighbours keeps (rho0, p_bg) and its own velocity. The force pass then treats
// boundary particles like fluid ones in the symmetric pressure term, which holds a fluid
// column at the hydrostatic pressure without the wall having to be penetrated.
#extension GL_GOOGLE_include_directive : require
#include "interface/sph.h"
#include "common/index.glsl"
#include "common/kernel.glsl"
#include "common/sph_params.glsl"
#include "common/clock.glsl"
#include "common/tait.glsl"

// Read-only inputs: uniform texel buffers (interface/sph.h, "texel slots").
layout(binding = HEMO_BPRESSURE_BINDING_POSITIONS) uniform samplerBuffer positions;
layout(binding = HEMO_BPRESSURE_BINDING_VELOCITIES) uniform samplerBuffer velocities;
layout(binding = HEMO_BPRESSURE_BINDING_FLUID_STATE) uniform samplerBuffer fluidState;
HEMO_SPH_PARAMS_UNIFORM(HEMO_BPRESSURE_BINDING_PARAMS);
layout(std430, binding = HEMO_BPRESSURE_BINDING_STATE) writeonly buffer State { vec4 state[]; };
layout(binding = HEMO_BPRESSURE_BINDING_NCOUNT) uniform usamplerBuffer neighbourCount;
layout(binding = HEMO_BPRESSURE_BINDING_NLIST) uniform usamplerBuffer neighbourList;
layout(std430, binding = HEMO_BPRESSURE_BINDING_VISCOUS_VEL) writeonly buffer ViscousVel { vec4 viscousVel[]; };
layout(std140, binding = HEMO_BPRESSURE_BINDING_CLOCK) uniform Clock { ClockRecord clocks[2]; };
layout(std430, binding = HEMO_BPRESSURE_BINDING_PAIR_POSITION) writeonly buffer PairPosition { vec4 pairPosition[]; };
layout(push_constant) uniform Push {
  uint n;
  uint clockIn;
} pc;

void main() {
  const uint b = hemo_global_index();
  if (b >= pc.n) {
    return;
  }
  const vec4 vb = texelFetch(velocities, int(b));
  if (uint(vb.w) == HEMO_KIND_FLUID) {
    return;
  }
  const vec4 xb4 = texelFetch(positions, int(b));
  const vec3 xb = xb4.xyz;
  const HemoPairParams pp = hemo_pair_params();
  float sumW = 0.0;
  float sumP = 0.0;
  vec3 sumRhoR = vec3(0.0);
  vec3 sumV = vec3(0.0);
  const uint count = texelFetch(neighbourCount, int(b)).x;
  for (uint k = 0u; k < count; ++k) {
    const int f = int(texelFetch(neighbourList, int(hemo_list_slot(b, k, pp))).x);  // fluid neighbours only
    const vec3 d = hemo_min_image(xb - texelFetch(positions, f).xyz, pp);
    const float r2 = dot(d, d);
    if (r2 >= pp.support2) {
      continue;
    }
    const float w = hemo_kernel_w(sqrt(r2), pp.h, pp.kernelNorm);
    const vec2 sf = texelFetch(fluidState, f).xy;
    sumW += w;
    sumP += sf.y * w;
    sumRhoR += sf.x * d * w;
    sumV += texelFetch(velocities, f).xyz * w;
  }
  const float background = hemo_background_pressure(clocks[pc.clockIn].time, params);
  float rho = params.rho0;
  float p = background;
  vec3 v = vb.xyz;
  if (sumW > 0.0) {
    v = 2.0 * vb.xyz - sumV / sumW;
    p = (sumP + dot(params.gravity.xyz, sumRhoR)) / sumW;
    if (params.clampNegativePressure != 0u) {
      p = max(p, 0.0);
    }
    rho = hemo_tait_density(p, background, params);
  }
  state[b] = vec4(rho, p, 0.0, 0.0);
  const float volume = xb4.w / rho;  // 0 when detached
  pairPosition[b] = vec4(xb, volume * p);
  viscousVel[b] = vec4(v, -volume);  // < 0: boundary or wall; -0 (neither) when detached
}
