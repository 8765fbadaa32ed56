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
layout(std430, binding = HEMO_CBUILD_BINDING_CLIST) writeonly buffer List { uint clusterList[]; };
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
uint gMembers;  // the cluster's members (a missing member is in no mask)
uint gEarlier;  // the members of the groups walked before this one
// The squared distance within which a boundary neighbour may come into the repulsion's reach
// (common/repulsion.glsl) before the next build: that reach plus the skin, by which a pair
// closes in at most while the list lasts (the rebuild test).
float gNear2;

// Candidate slot j at xj, walked by the group of `members` (none: a padding candidate,
// written where the next entry goes but not kept). It is written to the next free entry of
// its end and kept (the end advances) only if this group is the first to reach it: some member
// of the group is close enough and no member of an earlier group is (that group walked every
// particle close to its members and kept it). Its mask names every member close enough, in
// any group, so each pair of a member and a neighbour is listed exactly once.
void candidate(uint base, uint j, vec3 xj, uint members, uint mark, HemoPairParams pp, float list2) {
  const uint last = pc.capacity - 1u;
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
  // With used == last one entry is free, at gNf = last - gNb; past that the cluster has
  // overflowed (the run stops) and any entry of its own will do.
  const uint used = gNf + gNb;
  const uint at = used > last ? 0u : (boundary ? last - gNb : gNf);
  clusterList[base + at] = j | mask << HEMO_CLUSTER_MEMBER_SHIFT | mark;
  gNf += keep && !boundary ? 1u : 0u;
  gNb += keep && boundary ? 1u : 0u;
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
  const uint base = cluster * pc.capacity;
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
    candidate(base, j, x0, members, mark, pp, list2);
    candidate(base, j + 1u, x1, count > 1u ? members : 0u, mark, pp, list2);
    candidate(base, j + 2u, x2, count > 2u ? members : 0u, mark, pp, list2);
    candidate(base, j + 3u, x3, count > 3u ? members : 0u, mark, pp, list2);
    j += count;
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
  const uint used = gNf + gNb;
  const bool overflow = used > pc.capacity - 1u || most > params.neighbourCapacity;
  clusterCount[cluster] = overflow ? 0u : (gNf | gNb << 16u);
  if (overflow) {
    atomicAdd(status[HEMO_STATUS_NEIGHBOUR_OVERFLOW], 1u);
  }
  // One atomic per SIMD group on the shared word rather than one per invocation (on lavapipe
  // the build measured the same either way; docs/benchmarks.md "Session 30").
  const uint groupMost = subgroupMax(most);
  if (subgroupElect()) {
    atomicMax(status[HEMO_STATUS_MAX_NEIGHBOURS], groupMost);
  }
}
