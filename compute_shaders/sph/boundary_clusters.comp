#version 450
// sph/boundary_pressure.comp over the boundary particles' clusters (interface/sph.h,
// "Clusters"; scenes without wall particles): the same model, modes and outputs, with one
// invocation per cluster of HEMO_CLUSTER_SIZE boundary slots. Each fluid entry of the
// cluster's list is fetched once (position, state, velocity) and evaluated against every
// member (the list names each fluid neighbour of a member once; W is 0 beyond the support).
// The active list holds clusters with a fluid entry; a member of an active cluster without
// fluid within the support takes the values of a particle without fluid neighbours, as the
// per-particle pass gives it.
#extension GL_GOOGLE_include_directive : require
#include "interface/sph.h"
#include "common/index.glsl"
#include "common/kernel.glsl"
#include "common/cluster_texel.glsl"
#include "common/sph_params.glsl"
#include "common/clock.glsl"
#include "common/tait.glsl"

layout(binding = HEMO_BPRESSURE_BINDING_POSITIONS) uniform samplerBuffer positions;
layout(binding = HEMO_BPRESSURE_BINDING_VELOCITIES) uniform samplerBuffer velocities;
layout(binding = HEMO_BPRESSURE_BINDING_FLUID_STATE) uniform samplerBuffer fluidState;
HEMO_SPH_PARAMS_UNIFORM(HEMO_BPRESSURE_BINDING_PARAMS);
layout(std430, binding = HEMO_BPRESSURE_BINDING_STATE) writeonly buffer State { vec4 state[]; };
layout(binding = HEMO_BPRESSURE_BINDING_NCOUNT) uniform usamplerBuffer clusterCount;
layout(binding = HEMO_BPRESSURE_BINDING_NLIST) uniform usamplerBuffer clusterList;
layout(std430, binding = HEMO_BPRESSURE_BINDING_VISCOUS_VEL) writeonly buffer ViscousVel { vec4 viscousVel[]; };
layout(std140, binding = HEMO_BPRESSURE_BINDING_CLOCK) uniform Clock { ClockRecord clocks[2]; };
layout(std430, binding = HEMO_BPRESSURE_BINDING_PAIR_POSITION) writeonly buffer PairPosition { vec4 pairPosition[]; };
layout(std430, binding = HEMO_BPRESSURE_BINDING_ACTIVE) buffer Active { uint activeClusters[]; };
layout(std430, binding = HEMO_BPRESSURE_BINDING_ACTIVE_ARGS) buffer ActiveArgs { uvec4 activeArgs; };
#include "common/boundary_state.glsl"
layout(push_constant) uniform Push {
  uint first;     // the boundary slots [first, n), in clusters from `first` on
  uint n;
  uint clockIn;
  uint mode;      // HEMO_BPRESSURE_ACTIVE, _SORT or _REST
  uint capacity;  // entries per cluster (a multiple of 4)
  uint base;      // the cluster of slot `first`
} pc;

const uint M = HEMO_CLUSTER_SIZE;

vec3 gX[M];
HemoPairParams gPp;
float gHalfInvH;
float gSumW[M], gSumP[M];
vec3 gSumRhoR[M], gSumV[M];

// One entry (a fluid slot) with its data: position, (rho, p), velocity; `live` is 0 for the
// padding of the last texel (whose fetches read a member's data instead), 1 otherwise. Every
// member takes every entry: the list names each fluid neighbour of a member once, and W is 0
// from the support on.
void pair(vec3 xf, vec2 sf, vec3 vf, float live) {
  for (uint m = 0u; m < M; ++m) {
    const vec3 d = hemo_min_image(gX[m] - xf, gPp);
    // (the norm cancels in every ratio of common/boundary_state.glsl)
    const float w = hemo_kernel_w_shape_live(sqrt(dot(d, d)), gHalfInvH, live);
    gSumW[m] += w;
    gSumP[m] += sf.y * w;
    gSumRhoR[m] += sf.x * d * w;
    gSumV[m] += vf * w;
  }
}

