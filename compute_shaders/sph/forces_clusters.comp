#version 450
// sph/forces.comp over the clusters' lists (interface/sph.h, "Clusters"): one invocation per
// cluster, every entry fetched once and evaluated against all members. The terms are those of
// sph/forces.comp (pressure, laminar viscosity, the boundary's repulsion, gravity and body
// force) and so are the outputs: accel (a, 1 / max(sum T, 1)), the time-step limit, the blow-up
// diagnosis and the time step's first reduction level, here one (min, max) per invocation's
// members. Every member takes every entry (the list names each neighbour of a member once);
// beyond the support the kernel terms vanish and the repulsion's reach is shorter still. The
// repulsion runs over the list's back section only, which holds every boundary neighbour that
// may come within its reach before the next build; the front's boundary entries get the
// pressure and viscous terms alone, the same as in the back. A compact cluster walks its front
// taking each entry's periodic image once (common/cluster_frame.glsl); a wide one walks its
// front with the back, with the minimum image per member and entry and the repulsion (which
// the front's entries, all beyond its reach, leave unchanged). No SPS term: scenes with it use
// the per-particle lists.
#extension GL_GOOGLE_include_directive : require
#extension GL_KHR_shader_subgroup_basic : require
#extension GL_KHR_shader_subgroup_arithmetic : require
#extension GL_KHR_shader_subgroup_vote : require
#include "interface/sph.h"
#include "common/index.glsl"
#include "common/kernel.glsl"
#include "common/cluster_texel.glsl"
#include "common/sph_params.glsl"
#include "common/cluster_frame.glsl"
#include "common/repulsion.glsl"

layout(binding = HEMO_CFORCES_BINDING_POSITIONS) uniform samplerBuffer positions;
layout(binding = HEMO_CFORCES_BINDING_VELOCITIES) uniform samplerBuffer velocities;
layout(binding = HEMO_CFORCES_BINDING_NORMALS) uniform samplerBuffer normals;
HEMO_SPH_PARAMS_UNIFORM(HEMO_CFORCES_BINDING_PARAMS);
layout(binding = HEMO_CFORCES_BINDING_STATE) uniform samplerBuffer state;
layout(binding = HEMO_CFORCES_BINDING_CCOUNT) uniform usamplerBuffer clusterCount;
layout(binding = HEMO_CFORCES_BINDING_CLIST) uniform usamplerBuffer clusterList;
layout(std430, binding = HEMO_CFORCES_BINDING_ACCEL) writeonly buffer Accel { vec4 accel[]; };
layout(std430, binding = HEMO_CFORCES_BINDING_DT_LIMIT) writeonly buffer DtLimit { float dtLimit[]; };
layout(std430, binding = HEMO_CFORCES_BINDING_IDS) readonly buffer Ids { uint ids[]; };
layout(std430, binding = HEMO_CFORCES_BINDING_STATUS) buffer Status { uint status[]; };
layout(binding = HEMO_CFORCES_BINDING_VISCOUS_VEL) uniform samplerBuffer viscousVel;
layout(binding = HEMO_CFORCES_BINDING_PAIR_POSITION) uniform samplerBuffer pairPosition;
layout(std430, binding = HEMO_CFORCES_BINDING_DT_PARTIALS) writeonly buffer DtPartials { vec2 dtPartials[]; };
layout(std430, binding = HEMO_CFORCES_BINDING_DT_COUNTS) writeonly buffer DtCounts { uint dtCounts[2]; };
layout(binding = HEMO_CFORCES_BINDING_ORDER) uniform usamplerBuffer clusterOrder;
layout(push_constant) uniform Push {
  uint fluid;     // fluid slots: [0, fluid)
  uint capacity;  // entries per cluster (a multiple of 4)
  uint n;         // the slots [fluid, n) get sph/forces.comp's values for other kinds
} pc;

#include "common/dt_fold.glsl"

const uint M = HEMO_CLUSTER_SIZE;
const float kNoLimit = 3.0e38;

