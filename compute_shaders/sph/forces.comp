#version 450
// Accelerations of fluid particles from their neighbour list:
//  pressure   a -= (1 / rho_i) sum_j V_j (p_i + p_j) gradW_ij,  V_j = m_j / rho_j
//             The seed's symmetrisation (Mueller et al. 2003: f_i = -sum_j m_j (p_i + p_j) /
//             (2 rho_j) gradW, a force per volume) per unit mass and without its 1/2: for a
//             smooth field sum_j V_j p_i gradW_ij is about 0, so the sum approximates grad p,
//             where the halved one gives half of it (docs/physics.md). The form of DualSPHysics
//             (Crespo et al. 2015). m_i a_ij = -V_i V_j (p_i + p_j) gradW_ij: pairwise forces
//             are equal and opposite.
//  viscosity  a += m_j 2 mu / (rho_i rho_j) (x_ij . gradW_ij) / (r^2 + eta^2) v_ij
//             (laminar term of Morris et al. 1997 / Lo & Shao 2002); with non-Newtonian blood
//             (constant 3) 2 mu is mu_i + mu_j for a fluid pair and 2 mu_i for a boundary one,
//             mu_i from sph/sps_stress.comp (interface/sph.h, "Viscosity")
//  boundary   neighbours take part with the pressure, density and no-slip velocity
//             extrapolated to them from the fluid (boundary_pressure.comp), and repel: F = n N(x) T(y) with
//             N(x) = Psi (1 - r) / sqrt(r), r = x / 2h, for 0 < x < D (normal distance),
//             T(y) = 1 - y / dp for tangential distance y < dp; the summed force is divided
//             by max(sum T, 1), so it stays constant while a particle slides along a wall.
//  SPS        when enabled: a += (1 / rho_i) sum_j V_j (tau_i + tau_j) . gradW_ij (fluid
//             pairs; the stresses of Dalrymple & Rogers 2006 from sps_stress.comp, in the
//             pressure's symmetrisation)
//  gravity and body force.
// A neighbour's data is the pair data of interface/sph.h: the pair position (x_j, V_j p_j) and
// the viscous velocity (v_j, +-V_j), so the pair terms read
//   a += (1 / rho_i) sum_j [ -(V_j p_i + V_j p_j) gradW_ij + V_j (tau_i + tau_j) . gradW_ij
//                            + 2 mu V_j (x_ij . gradW_ij) / (r^2 + eta^2) v_ij ].
// accel.w keeps the repulsion's normalisation 1 / max(sum T, 1), so a wall particle can apply
// the exact reaction of its share. Also the particle's time-step limit min(C_a h / (c0 + |v|), C_f sqrt(h / |a|), dt_visc),
// and the first level of the time step's reduction over all limits (common/dt_fold.glsl).
#extension GL_GOOGLE_include_directive : require
#extension GL_KHR_shader_subgroup_basic : require
#extension GL_KHR_shader_subgroup_arithmetic : require
#extension GL_KHR_shader_subgroup_vote : require
#include "interface/sph.h"
#include "common/index.glsl"
#include "common/kernel.glsl"
#include "common/sph_params.glsl"
#include "common/repulsion.glsl"

