#version 450
// Summation density over fluid and boundary neighbours from the neighbour list (boundary
// particles act as virtual fluid particles so the density does not drop at walls), and the
// Tait pressure (Monaghan 1994; Batchelor's gamma = 7):
//   rho_i = sum_j m_j W(|x_i - x_j|, h)   (j includes i)
//   p_i   = B ((rho_i / rho0)^7 - 1) + p_bg,  B = c0^2 rho0 / 7,  optionally clamped at 0
// with p_bg the (ramped) background pressure of common/tait.glsl.
// Fluid particles only; boundary particles get theirs from boundary_pressure.comp.
// Also writes each fluid particle's pair data (interface/sph.h): pair position (x, V p) and
// viscous velocity (v, V), V = m / rho; and its interacting pairs, the list entries within
// interaction range, which the SPS and force passes walk instead of the whole list.
//
// With continuity density (kContinuity = 1 or 2) the density is not summed: each fluid
// particle carries its own (normals[i].w, interface/sph.h). With symplectic Euler (1) this pass
// advances it over the step just taken, with the rate at the positions and velocities that
// step produced (the partner of symplectic Euler's x1 = x0 + dt v1), and the integrator stores
// the result back:
//   rho_i(t + dt) = rho_i(t) + dt (d rho_i / dt)(x(t + dt), v(t + dt), rho(t))
// With the RK2 midpoint rule (2) the pass gives the pressure of the carried density as it is
// and the rate in state.z, and the integrator's two stages advance the density with it.
// The rate:
//   d rho_i / dt = sum_j m_j (v_i - v_j) . grad W_ij                     (continuity)
//                + delta h c0 sum_{j fluid} psi_ij (x_ji . grad W_ij) / (r^2 + eta^2) m_j / rho_j
//   psi_ij = 2 ((rho_j - rho_i) - (rho^H_j - rho^H_i)),
//   rho^H_j - rho^H_i = rho0 ((1 + rho0 g . x_ji / B)^(1/7) - 1)
// The second line is the density diffusion of delta-SPH (Molteni & Colagrossi 2009); psi
// leaves out the hydrostatic density difference (Fourtakas et al. 2019), so a column at rest
// is not diffused. Boundary neighbours take part in the continuity term with their own
// velocity (a moving wall compresses the fluid), not in the diffusion.
#extension GL_GOOGLE_include_directive : require
#include "interface/sph.h"
#include "common/index.glsl"
#include "common/kernel.glsl"
#include "common/sph_params.glsl"
#include "common/clock.glsl"
#include "common/tait.glsl"

// Read at neighbour indices: uniform texel buffers (interface/sph.h, "texel slots").
layout(binding = HEMO_DENSITY_BINDING_POSITIONS) uniform samplerBuffer positions;
layout(binding = HEMO_DENSITY_BINDING_VELOCITIES) uniform samplerBuffer velocities;
HEMO_SPH_PARAMS_UNIFORM(HEMO_DENSITY_BINDING_PARAMS);
layout(std430, binding = HEMO_DENSITY_BINDING_STATE) writeonly buffer State { vec4 state[]; };
layout(binding = HEMO_DENSITY_BINDING_NCOUNT) uniform usamplerBuffer neighbourCount;
layout(binding = HEMO_DENSITY_BINDING_NLIST) uniform usamplerBuffer neighbourList;
layout(std140, binding = HEMO_DENSITY_BINDING_CLOCK) uniform Clock { ClockRecord clocks[2]; };
layout(std430, binding = HEMO_DENSITY_BINDING_VISCOUS_VEL) writeonly buffer ViscousVel { vec4 viscousVel[]; };
layout(binding = HEMO_DENSITY_BINDING_NORMALS) uniform samplerBuffer normals;
layout(std430, binding = HEMO_DENSITY_BINDING_PAIR_POSITION) writeonly buffer PairPosition { vec4 pairPosition[]; };
layout(std430, binding = HEMO_DENSITY_BINDING_PAIR_COUNT) writeonly buffer PairCount { uint pairCount[]; };
layout(std430, binding = HEMO_DENSITY_BINDING_PAIR_LIST) writeonly buffer PairList { uint pairList[]; };
layout(constant_id = 1) const uint kContinuity = 0u;  // 0 summation, 1 / 2 continuity (see above)
layout(push_constant) uniform Push {
  uint n;
  uint clockIn;  // the record this step reads
} pc;

