#version 450
// DFSPH's prediction (interface/sph.h, "The pressure solver"). Density mode: for each fluid
// slot, the density the predicted velocities v* = v + dt a would give at the end of the step,
//   rho*_i = rho_i + dt sum_j m_j (v*_i - v*_j) . gradW_ij
// (boundary neighbours move with their own velocity), its residual
// e_i = max(rho*_i - rho0 - p_i C, 0) (p_i the density solve's own pressure so far, C its
// compliance 1 / c0^2, 0 when incompressible), and the stiffness that removes it when i alone
// responds (Bender & Koschier 2017, eq. 8-9, with the compliance in the diagonal),
//   kappa_i / rho_i = e_i / (dt^2 max(|sum_j m_j gradW_ij|^2 + sum_{j fluid} |m_j gradW_ij|^2, floor) + rho_i^2 C).
// Each workgroup sums e_i / rho0 in fixed point (HEMO_DFSPH_ERROR_SCALE) into its partial,
// which sph/dfsph_reduce.comp reduces to the mean. The slots [0, n): fluid ones only.
// Divergence mode: the velocities' compressive divergence d_i = max(sum_j m_j (v_i - v_j) .
// gradW_ij, 0), the stiffness k_i = d_i / D_i that removes it, and the error d_i dt' / rho0,
// dt' the last step's dt (0 on the first step: no solve).
// The pressure: the step's impulses over its dt. A prediction after correction k adds that
// correction's k_i (from the stiffness it stored) to its solve's sum: the divergence solve's
// sum of k_i in kappa.z, the density solve's pressure in kappa.y, which starts (its first
// prediction) from the divergence solve's impulse, (sum of k_i) rho_i^2 / dt, and grows by
// k_i rho_i^2 per correction; state.y becomes the density pass's pressure (the expansion side of
// the equation of state, common/tait.glsl) plus it. A step past the end time (dt = 0) keeps the last pressure,
// stiffness 0 and error 0.
#extension GL_GOOGLE_include_directive : require
#include "interface/sph.h"
#include "common/index.glsl"
#include "common/kernel.glsl"
#include "common/sph_params.glsl"
#include "common/clock.glsl"
#include "common/step_dt.glsl"
#include "common/tait.glsl"

layout(binding = HEMO_DFSPH_BINDING_POSITIONS) uniform samplerBuffer positions;
layout(binding = HEMO_DFSPH_BINDING_VELOCITIES) uniform samplerBuffer velocities;
layout(binding = HEMO_DFSPH_BINDING_ACCEL) uniform samplerBuffer accel;
HEMO_SPH_PARAMS_UNIFORM(HEMO_DFSPH_BINDING_PARAMS);
// (only its own record of each: the density, and the pressure it writes)
layout(std430, binding = HEMO_DFSPH_BINDING_STATE) buffer State { vec4 state[]; };
layout(binding = HEMO_DFSPH_BINDING_PAIR_COUNT) uniform usamplerBuffer pairCounts;
layout(binding = HEMO_DFSPH_BINDING_PAIR_LIST) uniform usamplerBuffer pairList;
// (k_i, p_i, the divergence solve's sum of k_i, the density solve's own pressure): its own record only
layout(std430, binding = HEMO_DFSPH_BINDING_KAPPA) buffer Kappa { vec4 kappa[]; };
layout(std430, binding = HEMO_DFSPH_BINDING_PARTIALS) writeonly buffer Partials { uint partials[]; };
layout(std140, binding = HEMO_DFSPH_BINDING_DT) uniform Dt { vec2 dtMinMax; };
layout(std140, binding = HEMO_DFSPH_BINDING_CLOCK) uniform Clock { ClockRecord clocks[2]; };
// 4: the list is read four entries per texel (common/sph_params.glsl, hemo_list_texel)
layout(constant_id = 1) const uint kListWidth = 1u;
layout(push_constant) uniform Push {
  uint n;        // the slots [0, n)
  uint clockIn;  // the record this step reads
  float endTime;  // s (the integrator's)
  uint iteration;  // 0: the solve's first prediction; k: the one after correction k
  uint mode;       // HEMO_DFSPH_MODE_*
} pc;

shared uint s_sum;