// Read-only inputs: uniform texel buffers (interface/sph.h, "texel slots").
layout(binding = HEMO_FORCES_BINDING_POSITIONS) uniform samplerBuffer positions;
layout(binding = HEMO_FORCES_BINDING_VELOCITIES) uniform samplerBuffer velocities;
layout(binding = HEMO_FORCES_BINDING_NORMALS) uniform samplerBuffer normals;
HEMO_SPH_PARAMS_UNIFORM(HEMO_FORCES_BINDING_PARAMS);
layout(binding = HEMO_FORCES_BINDING_STATE) uniform samplerBuffer state;
layout(binding = HEMO_FORCES_BINDING_NCOUNT) uniform usamplerBuffer neighbourCount;
layout(binding = HEMO_FORCES_BINDING_NLIST) uniform usamplerBuffer neighbourList;
layout(std430, binding = HEMO_FORCES_BINDING_ACCEL) writeonly buffer Accel { vec4 accel[]; };
layout(std430, binding = HEMO_FORCES_BINDING_DT_LIMIT) writeonly buffer DtLimit { float dtLimit[]; };
layout(std430, binding = HEMO_FORCES_BINDING_IDS) readonly buffer Ids { uint ids[]; };
layout(std430, binding = HEMO_FORCES_BINDING_STATUS) buffer Status { uint status[]; };
layout(binding = HEMO_FORCES_BINDING_TAU_A) uniform samplerBuffer tauA;
layout(binding = HEMO_FORCES_BINDING_TAU_B) uniform samplerBuffer tauB;
layout(binding = HEMO_FORCES_BINDING_VISCOUS_VEL) uniform samplerBuffer viscousVel;
layout(binding = HEMO_FORCES_BINDING_PAIR_POSITION) uniform samplerBuffer pairPosition;
// The time step's reduction's first level (common/dt_fold.glsl).
layout(std430, binding = HEMO_FORCES_BINDING_DT_PARTIALS) writeonly buffer DtPartials { vec2 dtPartials[]; };
layout(std430, binding = HEMO_FORCES_BINDING_DT_COUNTS) writeonly buffer DtCounts { uint dtCounts[2]; };
layout(binding = HEMO_FORCES_BINDING_VISCOSITY) uniform samplerBuffer viscosityT;  // at fluid slots
// 1 when the scene enables the SPS term. A specialization constant rather than a branch on
// the parameter block: llvmpipe runs a branch's body under a lane mask even when no lane
// takes it, and the dead SPS loads cost ~10% of the pass (dam break, docs/benchmarks.md).
layout(constant_id = 1) const uint kSps = 0u;
// 4: the list is read four entries per texel (common/sph_params.glsl, hemo_list_texel)
layout(constant_id = 2) const uint kListWidth = 1u;
// 1: non-Newtonian blood, each fluid particle's viscosity from viscosityT (interface/sph.h,
// "Viscosity"); 0: params.mu for all.
layout(constant_id = 3) const uint kViscosity = 0u;
#if HEMO_CELL_WALK
#define HEMO_WALK_BUILD_POSITIONS neighbourCount
#define HEMO_WALK_CELL_START neighbourList
#include "common/cell_walk.glsl"
#endif

// The SPS stress tau (Pa) of particle j as a symmetric matrix (sps_stress.comp).
mat3 hemo_sps_tensor(uint j) {
  const vec4 a = texelFetch(tauA, int(j));
  const vec4 b = texelFetch(tauB, int(j));
  return mat3(a.x, a.w, b.x, a.w, a.y, b.y, b.x, b.y, a.z);
}
layout(push_constant) uniform Push {
  uint n;      // the slots [first, n), all in one page of the list
  uint first;  // a multiple of the workgroup size
  uint last;   // 1: the last of the pass's dispatches (it writes the time-step partials' count)
} pc;

#include "common/dt_fold.glsl"

const float kNoLimit = 3.0e38;

// The pair loop's state, shared by its body (pair()) whichever way the list is read.
vec3 gXi, gVi;
float gPI;
mat3 gSpsI;
HemoPairParams gPp;
float gInvH, gGradNorm, gEtaSq;
HemoRepulsionParams gRp;
vec3 gStress;     // sum V_j [ -(p_i + p_j) I + tau_i + tau_j ] . gradW
vec3 gViscous;    // sum V_j (x_ij . gradW) / (r^2 + eta^2) v_ij, times mu_i + mu_j with kViscosity
float gMuI;       // kViscosity: mu_i
vec3 gRepulsion;
float gRepulsionWeight;
#if HEMO_CELL_WALK
float gKeep2;  // cell walks: the interacting pairs' range squared (hemo_pair_keep2)
#endif

