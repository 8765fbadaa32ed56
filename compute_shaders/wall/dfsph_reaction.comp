#version 450
// The wall's share of DFSPH's pressure (interface/wall.h, HEMO_WALLP_*), after the density
// solve: both solves corrected each fluid particle f next to a wall particle w by
//   -m_w k_f gradW_fw  (the mirrored boundary term of sph/dfsph_correct.comp),
// k_f summed over the step's corrections, which the solve keeps as the pressure
// p_f = k_f rho_f^2 (kappa.y: the divergence solve's impulse over dt plus the density
// solve's). The wall particle takes the exact opposite, gathered over its fluid neighbours:
//   F_w = sum_f m_f m_w (p_f / rho_f^2) gradW_fw,
// added to the acceleration wall/spring_forces.comp wrote (F_w over its spring mass), and to
// what the wall's substeps hold for the step. Anchored
// particles keep 0; a detached one (SPH mass 0) gets nothing, as the fluid got nothing from it.
// Other slots are left alone.
#extension GL_GOOGLE_include_directive : require
#include "interface/sph.h"
#include "interface/wall.h"
#include "common/index.glsl"
#include "common/kernel.glsl"
#include "common/sph_params.glsl"

layout(binding = HEMO_WALLP_BINDING_POSITIONS) uniform samplerBuffer positions;  // (x, SPH mass)
layout(binding = HEMO_WALLP_BINDING_VELOCITIES) uniform samplerBuffer velocities;  // w: kind
layout(binding = HEMO_WALLP_BINDING_IDS) uniform usamplerBuffer ids;
layout(binding = HEMO_WALLP_BINDING_WALL_INFO) uniform samplerBuffer wallInfo;  // by id: (mass, anchored)
layout(binding = HEMO_WALLP_BINDING_STATE) uniform samplerBuffer state;         // x: rho
layout(binding = HEMO_WALLP_BINDING_KAPPA) uniform samplerBuffer kappa;         // y: the solve's pressure
layout(binding = HEMO_WALLP_BINDING_NCOUNT) uniform usamplerBuffer neighbourCount;
layout(binding = HEMO_WALLP_BINDING_NLIST) uniform usamplerBuffer neighbourList;
HEMO_SPH_PARAMS_UNIFORM(HEMO_WALLP_BINDING_PARAMS);
layout(std430, binding = HEMO_WALLP_BINDING_ACCEL) buffer Accel { vec4 accel[]; };  // own (wall) slot only
layout(std430, binding = HEMO_WALLP_BINDING_HELD) buffer Held { vec4 held[]; };     // own (wall) slot only
// 4: the list is read four entries per texel (common/sph_params.glsl, hemo_list_texel)
layout(constant_id = 1) const uint kListWidth = 1u;
layout(push_constant) uniform Push {
  uint n;
  uint first;    // the slots [first, n)
  uint idCount;  // ids of the spring network
} pc;

HemoPairParams gPp;
float gInvH, gGradNorm;
vec3 gXw;
vec3 gSum;  // sum_f m_f (p_f / rho_f^2) gradW_fw

// One fluid neighbour f; `valid` false for the padding of the list's last texel (the caller
// passes the wall particle's own slot, so every fetch stays in bounds).
void reactionPair(uint f, bool valid) {
  const vec4 pf = texelFetch(positions, int(f));
  const vec3 d = hemo_min_image(pf.xyz - gXw, gPp);  // from w to f, as f's correction sees it
  const vec3 gradW = d * hemo_kernel_grad_factor(sqrt(dot(d, d)), gInvH, gGradNorm);  // 0 beyond the support
  const float rho = texelFetch(state, int(f)).x;
  const float k = texelFetch(kappa, int(f)).y / (rho * rho);
  gSum += valid ? (pf.w * k) * gradW : vec3(0.0);
}

void main() {
  const uint slot = pc.first + hemo_global_index();
  if (slot >= pc.n || uint(texelFetch(velocities, int(slot)).w) != HEMO_KIND_WALL) {
    return;
  }
  const uint id = texelFetch(ids, int(slot)).x;
  if (id >= pc.idCount) {
    return;  // not part of the spring network
  }
  const vec4 info = texelFetch(wallInfo, int(id));
  const vec4 xw = texelFetch(positions, int(slot));
  if (info.y != 0.0 || xw.w == 0.0) {
    return;  // anchored, or detached
  }
  gPp = hemo_pair_params();
  gInvH = 1.0 / gPp.h;
  gGradNorm = hemo_kernel_grad_norm(gPp.h, gPp.kernelNorm);
  gXw = xw.xyz;
  gSum = vec3(0.0);
  const uint count = texelFetch(neighbourCount, int(slot)).x;
  for (uint k = 0u; k < count; k += 4u) {
    const uvec4 fs = hemo_list_quad(neighbourList, slot, k, count, gPp);
    reactionPair(fs.x, true);
    reactionPair(k + 1u < count ? fs.y : slot, k + 1u < count);
    reactionPair(k + 2u < count ? fs.z : slot, k + 2u < count);
    reactionPair(k + 3u < count ? fs.w : slot, k + 3u < count);
  }
  const vec3 add = (xw.w / info.x) * gSum;
  accel[slot].xyz += add;
  held[slot].xyz += add;  // for the wall's substeps (wall/substep.comp)
}
