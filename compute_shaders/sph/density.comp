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
#include "common/inflow.glsl"

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
layout(std140, binding = HEMO_DENSITY_BINDING_INFLOW) uniform Inflow { InflowParams inflow; };
#include "common/inflow_speed.glsl"
layout(std430, binding = HEMO_DENSITY_BINDING_OPEN_PROFILE) readonly buffer OpenProfile { float openProfile[]; };
layout(constant_id = 1) const uint kContinuity = 0u;  // 0 summation, 1 / 2 continuity (see above)
// 4: the list is read four entries per texel (common/sph_params.glsl, hemo_list_texel)
layout(constant_id = 2) const uint kListWidth = 1u;
#if HEMO_CELL_WALK
#define HEMO_WALK_BUILD_POSITIONS neighbourCount
#define HEMO_WALK_CELL_START neighbourList
#include "common/cell_walk.glsl"
#endif
layout(push_constant) uniform Push {
  uint n;        // the slots [first, n), all in one page of the list
  uint clockIn;  // the record this step reads
  uint first;
} pc;

// The pair loop's state, shared by its body (pair()) whichever way the list is read.
uint gI;
vec4 gPi, gVi;
HemoPairParams gPp;
float gKeep2;   // squared interaction range: entries within it are kept as interacting pairs
uint gMf, gMb;  // interacting pairs kept so far: fluid, boundary
uint gLast;     // the list's last entry (capacity - 1), where the boundary pairs start
float gRho;     // summation: the sum; continuity: the carried density
float gContinuity, gDiffused;
float gInvH, gGradNorm, gRho0, gHydroScale, gEtaSq;
vec3 gG;

// One list entry (a slot, with HEMO_LIST_BOUNDARY_BIT for a boundary neighbour); `valid` is
// false for the padding of the last texel (the entry is then this particle), which adds
// nothing and is not kept.
void pair(uint entry, bool valid) {
  const uint j = entry & ~HEMO_LIST_BOUNDARY_BIT;
  const bool boundary = entry >= HEMO_LIST_BOUNDARY_BIT;
  const vec4 pj = texelFetch(positions, int(j));
  const vec3 d = hemo_min_image(gPi.xyz - pj.xyz, gPp);  // x_ij
  const float r2 = dot(d, d);
#if HEMO_CELL_WALK
  // (a candidate beyond the support adds nothing; with no list, no interacting pairs)
  if (!(r2 < gPp.support2)) {
    return;
  }
#else
  // Interacting pairs: every entry is stored at the next free slot of its end of the list,
  // and that end advances only for entries in range (no branch around the store). Before
  // entry k, at most k pairs are kept, so both next free slots lie in the gap between the
  // ends (fluid count <= capacity - 1 - boundary count).
  pairList[hemo_list_slot(gI, boundary ? gLast - gMb : gMf, gPp)] = j;
  const bool kept = valid && r2 < gKeep2;
  gMf += kept && !boundary ? 1u : 0u;
  gMb += kept && boundary ? 1u : 0u;
#endif
  if (kContinuity != 0u) {
    const vec3 gradW = d * hemo_kernel_grad_factor(sqrt(r2), gInvH, gGradNorm);  // 0 beyond the support and for j = i
    const vec4 vj = texelFetch(velocities, int(j));
    gContinuity += pj.w * dot(gVi.xyz - vj.xyz, gradW);
    if (valid && uint(vj.w) == HEMO_KIND_FLUID) {
      const float rhoJ = hemo_carried_density(texelFetch(normals, int(j)).w, gRho0);
      const float hydro = gRho0 * (pow(max(1.0 - gHydroScale * dot(gG, d), 1.0e-6), 1.0 / 7.0) - 1.0);
      gDiffused += 2.0 * ((rhoJ - gRho) - hydro) * (-dot(d, gradW)) / (r2 + gEtaSq) * (pj.w / rhoJ);
    }
  } else if (valid && r2 < gPp.support2) {
    gRho += pj.w * hemo_kernel_w_inv(sqrt(r2), gInvH, gPp.kernelNorm);
  }
}