vec3 gX[M], gV[M];  // gX in the cluster's frame (common/cluster_frame.glsl)
vec3 gCentre;
float gP[M];
// sum V_j [ -(p_i + p_j) gradW + 2 mu (x_ij . gradW) / (r^2 + eta^2) v_ij ] / gradNorm: one
// sum for both terms, as the registers of eight members are scarce
vec3 gSum[M];
vec4 gRepulsion[M];  // (sum n N T, sum T)
HemoPairParams gPp;
float gHalfInvH, gGradNorm, gEtaSq, gTwoMu;
HemoRepulsionParams gRp;

// One entry (the front section in the cluster's frame, or with the repulsion and the minimum
// image per member: constants at each call); `live` is 0 for the padding of a texel (whose
// fetches read a member's data instead), 1 otherwise. Every member takes every entry: the list
// names each neighbour of a member once, the kernel terms are 0 from the support on and the
// repulsion's reach is shorter still.
void pair(vec4 pj, vec4 vj, vec3 nrm, float live, const bool boundary, const bool frame) {
  const float volumeJ = abs(vj.w);
  const float viscJ = gTwoMu * volumeJ;
  const vec3 xj = frame ? hemo_image_near(pj.xyz, gCentre, gPp) : pj.xyz;
  for (uint m = 0u; m < M; ++m) {
    const vec3 d = frame ? gX[m] - xj : hemo_min_image(gX[m] - xj, gPp);
    const float r2 = dot(d, d);
    // grad W = F d, so x_ij . grad W = F r^2: both terms carry F (over gradNorm: the sum's
    // factor, applied once at the end)
    const float f = hemo_kernel_grad_shape_live(sqrt(r2), gHalfInvH, live);
    gSum[m] += f * ((viscJ * r2 / (r2 + gEtaSq)) * (gV[m] - vj.xyz) - (volumeJ * gP[m] + pj.w) * d);
    if (boundary) {
      // boundary and wall particles; detached ones (V = 0) do not repel, nor does a
      // coincident one (no direction), nor the padding (a fluid member: V > 0)
      const float x = dot(d, nrm);
      float w;
      const float push = hemo_repulsion(x, length(d - x * nrm), gRp, w);
      const bool repels = vj.w < 0.0 && r2 > 0.0 && w > 0.0;
      gRepulsion[m] += repels ? vec4(nrm * push, w) : vec4(0.0);
    }
  }
}

// Texels [0, texels) of a walk of the cluster's list (common/cluster_texel.glsl): a texel's
// four entries fetched together, so that the fetches (calls in llvmpipe, which spill the live
// registers) come in one run. The padding of a texel fetches slot `own` (a member: finite
// data) and counts for nothing.
void walk(uint base, HemoClusterWalk w, uint own, const bool boundary, const bool frame) {
  for (uint t = 0u; t < w.texels; ++t) {
    uint k, first, end;
    hemo_cluster_walk_texel(w, t, k, first, end);
    const uvec4 e = texelFetch(clusterList, int((base + k) >> 2u));
    vec4 live;
    const ivec4 j = hemo_cluster_slots(e, k, first, end, own, live);
    // (x_j, V_j p_j) and (v_j, +-V_j)
    const vec4 p0 = texelFetch(pairPosition, j.x), p1 = texelFetch(pairPosition, j.y);
    const vec4 p2 = texelFetch(pairPosition, j.z), p3 = texelFetch(pairPosition, j.w);
    const vec4 v0 = texelFetch(viscousVel, j.x), v1 = texelFetch(viscousVel, j.y);
    const vec4 v2 = texelFetch(viscousVel, j.z), v3 = texelFetch(viscousVel, j.w);
    vec3 n0 = vec3(0.0), n1 = vec3(0.0), n2 = vec3(0.0), n3 = vec3(0.0);
    if (boundary) {
      n0 = texelFetch(normals, j.x).xyz;
      n1 = texelFetch(normals, j.y).xyz;
      n2 = texelFetch(normals, j.z).xyz;
      n3 = texelFetch(normals, j.w).xyz;
    }
    pair(p0, v0, n0, live.x, boundary, frame);
    pair(p1, v1, n1, live.y, boundary, frame);
    pair(p2, v2, n2, live.z, boundary, frame);
    pair(p3, v3, n3, live.w, boundary, frame);
  }
}

