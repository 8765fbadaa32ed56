#version 450
// The clusters' lists (interface/sph.h, "Clusters"): for each cluster of HEMO_CLUSTER_SIZE
// consecutive fluid slots, every particle closer than the list radius to at least one member,
// with the mask of the members it is that close to; for a cluster of boundary slots (a second
// dispatch, in scenes without wall particles), every such fluid particle. One invocation per
// cluster. Its members are grouped by row of grid cells (the slots are in cell order, so a
// row's members are consecutive); each group walks the cells within the list radius of its
// members, as sph/build_list.comp does for one particle, and tests every candidate against
// its members. Boundary neighbours within the repulsion's reach (plus the skin) of a member go
// to the back of the list, all others to the front (interface/sph.h).
#extension GL_GOOGLE_include_directive : require
#extension GL_KHR_shader_subgroup_basic : require
#extension GL_KHR_shader_subgroup_arithmetic : require
#include "interface/sph.h"
#include "common/index.glsl"
#include "common/grid.glsl"
#include "common/sph_params.glsl"
#include "common/repulsion.glsl"

layout(binding = HEMO_CBUILD_BINDING_POSITIONS) uniform samplerBuffer positions;
layout(binding = HEMO_CBUILD_BINDING_CELL_START) uniform usamplerBuffer cellStart;
HEMO_SPH_PARAMS_UNIFORM(HEMO_CBUILD_BINDING_PARAMS);
layout(std430, binding = HEMO_CBUILD_BINDING_CCOUNT) writeonly buffer Counts { uint clusterCount[]; };
// (written a texel of four entries at a time)
layout(std430, binding = HEMO_CBUILD_BINDING_CLIST) writeonly buffer List { uvec4 clusterList[]; };
layout(std430, binding = HEMO_CBUILD_BINDING_STATUS) buffer Status { uint status[]; };
layout(std430, binding = HEMO_CBUILD_BINDING_ACTIVE_ARGS) writeonly buffer ActiveArgs { uvec4 activeArgs; };
layout(push_constant) uniform Push {
  HemoGrid grid;
  uint first;     // the dispatch's slots: [first, end), all fluid or all boundary
  uint end;
  uint capacity;  // entries per cluster
  uint base;      // the cluster of slot `first`
  uint boundary;  // 1: the members are boundary particles (they list fluid neighbours only)
} pc;

const uint M = HEMO_CLUSTER_SIZE;

// members' positions in cell units, in the period of their cells (common/list_ranges.glsl
// trims each row to the group's members in gListPointMask)
#define HEMO_LIST_POINTS HEMO_CLUSTER_SIZE
vec3 gListPoints[M];
uint gListPointMask;
#include "common/list_ranges.glsl"

vec3 gX[M];    // members' positions
ivec3 gC[M];   // members' cells
uint gNf, gNb; // entries kept: the front section (from entry 0 up) and the back (from the last down)
// Entries naming each member (itself included), two members per word in 16-bit halves
// (members 0 and 1, then 2 and 3): fewer operations per candidate than a counter each. An
// entry names a member at most once and a cluster holds fewer than 2^16 entries.
#if HEMO_CLUSTER_SIZE != 4
#error "the packed member counts assume clusters of four"
#endif
uvec2 gNamed;
uvec4 gPendingF, gPendingB;  // kept entries not yet stored (append())
uint gMembers;  // the cluster's members (a missing member is in no mask)
uint gEarlier;  // the members of the groups walked before this one
// The squared distance within which a boundary neighbour may come into the repulsion's reach
// (common/repulsion.glsl) before the next build: that reach plus the skin, by which a pair
// closes in at most while the list lasts (the rebuild test).
float gNear2;

// Candidate slot j at xj, walked by the group of `members` (none: a padding candidate, never
// kept). It is kept only if this group is the first to reach it: some member of the group is
// close enough and no member of an earlier group is (that group walked every particle close to
// its members and kept it). Its entry's mask names every member close enough, in any group, so
// each pair of a member and a neighbour is listed exactly once. `section`: 0 not kept, 1 the
// front, 2 the back.
uint candidate(uint j, vec3 xj, uint members, uint mark, HemoPairParams pp, float list2, out uint section) {
  uint mask = 0u;
  uint near = 0u;
  for (uint m = 0u; m < M; ++m) {
    const vec3 d = hemo_min_image(gX[m] - xj, pp);
    const float d2 = dot(d, d);
    mask |= d2 < list2 ? 1u << m : 0u;
    near |= d2 < gNear2 ? 1u << m : 0u;
  }
  mask &= gMembers;
  const bool keep = (mask & members) != 0u && (mask & gEarlier) == 0u;
  mask = keep ? mask : 0u;
  gNamed += uvec2((mask & 1u) | (mask & 2u) << 15u, (mask >> 2u & 1u) | (mask & 8u) << 13u);
  // A boundary entry that no member can come within the repulsion's reach of joins the
  // fluid's section, the force pass's loop without the repulsion (it keeps its mark).
  const bool boundary = mark != 0u && (near & mask) != 0u;
  section = keep ? (boundary ? 2u : 1u) : 0u;
  return j | mask << HEMO_CLUSTER_MEMBER_SHIFT | mark;
}

