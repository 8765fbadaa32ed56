#version 450
// The clusters' lists (interface/sph.h, "Clusters"): for each cluster of HEMO_CLUSTER_SIZE
// consecutive fluid slots, every particle closer than the list radius to at least one member,
// with the mask of the members it is that close to. One invocation per cluster. Its members
// are grouped by row of grid cells (the slots are in cell order, so a row's members are
// consecutive); each group walks the cells within the list radius of its members' box, as
// sph/build_list.comp does for one particle, and tests every candidate against its members.
#extension GL_GOOGLE_include_directive : require
#include "interface/sph.h"
#include "common/index.glsl"
#include "common/grid.glsl"
#include "common/sph_params.glsl"

layout(binding = HEMO_CBUILD_BINDING_POSITIONS) uniform samplerBuffer positions;
layout(binding = HEMO_CBUILD_BINDING_CELL_START) uniform usamplerBuffer cellStart;
HEMO_SPH_PARAMS_UNIFORM(HEMO_CBUILD_BINDING_PARAMS);
layout(std430, binding = HEMO_CBUILD_BINDING_CCOUNT) writeonly buffer Counts { uint clusterCount[]; };
layout(std430, binding = HEMO_CBUILD_BINDING_CLIST) writeonly buffer List { uint clusterList[]; };
layout(std430, binding = HEMO_CBUILD_BINDING_STATUS) buffer Status { uint status[]; };
layout(push_constant) uniform Push {
  HemoGrid grid;
  uint fluid;     // fluid slots: [0, fluid)
  uint capacity;  // entries per cluster
} pc;

const uint M = HEMO_CLUSTER_SIZE;

// Distance in cell units from the interval [a, b] to cell k along one axis; on a bounded axis
// the first and last cells reach to infinity (particles outside the grid are clamped into them).
float hemo_cell_gap(int k, float a, float b, uint dim, uint periodic) {
  float lo = float(k);
  float hi = float(k + 1);
  if (periodic == 0u) {
    lo = k <= 0 ? -3.0e38 : lo;
    hi = k >= int(dim) - 1 ? 3.0e38 : hi;
  }
  return max(0.0, max(lo - b, a - hi));
}

vec3 gX[M];    // members' positions
vec3 gU[M];    // members' positions in cell units, in the period of their cells
ivec3 gC[M];   // members' cells
uint gNf, gNb; // entries kept: fluid from the front, boundary from the back
uint gNamed[M]; // entries naming each member (itself included)

