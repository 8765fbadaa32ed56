#version 450
// DFSPH's correction (interface/sph.h, "The pressure solver"): with the stiffnesses k that
// sph/dfsph_predict.comp found, each fluid slot's acceleration (density mode) or velocity
// (divergence mode, and the pair data's copy of it) changes by
//   - sum_{j fluid} m_j (k_i + k_j) gradW_ij - sum_{b boundary} m_b k_i gradW_ib
// (the symmetric form: pairwise forces m_i a_ij are equal and opposite between fluid
// particles; a rigid boundary neighbour mirrors i's own stiffness, as in Akinci et al. 2012),
// (the next prediction adds k_i rho_i^2 to the pressure). Each slot writes only its own records.
#extension GL_GOOGLE_include_directive : require
#include "interface/sph.h"
#include "common/index.glsl"
#include "common/kernel.glsl"
#include "common/sph_params.glsl"

layout(binding = HEMO_DFSPH_BINDING_POSITIONS) uniform samplerBuffer positions;
layout(std430, binding = HEMO_DFSPH_BINDING_VELOCITIES) buffer Velocities { vec4 velocities[]; };
layout(std430, binding = HEMO_DFSPH_BINDING_ACCEL) buffer Accel { vec4 accel[]; };
HEMO_SPH_PARAMS_UNIFORM(HEMO_DFSPH_BINDING_PARAMS);
layout(binding = HEMO_DFSPH_BINDING_PAIR_COUNT) uniform usamplerBuffer pairCounts;
layout(binding = HEMO_DFSPH_BINDING_PAIR_LIST) uniform usamplerBuffer pairList;
layout(binding = HEMO_DFSPH_BINDING_KAPPA) uniform samplerBuffer kappa;
layout(std430, binding = HEMO_DFSPH_BINDING_VISCOUS_VEL) buffer ViscousVel { vec4 viscousVel[]; };
// 4: the list is read four entries per texel (common/sph_params.glsl, hemo_list_texel)
layout(constant_id = 1) const uint kListWidth = 1u;
layout(push_constant) uniform Push {
  uint n;     // the slots [0, n)
  uint mode;  // HEMO_DFSPH_MODE_*
} pc;

HemoPairParams gPp;
vec3 gXi;
float gKappaI, gInvH, gGradNorm;
vec3 gSum;  // sum_j m_j (kappa_i / rho_i + kappa_j / rho_j) gradW_ij (boundary: kappa_j = 0)

void pair(uint j, const bool boundary) {
  const vec4 pj = texelFetch(positions, int(j));
  const vec3 d = hemo_min_image(gXi - pj.xyz, gPp);
  const vec3 gradW = d * hemo_kernel_grad_factor(sqrt(dot(d, d)), gInvH, gGradNorm);
  const float kj = boundary ? 0.0 : texelFetch(kappa, int(j)).x;
  gSum += (pj.w * (gKappaI + kj)) * gradW;
}

#include "common/dfsph_pairs.glsl"

void main() {
  const uint i = hemo_global_index();
  if (i >= pc.n || uint(velocities[i].w) != HEMO_KIND_FLUID) {
    return;
  }
  gPp = hemo_pair_params();
  gInvH = 1.0 / gPp.h;
  gGradNorm = hemo_kernel_grad_norm(gPp.h, gPp.kernelNorm);
  gXi = texelFetch(positions, int(i)).xyz;
  gKappaI = texelFetch(kappa, int(i)).x;
  gSum = vec3(0.0);
  hemo_dfsph_pairs(i);
  if (pc.mode == HEMO_DFSPH_MODE_DIVERGENCE) {
    const vec3 v = velocities[i].xyz - gSum;
    velocities[i].xyz = v;
    viscousVel[i].xyz = v;  // what the force pass's viscous term reads (sph/density.comp wrote it)
  } else {
    accel[i].xyz -= gSum;
  }
}