// The texel (of the cluster's, from its first) that holds a section's entry `count`: the
// front fills texels from the list's start, the back from its end down (entry capacity - 1 - k
// holds its k-th entry). Past the capacity the cluster has overflowed (the run stops) and any
// texel of its own will do.
uint frontTexel(uint count, uint lastTexel) { return min(count >> 2u, lastTexel); }
uint backTexel(uint count, uint lastTexel) { return lastTexel - min(count >> 2u, lastTexel); }

// The kept entries go to the list a texel at a time. A store is a loop over the SIMD lanes in
// llvmpipe, as costly as the rest of a candidate's work; one per candidate (a store of every
// entry, kept or not, to the next free place) took about a third of the build. Each section
// holds its entries not yet stored (fewer than four); four candidates' kept entries are
// appended to them in order, and a texel that fills is stored. `count` is the section's
// entries so far (gNf or gNb), `pending` its entries not yet stored, in slots [0, count & 3).
// Returns the full texel's entries in its slots [0, 4) when one filled (`full`), and leaves
// the rest in `pending`.
uvec4 append(inout uvec4 pending, inout uint count, uvec4 e, uvec4 section, uint which, out bool full) {
  uvec4 lo = pending;
  uvec3 hi = uvec3(0u);
  uint at = count & 3u;
  // candidate k lands in slot at + (the kept ones before it): at most 3 + k
  for (uint k = 0u; k < 4u; ++k) {
    const bool take = section[k] == which;
    lo.x = take && at == 0u ? e[k] : lo.x;
    lo.y = take && at == 1u ? e[k] : lo.y;
    lo.z = take && at == 2u ? e[k] : lo.z;
    lo.w = take && at == 3u ? e[k] : lo.w;
    if (k >= 1u) hi.x = take && at == 4u ? e[k] : hi.x;
    if (k >= 2u) hi.y = take && at == 5u ? e[k] : hi.y;
    if (k >= 3u) hi.z = take && at == 6u ? e[k] : hi.z;
    at += take ? 1u : 0u;
  }
  full = at >= 4u;
  pending = full ? uvec4(hi, 0u) : lo;
  count += at - (count & 3u);
  return lo;
}

// The members [g0, g1) (one row of cells): walk their candidates and keep each one within the
// list radius of at least one of them and of no member of an earlier row (candidate()).
void group(uint cluster, uint g0, uint g1, HemoPairParams pp, float list2) {
  vec3 lo = gListPoints[g0];
  vec3 hi = gListPoints[g0];
  uint members = 0u;
  for (uint m = 0u; m < M; ++m) {
    const bool inGroup = m >= g0 && m < g1;
    lo = inGroup ? min(lo, gListPoints[m]) : lo;
    hi = inGroup ? max(hi, gListPoints[m]) : hi;
    members |= inGroup ? 1u << m : 0u;
  }
  gListPointMask = members;
  // the rows around the group's box (common/list_ranges.glsl)
  const uint rangeCount = hemo_list_ranges(pc.grid, gC[g0], lo, hi, pc.boundary == 0u, params.listRadius);
  // The candidates as one flat loop (sph/build_list.comp).
  const uint base = cluster * (pc.capacity >> 2u);  // in texels
  const uint lastTexel = (pc.capacity >> 2u) - 1u;
  uint next = 0u;
  uint j = 0u;
  uint jEnd = 0u;
  uint mark = 0u;
  for (;;) {
    if (j == jEnd) {
      if (next == rangeCount) {
        break;
      }
      const uvec2 r = gRanges[next];
      ++next;
      j = r.x;
      jEnd = r.y & ~HEMO_LIST_BOUNDARY_BIT;
      mark = r.y & HEMO_LIST_BOUNDARY_BIT;
    }
    // up to four candidates of the range, their positions fetched together (llvmpipe's
    // fetches are calls that spill the live registers: one run of calls instead of four)
    const uint count = min(jEnd - j, 4u);
    const uint j3 = j + count - 1u;
    const vec3 x0 = texelFetch(positions, int(j)).xyz;
    const vec3 x1 = texelFetch(positions, int(min(j + 1u, j3))).xyz;
    const vec3 x2 = texelFetch(positions, int(min(j + 2u, j3))).xyz;
    const vec3 x3 = texelFetch(positions, int(j3)).xyz;
    uvec4 e, section;
    e.x = candidate(j, x0, members, mark, pp, list2, section.x);
    e.y = candidate(j + 1u, x1, count > 1u ? members : 0u, mark, pp, list2, section.y);
    e.z = candidate(j + 2u, x2, count > 2u ? members : 0u, mark, pp, list2, section.z);
    e.w = candidate(j + 3u, x3, count > 3u ? members : 0u, mark, pp, list2, section.w);
    j += count;
    const uint texelF = frontTexel(gNf, lastTexel);
    const uint texelB = backTexel(gNb, lastTexel);
    bool fullF, fullB;
    const uvec4 front = append(gPendingF, gNf, e, section, 1u, fullF);
    const uvec4 back = append(gPendingB, gNb, e, section, 2u, fullB);
    if (fullF) {
      clusterList[base + texelF] = front;
    }
    if (fullB) {
      clusterList[base + texelB] = back.wzyx;
    }
  }
}