// One interacting pair (i, j), j a boundary or wall particle or not (a constant at each call,
// so each loop holds only its own terms). The padding of a texel read passes j = i: a pair at
// zero distance, whose terms are all exactly 0 (grad W = 0, and no repulsion at r = 0).
void pair(uint j, const bool boundary) {
  const vec4 pj = texelFetch(pairPosition, int(j));  // (x_j, V_j p_j)
  const vec3 d = hemo_min_image(gXi - pj.xyz, gPp);
  const float r2 = dot(d, d);
#if HEMO_CELL_WALK
  if (!(r2 < gKeep2)) {
    return;  // not an interacting pair (sph/density.comp keeps those within the range)
  }
#endif
  // grad W vanishes beyond the support (the list's skin) and for a coincident pair (no
  // defined direction), so neither needs a branch: llvmpipe runs both ways of a branch under
  // a lane mask, and the branch itself cost ~5% of the pass.
  const vec3 gradW = d * hemo_kernel_grad_factor(sqrt(r2), gInvH, gGradNorm);
  const vec4 vj = texelFetch(viscousVel, int(j));  // (fluid: own velocity, boundary: no-slip velocity; +-V_j)
  const float volumeJ = abs(vj.w);
  gStress -= (volumeJ * gPI + pj.w) * gradW;
  if (kViscosity != 0u) {
    const float muPair = gMuI + (boundary ? gMuI : texelFetch(viscosityT, int(j)).x);
    gViscous += (muPair * volumeJ * dot(d, gradW) / (r2 + gEtaSq)) * (gVi - vj.xyz);
  } else {
    gViscous += (volumeJ * dot(d, gradW) / (r2 + gEtaSq)) * (gVi - vj.xyz);
  }
  if (kSps != 0u && !boundary) {
    // sub-particle-scale stress (Dalrymple & Rogers 2006), fluid pairs only
    gStress += volumeJ * ((gSpsI + hemo_sps_tensor(j)) * gradW);
  }
  if (boundary && vj.w < 0.0 && r2 > 0.0) {  // boundary and wall particles; detached ones (V = 0) do not repel
    const vec3 nrm = texelFetch(normals, int(j)).xyz;
    const float x = dot(d, nrm);
    float w;
    const float push = hemo_repulsion(x, length(d - x * nrm), gRp, w);
    if (w > 0.0) {
      gRepulsion += nrm * push;
      gRepulsionWeight += w;
    }
  }
}

// The pairs in entries [first, end) of particle i's pair list: all fluid or all boundary.
void pairRange(uint i, uint first, uint end, const bool boundary) {
  // (one entry per texel: from `first` itself)
  for (uint k = kListWidth == 4u ? first & ~3u : first; k < end; k += 4u) {
    const uvec4 js = hemo_list_quad(neighbourList, i, k, end, gPp);
    pair(k >= first ? js.x : i, boundary);
    pair(k + 1u >= first && k + 1u < end ? js.y : i, boundary);
    pair(k + 2u >= first && k + 2u < end ? js.z : i, boundary);
    pair(k + 3u >= first && k + 3u < end ? js.w : i, boundary);
  }
}

