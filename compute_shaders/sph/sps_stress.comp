#version 450
// What the fluid's strain rate gives each fluid particle, in one pass over its pairs: the
// sub-particle-scale (SPS) turbulence stress (constant 2) and its non-Newtonian viscosity
// (constant 3, interface/sph.h "Viscosity"). Runs only when the scene asks for either.
// The SPS stress of Dalrymple & Rogers (2006), in the form used by DualSPHysics: with the
// strain rate S = (grad u + grad u^T) / 2 from
//   grad u_i = sum_j (m_j / rho_j) (u_j - u_i) (x) gradW_ij   (fluid and boundary neighbours;
//   boundary particles bring their wall velocity, so walls shear the flow),
// |S| = sqrt(2 S:S), nu_t = (C_s dp)^2 |S|, the stress is
//   tau = rho (2 nu_t (S - tr(S) I / 3) - 2/3 C_I dp^2 |S|^2 I).
// forces.comp adds (1 / rho_i) sum_j V_j (tau_i + tau_j) . gradW_ij between fluid particles,
// the symmetrisation of its pressure term. The viscosity: the Carreau-Yasuda law at the shear
// rate |S| of the corrected gradient (interface/sph.h, "Viscosity").
#extension GL_GOOGLE_include_directive : require
#include "interface/sph.h"
#include "common/index.glsl"
#include "common/kernel.glsl"
#include "common/sph_params.glsl"

// Read-only inputs are uniform texel buffers (interface/sph.h, "texel slots").
layout(binding = HEMO_SPS_BINDING_POSITIONS) uniform samplerBuffer positions;
layout(binding = HEMO_SPS_BINDING_VELOCITIES) uniform samplerBuffer velocities;
HEMO_SPH_PARAMS_UNIFORM(HEMO_SPS_BINDING_PARAMS);
layout(binding = HEMO_SPS_BINDING_STATE) uniform samplerBuffer state;
layout(binding = HEMO_SPS_BINDING_NCOUNT) uniform usamplerBuffer neighbourCount;
layout(binding = HEMO_SPS_BINDING_NLIST) uniform usamplerBuffer neighbourList;
layout(std430, binding = HEMO_SPS_BINDING_TAU_A) writeonly buffer TauA { vec4 tauA[]; };
layout(std430, binding = HEMO_SPS_BINDING_TAU_B) writeonly buffer TauB { vec4 tauB[]; };
layout(std430, binding = HEMO_SPS_BINDING_VISCOSITY) writeonly buffer Viscosity { float viscosity[]; };
layout(binding = HEMO_SPS_BINDING_VISCOUS_VEL) uniform samplerBuffer viscousVel;  // the pair data (v_j, +-V_j)
// 4: the list is read four entries per texel (common/sph_params.glsl, hemo_list_texel)
layout(constant_id = 1) const uint kListWidth = 1u;
// 1 where the pass writes the SPS stress (tauA, tauB) and the non-Newtonian viscosity
// (viscosity) respectively.
layout(constant_id = 2) const uint kStress = 1u;
layout(constant_id = 3) const uint kViscosity = 0u;
#if HEMO_CELL_WALK
#define HEMO_WALK_BUILD_POSITIONS neighbourCount
#define HEMO_WALK_CELL_START neighbourList
#include "common/cell_walk.glsl"
#endif
layout(push_constant) uniform Push {
  uint n;  // the slots [first, n), all in one page of the list
  uint first;
} pc;

// The loop's state, shared by its body (pair()) whichever way the list is read.
vec3 gXi, gVi;
HemoPairParams gPp;
float gInvH, gGradNorm;
mat3 gG;  // g[b][a] = d u_a / d x_b (column b)
mat3 gGv;  // kViscosity: sum_j V_j (u_j - u_i) (x) gradW_ij with the no-slip velocity of boundary j
mat3 gM;   // kViscosity: sum_j V_j (x_j - x_i) (x) gradW_ij, the gradient's correction (its inverse)
#if HEMO_CELL_WALK
float gKeep2;  // cell walks: the interacting pairs' range squared (hemo_pair_keep2)
#endif

// One interacting pair; the padding of the list's last texel passes j = i, whose grad W is 0.
void pair(uint j) {
  const vec4 pj = texelFetch(positions, int(j));
  const vec3 d = hemo_min_image(gXi - pj.xyz, gPp);
#if HEMO_CELL_WALK
  if (!(dot(d, d) < gKeep2)) {
    return;  // not an interacting pair (sph/density.comp keeps those within the range)
  }
#endif
  // grad W is 0 beyond the support and for a coincident pair (common/kernel.glsl)
  const vec3 gradW = d * hemo_kernel_grad_factor(sqrt(dot(d, d)), gInvH, gGradNorm);
  if (kStress != 0u) {
    const vec3 du = (texelFetch(velocities, int(j)).xyz - gVi) * (pj.w / texelFetch(state, int(j)).x);
    gG += outerProduct(du, gradW);
  }
  if (kViscosity != 0u) {
    const vec4 vj = texelFetch(viscousVel, int(j));  // (the no-slip velocity of a boundary particle, +-V_j)
    const float volumeJ = abs(vj.w);
    gGv += outerProduct((vj.xyz - gVi) * volumeJ, gradW);
    gM -= outerProduct(d * volumeJ, gradW);
  }
}