void main() {
  if (hemo_global_index() == 0u && pc.boundary == 0u) {
    activeArgs = uvec4(0u, 1u, 1u, 0u);  // the boundary-pressure pass's active list, filled after the build
  }
  const uint cluster = pc.base + hemo_global_index();
  const uint first = pc.first + hemo_global_index() * M;
  if (first >= pc.end) {
    return;
  }
  const uint count = min(M, pc.end - first);
  const HemoPairParams pp = hemo_pair_params();
  const float list2 = params.listRadius * params.listRadius;
  const float near = hemo_repulsion_reach(params.repulsionCutoff, params.wallSpacing) +
                     (params.listRadius - params.supportRadius);
  gNear2 = near * near;
  const vec3 dimsF = vec3(pc.grid.dimsN.xyz);
  for (uint m = 0u; m < M; ++m) {
    // a missing member repeats the last one (same cells, never in a mask)
    const vec3 x = texelFetch(positions, int(first + min(m, count - 1u))).xyz;
    bool outside;
    gC[m] = hemo_cell_coords(x, pc.grid, outside);
    vec3 u = (x - pc.grid.origin.xyz) * pc.grid.invCell.xyz;
    u = mix(u, u - dimsF * floor(u / dimsF), notEqual(pc.grid.periodic.xyz, uvec3(0u)));
    // clamped into the grid like the cell, so a member outside it stays in its cell's box
    gListPoints[m] = clamp(u, vec3(gC[m]), vec3(gC[m]) + 0.999999);
    gX[m] = x;
  }
  gNf = 0u;
  gNb = 0u;
  gPendingF = uvec4(0u);
  gPendingB = uvec4(0u);
  gNamed = uvec2(0u);
  gMembers = (1u << count) - 1u;
  gEarlier = 0u;
  // The members' rows, in order: [g0, g1) share (cell y, cell z).
  uint g0 = 0u;
  while (g0 < count) {
    uint g1 = g0 + 1u;
    while (g1 < count && gC[g1].yz == gC[g0].yz) {
      ++g1;
    }
    group(cluster, g0, g1, pp, list2);
    gEarlier |= (1u << g1) - (1u << g0);
    g0 = g1;
  }
  // Neighbours of the most crowded member (a fluid member not counting itself). The capacity holds every
  // member's neighbours even when each member walks alone (HEMO_CLUSTER_SIZE rows), so the
  // cluster overflows only when a member has more than the particles' capacity, as a
  // per-particle list would; the run then stops (status).
  const uint self = 1u - pc.boundary;
  uint most = 0u;
  for (uint m = 0u; m < M; ++m) {
    const uint named = (gNamed[m >> 1u] >> (16u * (m & 1u))) & 0xffffu;
    most = max(most, max(named, self) - self);
  }
  // The sections' last texels, partly filled (their other entries are never read).
  const uint base = cluster * (pc.capacity >> 2u);
  const uint lastTexel = (pc.capacity >> 2u) - 1u;
  if ((gNf & 3u) != 0u) {
    clusterList[base + frontTexel(gNf, lastTexel)] = gPendingF;
  }
  if ((gNb & 3u) != 0u) {
    clusterList[base + backTexel(gNb, lastTexel)] = gPendingB.wzyx;
  }
  // The sections' texels must not meet.
  const uint used = ((gNf + 3u) & ~3u) + ((gNb + 3u) & ~3u);
  const bool overflow = used > pc.capacity || most > params.neighbourCapacity;
  clusterCount[cluster] = overflow ? 0u : (gNf | gNb << 16u);
  if (overflow) {
    atomicAdd(status[HEMO_STATUS_NEIGHBOUR_OVERFLOW], 1u);
  }
  // One atomic per SIMD group on the shared word rather than one per invocation (on lavapipe
  // the build measured the same either way).
  const uint groupMost = subgroupMax(most);
  if (subgroupElect()) {
    atomicMax(status[HEMO_STATUS_MAX_NEIGHBOURS], groupMost);
  }
}