void main() {
  // Invocations past the clusters: one per slot of [fluid, n), no acceleration and no limit.
  // (clusters in the walk order of sph/cluster_order.comp: lanes with lists of about the same
  // length)
  const uint g = hemo_global_index();
  const uint clusters = (pc.fluid + M - 1u) / M;
  const uint cluster = g < clusters ? texelFetch(clusterOrder, int(g)).x : g;
  const uint first = cluster * M;
  const float inf = uintBitsToFloat(0x7f800000u);
  vec2 limits = vec2(inf, -inf);
  bool anyNan = false;
  const uint other = pc.fluid + (cluster - clusters);
  if (cluster >= clusters && other < pc.n) {
    accel[other] = vec4(0.0);
    dtLimit[other] = kNoLimit;
    limits = vec2(kNoLimit);
  }
  if (cluster < clusters) {
    const uint count = min(M, pc.fluid - first);
    gPp = hemo_pair_params();
    gHalfInvH = 0.5 / gPp.h;
    gGradNorm = hemo_kernel_grad_norm(gPp.h, gPp.kernelNorm);
    gEtaSq = params.etaSq;
    gTwoMu = 2.0 * params.mu;
    gRp = hemo_repulsion_params(gPp.h, params.psi, params.repulsionCutoff, params.wallSpacing);
    const bool diagnose = status[HEMO_STATUS_FIRST_BAD_STEP] == 0xffffffffu;
    float rho[M];
    bool finiteInput[M];
    for (uint m = 0u; m < M; ++m) {
      const uint i = first + min(m, count - 1u);
      const vec3 xi = texelFetch(positions, int(i)).xyz;
      const vec3 vi = texelFetch(velocities, int(i)).xyz;
      const vec2 si = texelFetch(state, int(i)).xy;  // rho, p
      gX[m] = xi;
      gV[m] = vi;
      gP[m] = si.y;
      rho[m] = si.x;
      finiteInput[m] = !(any(isnan(xi)) || any(isinf(xi)) || any(isnan(vi)) || any(isinf(vi)) || any(isnan(si)) ||
                         any(isinf(si)));
      gSum[m] = vec3(0.0);
      gRepulsion[m] = vec4(0.0);
    }
    const bool compact = hemo_cluster_frame(gX, gPp, gCentre);
    const uint counts = texelFetch(clusterCount, int(cluster)).x;
    const uint base = cluster * pc.capacity;
    // a compact cluster's front in its frame; the back (and a wide cluster's front) per member
    walk(base, hemo_cluster_front(counts, compact), first, false, true);
    walk(base, hemo_cluster_rest(counts, compact, pc.capacity), first, true, false);
    const float h = gPp.h;
    for (uint m = 0u; m < M; ++m) {
      if (m < count) {
        const uint i = first + m;
        if (diagnose && !finiteInput[m]) {
          atomicMin(status[HEMO_STATUS_BAD_INPUT_ID], ids[i]);
        }
        vec3 a = gSum[m] * (gGradNorm / rho[m]);
        const float repulsionScale = 1.0 / max(gRepulsion[m].w, 1.0);
        a += gRepulsion[m].xyz * repulsionScale;
        a += params.gravity.xyz;
        accel[i] = vec4(a, repulsionScale);
        if (diagnose && finiteInput[m] && (any(isnan(a)) || any(isinf(a)))) {
          atomicMin(status[HEMO_STATUS_BAD_FORCE_ID], ids[i]);
        }
        const float speed = length(gV[m]);
        const float accelMag = length(a);
        float limit = min(params.cflAcoustic * h / max(params.c0 + speed, 1.0e-30), params.dtViscous);
        if (accelMag > 0.0) {
          limit = min(limit, params.cflForce * sqrt(h / accelMag));
        }
        dtLimit[i] = limit;  // NaN if anything went non-finite
        limits = vec2(min(limits.x, limit), max(limits.y, limit));
        anyNan = anyNan || isnan(limit);
      }
    }
  }
  hemo_dt_partial_range(limits, anyNan, 0u, 0u);  // every invocation: subgroup operations
}