void main() {
  const uint i = pc.first + hemo_global_index();
  if (i >= pc.n) {
    return;
  }
  gI = i;
  gVi = texelFetch(velocities, int(i));
  if (uint(gVi.w) == HEMO_KIND_PARKED) {
    // No particle here (interface/sph.h): no volume, so a list built before it was parked
    // finds nothing in it (its position is the parking point's: beyond every support).
    const vec4 x = texelFetch(positions, int(i));
#if !HEMO_CELL_WALK
    pairCount[i] = 0u;
#endif
    state[i] = vec4(params.rho0, 0.0, 0.0, 0.0);
    pairPosition[i] = vec4(x.xyz, 0.0);
    viscousVel[i] = vec4(0.0);
    return;
  }
  if (uint(gVi.w) != HEMO_KIND_FLUID) {
    return;
  }
  gPi = texelFetch(positions, int(i));
  gPp = hemo_pair_params();
  gKeep2 = hemo_pair_keep2(gPp);
  gMf = 0u;
  gMb = 0u;
  gLast = params.neighbourCapacity - 1u;
  gContinuity = 0.0;
  gDiffused = 0.0;
  if (kContinuity != 0u) {
    gRho = hemo_carried_density(texelFetch(normals, int(i)).w, params.rho0);
    gInvH = 1.0 / gPp.h;
    gGradNorm = hemo_kernel_grad_norm(gPp.h, gPp.kernelNorm);
    gG = params.gravityOnly.xyz;
    gRho0 = params.rho0;
    gHydroScale = params.rho0 / params.taitB;
    gEtaSq = params.etaSq;  // registers
  } else {
    gInvH = 1.0 / gPp.h;
    gRho = gPi.w * hemo_kernel_w(0.0, gPp.h, gPp.kernelNorm);
  }
#if HEMO_CELL_WALK
  // the list's entries, in its order, among the candidates (common/cell_walk.glsl)
  const uint ranges = hemo_walk_ranges(i);
  for (uint r = 0u; r < ranges; ++r) {
    const uint mark = gRanges[r].y & HEMO_LIST_BOUNDARY_BIT;
    const uint end = gRanges[r].y & ~HEMO_LIST_BOUNDARY_BIT;
    for (uint j = gRanges[r].x; j < end; ++j) {
      if (j != i) {
        pair(j | mark, true);
      }
    }
  }
#else
  const uint count = texelFetch(neighbourCount, int(i)).x;
  for (uint k = 0u; k < count; k += 4u) {
    const uvec4 js = hemo_list_quad(neighbourList, i, k, count, gPp);
    pair(js.x, true);
    pair(k + 1u < count ? js.y : i, k + 1u < count);
    pair(k + 2u < count ? js.z : i, k + 2u < count);
    pair(k + 3u < count ? js.w : i, k + 3u < count);
  }
#endif
  float rho = gRho;
  float rate = 0.0;  // d rho / dt, for the RK2 stages (kContinuity = 2)
  if (kContinuity != 0u) {
    rate = gContinuity + params.deltaSph * gPp.h * params.c0 * gDiffused;
    if (kContinuity == 1u) {
      rho += clocks[pc.clockIn].lastDt * rate;
      rate = 0.0;
    }
  }
  const float time = clocks[pc.clockIn].time;
  const float background = hemo_background_pressure(time, params);
  float p = hemo_state_pressure(rho, background, params);
  if (inflow.open != 0u) {
    // Open ends (hemo/sim/inflow.hpp): a pressure end's buffer holds its pressure (the inlet's
    // rising over the inflow's ramp), whatever its particles' density.
    // A velocity-driven buffer takes the pressure the lumen has next to its plane (a zero
    // gradient along the axis, once measured): its own summed density is cut off at its far
    // end, and its images land among its particles.
    for (uint e = 0u; e < inflow.endCount; ++e) {
      const vec2 l = hemo_open_local(inflow, e, gPi.xyz);
      const float reach = inflow.ends[e].shift.w;
      if (l.x < inflow.ends[e].origin.w && l.x >= -reach && l.y < reach * reach) {
        if (inflow.ends[e].drive.z != 0.0) {
          p = background + hemo_open_end_pressure(e, time);
        } else if (openProfile[HEMO_OPEN_PRESSURE(e)] > 0.5 * HEMO_OPEN_NO_PRESSURE) {
          p = openProfile[HEMO_OPEN_PRESSURE(e)];
        }
        break;
      }
    }
  }
#if !HEMO_CELL_WALK
  pairCount[i] = gMf | gMb << 16u;  // hemo_pair_counts
#endif
  state[i] = vec4(rho, p, rate, 0.0);
  const float volume = gPi.w / rho;
  pairPosition[i] = vec4(gPi.xyz, volume * p);
  viscousVel[i] = vec4(gVi.xyz, volume);  // > 0: fluid
}
