#version 450
// sph/density.comp's summation density over the clusters' lists (interface/sph.h, "Clusters"):
// one invocation per cluster, every entry fetched once and evaluated against all members,
//   rho_i = sum_j m_j W(|x_i - x_j|, h)   (j includes i: each member is in its cluster's list)
//   p_i   = B ((rho_i / rho0)^7 - 1) + p_bg   (common/tait.glsl)
// and the pair data of interface/sph.h: pair position (x, V p) and viscous velocity (v, V).
// Every member counts every entry: the build lists each neighbour of a member once, and W is 0
// from the support on, so the entry's mask is not needed. A compact cluster walks its front
// section taking each entry's periodic image once (common/cluster_frame.glsl); the back
// section, and a wide cluster's front, take the minimum image per member and entry.
#extension GL_GOOGLE_include_directive : require
#include "interface/sph.h"
#include "common/index.glsl"
#include "common/kernel.glsl"
#include "common/cluster_texel.glsl"
#include "common/sph_params.glsl"
#include "common/cluster_frame.glsl"
#include "common/clock.glsl"
#include "common/tait.glsl"

layout(binding = HEMO_CDENSITY_BINDING_POSITIONS) uniform samplerBuffer positions;
layout(binding = HEMO_CDENSITY_BINDING_VELOCITIES) uniform samplerBuffer velocities;
HEMO_SPH_PARAMS_UNIFORM(HEMO_CDENSITY_BINDING_PARAMS);
layout(std430, binding = HEMO_CDENSITY_BINDING_STATE) writeonly buffer State { vec4 state[]; };
layout(binding = HEMO_CDENSITY_BINDING_CCOUNT) uniform usamplerBuffer clusterCount;
layout(binding = HEMO_CDENSITY_BINDING_CLIST) uniform usamplerBuffer clusterList;
layout(std140, binding = HEMO_CDENSITY_BINDING_CLOCK) uniform Clock { ClockRecord clocks[2]; };
layout(std430, binding = HEMO_CDENSITY_BINDING_VISCOUS_VEL) writeonly buffer ViscousVel { vec4 viscousVel[]; };
layout(std430, binding = HEMO_CDENSITY_BINDING_PAIR_POSITION) writeonly buffer PairPosition { vec4 pairPosition[]; };
layout(binding = HEMO_CDENSITY_BINDING_ORDER) uniform usamplerBuffer clusterOrder;
layout(push_constant) uniform Push {
  uint fluid;     // fluid slots: [0, fluid)
  uint capacity;  // entries per cluster (a multiple of 4)
  uint clockIn;   // the clock record this step reads
} pc;

const uint M = HEMO_CLUSTER_SIZE;

vec3 gX[M];  // in the cluster's frame (common/cluster_frame.glsl)
vec3 gCentre;
float gRho[M];
HemoPairParams gPp;
float gHalfInvH;

// One entry whose data is fetched; `live` is 0 for the padding of a texel (whose fetch read a
// member's data instead), 1 otherwise. Every member counts every entry: the list names each
// neighbour once (the build's masks are not needed here), and W is 0 from the support on.
// `frame`: the entry's image nearest the centre serves every member (a compact cluster), or
// each member takes the minimum image.
void pair(vec4 pj, float live, const bool frame) {
  const vec3 xj = frame ? hemo_image_near(pj.xyz, gCentre, gPp) : pj.xyz;
  for (uint m = 0u; m < M; ++m) {
    const vec3 d = frame ? gX[m] - xj : hemo_min_image(gX[m] - xj, gPp);
    const float w = hemo_kernel_w_shape_live(sqrt(dot(d, d)), gHalfInvH, live);  // the norm applied to the sum
    gRho[m] += pj.w * w;
  }
}

// Texels [0, texels) of a walk of the cluster's list (common/cluster_texel.glsl): a texel's
// four entries fetched together, so that the fetches (calls in llvmpipe, which spill the live
// registers) come in one run. The padding of a texel fetches slot `own` (a member: finite
// data) and counts for nothing.
void walk(uint base, HemoClusterWalk w, uint own, const bool frame) {
  for (uint t = 0u; t < w.texels; ++t) {
    uint k, first, end;
    hemo_cluster_walk_texel(w, t, k, first, end);
    const uvec4 e = texelFetch(clusterList, int((base + k) >> 2u));
    vec4 live;
    const ivec4 j = hemo_cluster_slots(e, k, first, end, own, live);
    const vec4 p0 = texelFetch(positions, j.x);
    const vec4 p1 = texelFetch(positions, j.y);
    const vec4 p2 = texelFetch(positions, j.z);
    const vec4 p3 = texelFetch(positions, j.w);
    pair(p0, live.x, frame);
    pair(p1, live.y, frame);
    pair(p2, live.z, frame);
    pair(p3, live.w, frame);
  }
}

void main() {
  // (in the walk order of sph/cluster_order.comp: lanes with lists of about the same length)
  const uint g = hemo_global_index();
  if (g * M >= pc.fluid) {
    return;
  }
  const uint cluster = texelFetch(clusterOrder, int(g)).x;
  const uint first = cluster * M;
  const uint count = min(M, pc.fluid - first);
  gPp = hemo_pair_params();
  gHalfInvH = 0.5 / gPp.h;
  for (uint m = 0u; m < M; ++m) {
    gX[m] = texelFetch(positions, int(first + min(m, count - 1u))).xyz;
    gRho[m] = 0.0;
  }
  const bool compact = hemo_cluster_frame(gX, gPp, gCentre);
  const uint counts = texelFetch(clusterCount, int(cluster)).x;
  const uint base = cluster * pc.capacity;
  // a compact cluster's front in its frame; the back (and a wide cluster's front) per member
  walk(base, hemo_cluster_front(counts, compact), first, true);
  walk(base, hemo_cluster_rest(counts, compact, pc.capacity), first, false);
  const float background = hemo_background_pressure(clocks[pc.clockIn].time, params);
  for (uint m = 0u; m < M; ++m) {
    if (m < count) {
      const uint i = first + m;
      const float rho = gRho[m] * gPp.kernelNorm;
      const float p = hemo_tait_pressure(rho, background, params);
      state[i] = vec4(rho, p, 0.0, 0.0);
      const vec4 xi = texelFetch(positions, int(i));
      const vec4 vi = texelFetch(velocities, int(i));
      const float volume = xi.w / rho;
      pairPosition[i] = vec4(xi.xyz, volume * p);
      viscousVel[i] = vec4(vi.xyz, volume);
    }
  }
}