// The members [g0, g1) (one row of cells): walk their candidates and keep each one within the
// list radius of at least one of them, with that mask.
void group(uint cluster, uint g0, uint g1, HemoPairParams pp, float list2) {
  const uvec3 dims = pc.grid.dimsN.xyz;
  const uint cellCount = dims.x * dims.y * dims.z;
  const ivec3 c = gC[g0];
  vec3 lo = gU[g0];
  vec3 hi = gU[g0];
  uint members = 0u;
  for (uint m = 0u; m < M; ++m) {
    const bool inGroup = m >= g0 && m < g1;
    lo = inGroup ? min(lo, gU[m]) : lo;
    hi = inGroup ? max(hi, gU[m]) : hi;
    members |= inGroup ? 1u << m : 0u;
  }
  const vec3 cellM = 1.0 / pc.grid.invCell.xyz;
  const int hiX = int(dims.x) - 1;
  const int reachX = int(ceil(params.listRadius * pc.grid.invCell.x));
  const int cxLo = int(floor(lo.x));
  const int cxHi = int(floor(hi.x));
  const float trim2 = list2 * 1.0001;
  uvec2 ranges[100];
  uint rangeCount = 0u;
  for (int dz = -2; dz <= 2; ++dz) {
    const float gz = hemo_cell_gap(c.z + dz, lo.z, hi.z, dims.z, pc.grid.periodic.z) * cellM.z;
    const int z = hemo_grid_step(c.z, dz, dims.z, pc.grid.periodic.z);
    if (z < 0 || gz * gz >= trim2) {
      continue;
    }
    int yLo = c.y - 2;
    int yHi = c.y + 2;
    if (pc.grid.periodic.y != 0u && (yLo < 0 || yHi >= int(dims.y))) {
      yLo = 0;
      yHi = int(dims.y) - 1;
    }
    yLo = clamp(yLo, 0, int(dims.y) - 1);
    yHi = clamp(yHi, 0, int(dims.y) - 1);
    const uint planeFirst = hemo_cell_linear(ivec3(0, yLo, z), dims);
    const uint planeLast = hemo_cell_linear(ivec3(hiX, yHi, z), dims);
    // the boundary part is walked only where the plane's rows hold some of it
    const bool occupied = texelFetch(cellStart, int(cellCount + planeFirst)).x !=
                          texelFetch(cellStart, int(cellCount + planeLast + 1u)).x;
    const uint parts = occupied ? 2u : 1u;
    for (int dy = -2; dy <= 2; ++dy) {
      const float gy = hemo_cell_gap(c.y + dy, lo.y, hi.y, dims.y, pc.grid.periodic.y) * cellM.y;
      const float rest2 = trim2 - gy * gy - gz * gz;
      const int y = hemo_grid_step(c.y, dy, dims.y, pc.grid.periodic.y);
      if (y < 0 || rest2 <= 0.0) {
        continue;
      }
      const float reach = sqrt(rest2) * pc.grid.invCell.x;
      int xLo = int(floor(lo.x - reach));
      int xHi = int(floor(hi.x + reach));
      if (pc.grid.periodic.x == 0u) {
        xLo = clamp(xLo, 0, hiX);
        xHi = clamp(xHi, 0, hiX);
      }
      xLo = max(xLo, cxLo - reachX);
      xHi = min(xHi, min(cxHi + reachX, xLo + hiX));  // never a cell twice round a periodic x axis
      ivec2 xr[2];
      xr[0] = ivec2(max(xLo, 0), min(xHi, hiX));
      xr[1] = xLo < 0 ? ivec2(xLo + int(dims.x), hiX) : ivec2(0, xHi - int(dims.x));
      const int segments = pc.grid.periodic.x != 0u ? 2 : 1;
      for (int s = 0; s < segments; ++s) {
        if (xr[s].x > xr[s].y) {
          continue;
        }
        const uint first = hemo_cell_linear(ivec3(xr[s].x, y, z), dims);
        const uint last = hemo_cell_linear(ivec3(xr[s].y, y, z), dims);
        for (uint part = 0u; part < parts; ++part) {
          const uint base = part * cellCount;
          const uint jBegin = texelFetch(cellStart, int(base + first)).x;
          const uint jEnd = texelFetch(cellStart, int(base + last + 1u)).x;
          if (jBegin < jEnd) {
            ranges[rangeCount] = uvec2(jBegin, jEnd | (part == 0u ? 0u : HEMO_LIST_BOUNDARY_BIT));
            ++rangeCount;
          }
        }
      }
    }
  }
  // The candidates as one flat loop (sph/build_list.comp). Each is written to the next free
  // entry of its end and kept (the end advances) only if some member is close enough.
  const uint base = cluster * pc.capacity;
  const uint last = pc.capacity - 1u;
  uint next = 0u;
  uint j = 0u;
  uint jEnd = 0u;
  uint mark = 0u;
  for (;;) {
    if (j == jEnd) {
      if (next == rangeCount) {
        break;
      }
      const uvec2 r = ranges[next];
      ++next;
      j = r.x;
      jEnd = r.y & ~HEMO_LIST_BOUNDARY_BIT;
      mark = r.y & HEMO_LIST_BOUNDARY_BIT;
    }
    const vec3 xj = texelFetch(positions, int(j)).xyz;
    uint mask = 0u;
    for (uint m = 0u; m < M; ++m) {
      const vec3 d = hemo_min_image(gX[m] - xj, pp);
      mask |= dot(d, d) < list2 ? 1u << m : 0u;
    }
    mask &= members;
    for (uint m = 0u; m < M; ++m) {
      gNamed[m] += (mask >> m) & 1u;
    }
    const bool boundary = mark != 0u;
    const uint used = gNf + gNb;
    const uint at = used >= last ? (boundary ? 0u : last) : (boundary ? last - gNb : gNf);
    clusterList[base + at] = j | mask << HEMO_CLUSTER_MEMBER_SHIFT | mark;
    gNf += mask != 0u && !boundary ? 1u : 0u;
    gNb += mask != 0u && boundary ? 1u : 0u;
    ++j;
  }
}

void main() {
  const uint cluster = hemo_global_index();
  const uint first = cluster * M;
  if (first >= pc.fluid) {
    return;
  }
  const uint count = min(M, pc.fluid - first);
  const HemoPairParams pp = hemo_pair_params();
  const float list2 = params.listRadius * params.listRadius;
  const vec3 dimsF = vec3(pc.grid.dimsN.xyz);
  for (uint m = 0u; m < M; ++m) {
    // a missing member repeats the last one (same cells, never in a mask)
    const vec3 x = texelFetch(positions, int(first + min(m, count - 1u))).xyz;
    bool outside;
    gC[m] = hemo_cell_coords(x, pc.grid, outside);
    vec3 u = (x - pc.grid.origin.xyz) * pc.grid.invCell.xyz;
    u = mix(u, u - dimsF * floor(u / dimsF), notEqual(pc.grid.periodic.xyz, uvec3(0u)));
    // clamped into the grid like the cell, so a member outside it stays in its cell's box
    gU[m] = clamp(u, vec3(gC[m]), vec3(gC[m]) + 0.999999);
    gX[m] = x;
    gNamed[m] = 0u;
  }
  gNf = 0u;
  gNb = 0u;
  // The members' rows, in order: [g0, g1) share (cell y, cell z).
  uint g0 = 0u;
  while (g0 < count) {
    uint g1 = g0 + 1u;
    while (g1 < count && gC[g1].yz == gC[g0].yz) {
      ++g1;
    }
    group(cluster, g0, g1, pp, list2);
    g0 = g1;
  }
  // Neighbours of the most crowded member (itself not counted). The capacity holds every
  // member's neighbours even when each member walks alone (HEMO_CLUSTER_SIZE rows), so the
  // cluster overflows only when a member has more than the particles' capacity, as a
  // per-particle list would; the run then stops (status).
  uint most = 0u;
  for (uint m = 0u; m < M; ++m) {
    most = max(most, max(gNamed[m], 1u) - 1u);
  }
  const uint used = gNf + gNb;
  const bool overflow = used > pc.capacity - 1u || most > params.neighbourCapacity;
  clusterCount[cluster] = overflow ? 0u : (gNf | gNb << 16u);
  if (overflow) {
    atomicAdd(status[HEMO_STATUS_NEIGHBOUR_OVERFLOW], 1u);
  }
  atomicMax(status[HEMO_STATUS_MAX_NEIGHBOURS], most);
}