void main() {
  const uint i = hemo_global_index();
  if (i >= pc.n) {
    return;
  }
  const vec4 vi = texelFetch(velocities, int(i));
  if (uint(vi.w) != HEMO_KIND_FLUID) {
    return;
  }
  const vec4 pi = texelFetch(positions, int(i));
  const HemoPairParams pp = hemo_pair_params();
  const uint count = texelFetch(neighbourCount, int(i)).x;
  // Interacting pairs: every entry is stored at the next free slot and the slot advances only
  // for entries in range (no branch around the store; m <= k keeps it inside the list).
  const float cutoffReach = abs(params.repulsionCutoff) + params.wallSpacing;
  const float keep2 = max(pp.support2, cutoffReach * cutoffReach + params.wallSpacing * params.wallSpacing);
  uint m = 0u;
  float rho;
  float rate = 0.0;  // d rho / dt, for the RK2 stages (kContinuity = 2)
  if (kContinuity != 0u) {
    rho = hemo_carried_density(texelFetch(normals, int(i)).w, params.rho0);
    const float invH = 1.0 / pp.h;
    const float gradNorm = hemo_kernel_grad_norm(pp.h, pp.kernelNorm);
    const float diffusion = params.deltaSph * pp.h * params.c0;
    const vec3 g = params.gravityOnly.xyz;
    const float rho0 = params.rho0, hydroScale = params.rho0 / params.taitB, etaSq = params.etaSq;  // registers
    float continuity = 0.0, diffused = 0.0;
    for (uint k = 0u; k < count; ++k) {
      const uint j = texelFetch(neighbourList, int(hemo_list_slot(i, k, pp))).x;
      const vec4 pj = texelFetch(positions, int(j));
      const vec3 d = hemo_min_image(pi.xyz - pj.xyz, pp);  // x_ij
      const float r2 = dot(d, d);
      pairList[hemo_list_slot(i, m, pp)] = j;
      m += r2 < keep2 ? 1u : 0u;
      const vec3 gradW = d * hemo_kernel_grad_factor(sqrt(r2), invH, gradNorm);  // 0 beyond the support
      const vec4 vj = texelFetch(velocities, int(j));
      continuity += pj.w * dot(vi.xyz - vj.xyz, gradW);
      if (uint(vj.w) == HEMO_KIND_FLUID) {
        const float rhoJ = hemo_carried_density(texelFetch(normals, int(j)).w, rho0);
        const float hydro = rho0 * (pow(max(1.0 - hydroScale * dot(g, d), 1.0e-6), 1.0 / 7.0) - 1.0);
        diffused += 2.0 * ((rhoJ - rho) - hydro) * (-dot(d, gradW)) / (r2 + etaSq) * (pj.w / rhoJ);
      }
    }
    rate = continuity + diffusion * diffused;
    if (kContinuity == 1u) {
      rho += clocks[pc.clockIn].lastDt * rate;
      rate = 0.0;
    }
  } else {
    rho = pi.w * hemo_kernel_w(0.0, pp.h, pp.kernelNorm);
    for (uint k = 0u; k < count; ++k) {
      const uint j = texelFetch(neighbourList, int(hemo_list_slot(i, k, pp))).x;
      const vec4 pj = texelFetch(positions, int(j));
      const vec3 d = hemo_min_image(pi.xyz - pj.xyz, pp);
      const float r2 = dot(d, d);
      pairList[hemo_list_slot(i, m, pp)] = j;
      m += r2 < keep2 ? 1u : 0u;
      if (r2 < pp.support2) {
        rho += pj.w * hemo_kernel_w(sqrt(r2), pp.h, pp.kernelNorm);
      }
    }
  }
  const float background = hemo_background_pressure(clocks[pc.clockIn].time, params);
  const float p = hemo_tait_pressure(rho, background, params);
  pairCount[i] = m;
  state[i] = vec4(rho, p, rate, 0.0);
  const float volume = pi.w / rho;
  pairPosition[i] = vec4(pi.xyz, volume * p);
  viscousVel[i] = vec4(vi.xyz, volume);  // > 0: fluid
}