// The acceleration of slot i (< n); returns its time-step limit.
float hemo_forces(uint i) {
  const vec4 vi = texelFetch(velocities, int(i));
  if (uint(vi.w) != HEMO_KIND_FLUID) {
    accel[i] = vec4(0.0);
    dtLimit[i] = kNoLimit;
    return kNoLimit;
  }
  const vec3 xi = texelFetch(positions, int(i)).xyz;
  const vec2 si = texelFetch(state, int(i)).xy;  // rho, p
  // Blow-up diagnosis, only until the first non-finite step has been recorded (after that
  // the NaNs have spread): which particle was non-finite first (its own state), or which
  // one's forces became non-finite from finite inputs.
  const bool diagnose = status[HEMO_STATUS_FIRST_BAD_STEP] == 0xffffffffu;
  const bool finiteInput = !(any(isnan(xi)) || any(isinf(xi)) || any(isnan(vi.xyz)) || any(isinf(vi.xyz)) ||
                             any(isnan(si)) || any(isinf(si)));
  if (diagnose && !finiteInput) {
    atomicMin(status[HEMO_STATUS_BAD_INPUT_ID], ids[i]);
  }
  // Parameters read once into registers (see HemoPairParams).
  gPp = hemo_pair_params();
  const float h = gPp.h;
  gInvH = 1.0 / h;
  gGradNorm = hemo_kernel_grad_norm(h, gPp.kernelNorm);
  // (non-Newtonian: the pair terms carry mu_i + mu_j themselves)
  const float twoMu = kViscosity != 0u ? 1.0 : 2.0 * params.mu;
  gMuI = kViscosity != 0u ? texelFetch(viscosityT, int(i)).x : 0.0;
  gEtaSq = params.etaSq;
  gRp = hemo_repulsion_params(h, params.psi, params.repulsionCutoff, params.wallSpacing);
  gXi = xi;
  gVi = vi.xyz;
  gSpsI = kSps != 0u ? hemo_sps_tensor(i) : mat3(0.0);
  gPI = si.y;
  gStress = vec3(0.0);
  gViscous = vec3(0.0);
  gRepulsion = vec3(0.0);
  gRepulsionWeight = 0.0;
  // the fluid pairs from the list's first entry, then the boundary pairs, which end at its
  // last (interface/sph.h)
#if HEMO_CELL_WALK
  // The same pairs in the same order without the list (common/cell_walk.glsl): the fluid
  // candidates forwards; the boundary ones backwards, as the density pass stores them from
  // the list's last entry down.
  gKeep2 = hemo_pair_keep2(gPp);
  const uint ranges = hemo_walk_ranges(i);
  for (uint r = 0u; r < ranges; ++r) {
    if (gRanges[r].y < HEMO_LIST_BOUNDARY_BIT) {
      for (uint j = gRanges[r].x; j < gRanges[r].y; ++j) {
        if (j != i) {
          pair(j, false);
        }
      }
    }
  }
  for (uint r = ranges; r > 0u; --r) {
    if (gRanges[r - 1u].y >= HEMO_LIST_BOUNDARY_BIT) {
      for (uint j = gRanges[r - 1u].y & ~HEMO_LIST_BOUNDARY_BIT; j > gRanges[r - 1u].x; --j) {
        pair(j - 1u, true);
      }
    }
  }
#else
  const uvec2 counts = hemo_pair_counts(texelFetch(neighbourCount, int(i)).x);
  pairRange(i, 0u, counts.x, false);
  pairRange(i, params.neighbourCapacity - counts.y, params.neighbourCapacity, true);
#endif
  const vec3 stress = gStress, viscous = gViscous, repulsion = gRepulsion;
  const float repulsionWeight = gRepulsionWeight;
  vec3 a = (stress + twoMu * viscous) / si.x;
  const float repulsionScale = 1.0 / max(repulsionWeight, 1.0);
  a += repulsion * repulsionScale;
  a += params.gravity.xyz;
  accel[i] = vec4(a, repulsionScale);  // w: for the wall's reaction (wall/spring_forces.comp)
  if (diagnose && finiteInput && (any(isnan(a)) || any(isinf(a)))) {
    atomicMin(status[HEMO_STATUS_BAD_FORCE_ID], ids[i]);
  }

  const float speed = length(vi.xyz);
  const float accelMag = length(a);
  // (under DFSPH c0 is 0: a particle at rest has no flow limit, and the floor keeps the
  // division defined)
  float limit = min(params.cflAcoustic * h / max(params.c0 + speed, 1.0e-30), params.dtViscous);
  if (accelMag > 0.0) {
    limit = min(limit, params.cflForce * sqrt(h / accelMag));
  }
  dtLimit[i] = limit;  // NaN if anything went non-finite: the reduction propagates it
  return limit;
}

void main() {
  const uint i = pc.first + hemo_global_index();
  const bool valid = i < pc.n;
  float limit = kNoLimit;
  if (valid) {
    limit = hemo_forces(i);
  }
  // every invocation: subgroup operations; the pages' workgroups numbered on from the first's
  hemo_dt_partial(limit, valid, 0u, 0u, pc.first / gl_WorkGroupSize.x, pc.last != 0u);
}