// The pairs in entries [first, end) of particle i's pair list.
void pairRange(uint i, uint first, uint end) {
  // (one entry per texel: from `first` itself)
  for (uint k = kListWidth == 4u ? first & ~3u : first; k < end; k += 4u) {
    const uvec4 js = hemo_list_quad(neighbourList, i, k, end, gPp);
    pair(k >= first ? js.x : i);
    pair(k + 1u >= first && k + 1u < end ? js.y : i);
    pair(k + 2u >= first && k + 2u < end ? js.z : i);
    pair(k + 3u >= first && k + 3u < end ? js.w : i);
  }
}

void main() {
  const uint i = pc.first + hemo_global_index();
  if (i >= pc.n) {
    return;
  }
  const vec4 vi = texelFetch(velocities, int(i));
  if (uint(vi.w) != HEMO_KIND_FLUID) {
    if (kStress != 0u) {
      tauA[i] = vec4(0.0);
      tauB[i] = vec4(0.0);
    }
    if (kViscosity != 0u) {
      viscosity[i] = 0.0;  // (read by nobody: pairs with a boundary particle take the fluid's)
    }
    return;
  }
  gXi = texelFetch(positions, int(i)).xyz;
  gVi = vi.xyz;
  gPp = hemo_pair_params();
  gInvH = 1.0 / gPp.h;
  gGradNorm = hemo_kernel_grad_norm(gPp.h, gPp.kernelNorm);
  gG = mat3(0.0);
  gGv = mat3(0.0);
  gM = mat3(0.0);
  // the fluid pairs from the list's first entry, then the boundary pairs, which end at its
  // last (interface/sph.h)
#if HEMO_CELL_WALK
  // the same pairs in the same order without the list (sph/forces.comp)
  gKeep2 = hemo_pair_keep2(gPp);
  const uint ranges = hemo_walk_ranges(i);
  for (uint r = 0u; r < ranges; ++r) {
    if (gRanges[r].y < HEMO_LIST_BOUNDARY_BIT) {
      for (uint j = gRanges[r].x; j < gRanges[r].y; ++j) {
        if (j != i) {
          pair(j);
        }
      }
    }
  }
  for (uint r = ranges; r > 0u; --r) {
    if (gRanges[r - 1u].y >= HEMO_LIST_BOUNDARY_BIT) {
      for (uint j = gRanges[r - 1u].y & ~HEMO_LIST_BOUNDARY_BIT; j > gRanges[r - 1u].x; --j) {
        pair(j - 1u);
      }
    }
  }
#else
  const uvec2 counts = hemo_pair_counts(texelFetch(neighbourCount, int(i)).x);
  pairRange(i, 0u, counts.x);
  pairRange(i, params.neighbourCapacity - counts.y, params.neighbourCapacity);
#endif
  if (kViscosity != 0u) {
    // Carreau-Yasuda: mu_inf + (mu_0 - mu_inf) (1 + (lambda |S|)^a)^((n - 1) / a), |S| of the
    // corrected gradient G M^-1 (G alone where M is nearly singular)
    const mat3 m = gM;
    const mat3 c = determinant(m) > 0.25 ? gGv * inverse(m) : gGv;
    const float cxy = 0.5 * (c[1][0] + c[0][1]), cxz = 0.5 * (c[2][0] + c[0][2]), cyz = 0.5 * (c[2][1] + c[1][2]);
    const float rate = sqrt(2.0 * (c[0][0] * c[0][0] + c[1][1] * c[1][1] + c[2][2] * c[2][2] +
                                   2.0 * (cxy * cxy + cxz * cxz + cyz * cyz)));
    const vec4 cy = params.carreau;
    const float lg = cy.z * rate;
    const float shear = lg > 0.0 ? pow(lg, cy.w) : 0.0;
    viscosity[i] = cy.x + cy.y * pow(1.0 + shear, params.rheologyExponent);
  }
  if (kStress == 0u) {
    return;
  }
  const mat3 g = gG;
  const float sxx = g[0][0], syy = g[1][1], szz = g[2][2];
  const float sxy = 0.5 * (g[1][0] + g[0][1]);
  const float sxz = 0.5 * (g[2][0] + g[0][2]);
  const float syz = 0.5 * (g[2][1] + g[1][2]);
  const float s2 = 2.0 * (sxx * sxx + syy * syy + szz * szz + 2.0 * (sxy * sxy + sxz * sxz + syz * syz));  // |S|^2
  const float magnitude = sqrt(s2);
  const float rho = texelFetch(state, int(i)).x;
  const float twoMuT = 2.0 * rho * params.spsSmagorinsky * magnitude;  // 2 rho nu_t
  const float trace3 = (sxx + syy + szz) / 3.0;
  const float iso = rho * (2.0 / 3.0) * params.spsBlinn * s2;
  tauA[i] = vec4(twoMuT * (sxx - trace3) - iso, twoMuT * (syy - trace3) - iso, twoMuT * (szz - trace3) - iso,
                 twoMuT * sxy);
  tauB[i] = vec4(twoMuT * sxz, twoMuT * syz, 0.0, 0.0);
}