HemoPairParams gPp;
vec3 gXi, gVi;     // position, predicted velocity
float gDt, gInvH, gGradNorm;
bool gPredicts;     // density mode: v* = v + dt a (the divergence solve reads no acceleration)
float gDivergence;  // sum_j m_j (v*_i - v*_j) . gradW_ij
vec3 gGradSum;      // sum_j m_j gradW_ij
float gGradSq;      // sum_{j fluid} |m_j gradW_ij|^2

void pair(uint j, const bool boundary) {
  const vec4 pj = texelFetch(positions, int(j));
  const vec3 d = hemo_min_image(gXi - pj.xyz, gPp);
  const vec3 mGradW = pj.w * (d * hemo_kernel_grad_factor(sqrt(dot(d, d)), gInvH, gGradNorm));
  vec3 vj = texelFetch(velocities, int(j)).xyz;
  if (!boundary) {
    if (gPredicts) {
      vj += gDt * texelFetch(accel, int(j)).xyz;
    }
    gGradSq += dot(mGradW, mGradW);
  }
  gDivergence += dot(gVi - vj, mGradW);
  gGradSum += mGradW;
}

#include "common/dfsph_pairs.glsl"

void main() {
  const uint i = hemo_global_index();
  if (gl_LocalInvocationIndex == 0u) {
    s_sum = 0u;
  }
  barrier();
  uint fixedError = 0u;
  const ClockRecord clock = clocks[pc.clockIn];
  const bool divergence = pc.mode == HEMO_DFSPH_MODE_DIVERGENCE;
  // (the divergence solve predicts nothing: its velocities are the particles' own)
  gDt = divergence ? 0.0 : hemo_step_dt(clock, pc.endTime, dtMinMax.x, params.dtMax);
  if (i < pc.n) {
    const vec4 vi = texelFetch(velocities, int(i));
    if (uint(vi.w) == HEMO_KIND_FLUID) {
      gPp = hemo_pair_params();
      gInvH = 1.0 / gPp.h;
      gGradNorm = hemo_kernel_grad_norm(gPp.h, gPp.kernelNorm);
      gXi = texelFetch(positions, int(i)).xyz;
      gPredicts = !divergence;
      gVi = divergence ? vi.xyz : vi.xyz + gDt * texelFetch(accel, int(i)).xyz;
      gDivergence = 0.0;
      gGradSum = vec3(0.0);
      gGradSq = 0.0;
      hemo_dfsph_pairs(i);
      const float rho0 = params.rho0;
      // (floored: interface/sph.h, solveFloor)
      const float d = max(dot(gGradSum, gGradSum) + gGradSq, params.solveFloor);
      const vec4 last = kappa[i];
      float e;
      if (divergence) {
        const float rate = max(gDivergence, 0.0);
        kappa[i] = vec4(rate / d, last.y, pc.iteration == 0u ? 0.0 : last.z + last.x, 0.0);
        e = rate * clock.lastDt / rho0;
      } else {
        const vec4 si = state[i];
        // (dt = 0 once the run has ended: no stiffness, no error, and the last pressure kept)
        const bool running = gDt > 0.0;
        const float rho2 = si.x * si.x;
        const bool first = pc.iteration == 0u;
        const float p = !running ? last.y : first ? last.z * rho2 / gDt : last.y + last.x * rho2;
        // the density solve's own pressure, which the compliance holds as compression
        const float own = !running ? last.w : first ? 0.0 : last.w + last.x * rho2;
        const float residual = max(si.x + gDt * gDivergence - rho0 - own * params.solveCompliance, 0.0);
        kappa[i] = vec4(running ? residual / (gDt * gDt * d + rho2 * params.solveCompliance) : 0.0, p, last.z, own);
        // (the density pass's pressure, recomputed: this pass overwrites it)
        state[i].y = p + hemo_expansion_pressure(si.x, hemo_background_pressure(clock.time, params), params);
        e = running ? residual / rho0 : 0.0;
      }
      // (NaN counts as the largest error, so a blown-up solve never reads as converged)
      fixedError = uint(isnan(e) ? HEMO_DFSPH_ERROR_SCALE : min(e, 1.0) * HEMO_DFSPH_ERROR_SCALE + 0.5);
    }
  }
  if (fixedError != 0u) {
    atomicAdd(s_sum, fixedError);  // integers: the sum is the same in any order
  }
  barrier();
  if (gl_LocalInvocationIndex == 0u) {
    partials[hemo_group_index()] = s_sum;
  }
}