void main() {
  uint c;  // the cluster, counted from `base`
  if (pc.mode == HEMO_BPRESSURE_ACTIVE) {
    const uint k = hemo_global_index();
    if (k >= activeArgs.w) {
      return;
    }
    c = activeClusters[k];
  } else {
    c = hemo_global_index();
  }
  const uint first = pc.first + c * M;
  if (first >= pc.n) {
    return;
  }
  const uint count = min(M, pc.n - first);
  const uint fluidEntries = texelFetch(clusterCount, int(pc.base + c)).x & 0xffffu;
  const float background = hemo_background_pressure(clocks[pc.clockIn].time, params);
  if (pc.mode != HEMO_BPRESSURE_ACTIVE) {
    if (fluidEntries > 0u) {
      if (pc.mode == HEMO_BPRESSURE_SORT) {
        // (in whatever order the invocations run: each cluster's result does not depend on
        // its place; the invocation that opens a workgroup's worth adds the workgroup. This
        // list is the one sph/cluster_order.comp then sorts into the evaluations' walk order.)
        const uint k = atomicAdd(activeArgs.w, 1u);
        activeClusters[k] = c;
        if (k % gl_WorkGroupSize.x == 0u) {
          const uvec2 groups = hemo_fold_groups(k / gl_WorkGroupSize.x + 1u);  // (atomicMax: any order)
          atomicMax(activeArgs.x, groups.x);
          atomicMax(activeArgs.y, groups.y);
        }
      }
      return;
    }
    for (uint m = 0u; m < count; ++m) {
      const uint b = first + m;
      hemo_boundary_store(b, texelFetch(positions, int(b)), texelFetch(velocities, int(b)).xyz, 0.0, 0.0, vec3(0.0),
                          vec3(0.0), background);
    }
    return;
  }
  gPp = hemo_pair_params();
  gHalfInvH = 0.5 / gPp.h;
  for (uint m = 0u; m < M; ++m) {
    // a missing member repeats the last one (its sums are not stored)
    gX[m] = texelFetch(positions, int(first + min(m, count - 1u))).xyz;
    gSumW[m] = 0.0;
    gSumP[m] = 0.0;
    gSumRhoR[m] = vec3(0.0);
    gSumV[m] = vec3(0.0);
  }
  const uint base = (pc.base + c) * pc.capacity;
  for (uint k = 0u; k < fluidEntries; k += 4u) {
    // a texel's four entries fetched together: the fetches (calls in llvmpipe, which spill the
    // live registers) come in one run
    // (the padding of the last texel fetches its first entry, a fluid slot: finite data; a
    // boundary slot's state is what this pass writes)
    const uvec4 e = texelFetch(clusterList, int((base + k) >> 2u));
    vec4 live;
    const ivec4 f = hemo_cluster_slots(e, k, 0u, fluidEntries, e.x & HEMO_CLUSTER_SLOT_MASK, live);
    const vec3 x0 = texelFetch(positions, f.x).xyz, x1 = texelFetch(positions, f.y).xyz;
    const vec3 x2 = texelFetch(positions, f.z).xyz, x3 = texelFetch(positions, f.w).xyz;
    const vec2 s0 = texelFetch(fluidState, f.x).xy, s1 = texelFetch(fluidState, f.y).xy;
    const vec2 s2 = texelFetch(fluidState, f.z).xy, s3 = texelFetch(fluidState, f.w).xy;
    const vec3 v0 = texelFetch(velocities, f.x).xyz, v1 = texelFetch(velocities, f.y).xyz;
    const vec3 v2 = texelFetch(velocities, f.z).xyz, v3 = texelFetch(velocities, f.w).xyz;
    pair(x0, s0, v0, live.x);
    pair(x1, s1, v1, live.y);
    pair(x2, s2, v2, live.z);
    pair(x3, s3, v3, live.w);
  }
  for (uint m = 0u; m < count; ++m) {
    const uint b = first + m;
    hemo_boundary_store(b, texelFetch(positions, int(b)), texelFetch(velocities, int(b)).xyz, gSumW[m], gSumP[m],
                        gSumRhoR[m], gSumV[m], background);
  }
}
