#version 450
// The per-particle neighbour list (a Verlet list): every other particle closer than the list
// radius = support * (1 + skin), as slots of the sorted order (the order only has to be the
// same every build). The skin lets the list serve the following steps until some particle
// has moved half of it (the solver's gate decides on the GPU when to rebuild). The grid has
// two parts (interface/grid.h): the fluid's slots come first, so a SIMD group of this pass
// and of the passes over the list holds one kind. Fluid particles list the neighbours of
// both parts, the fluid's first in each row of cells; boundary particles list only their
// fluid neighbours (all boundary_pressure.comp needs), from the fluid part alone.
#extension GL_GOOGLE_include_directive : require
#include "interface/sph.h"
#include "common/index.glsl"
#include "common/grid.glsl"
#include "common/sph_params.glsl"

// The positions of this build with each particle's kind in w (grid/reorder.comp), so a
// candidate's position and kind come in one load.
// Read-only inputs are uniform texel buffers (interface/sph.h, "texel slots").
layout(binding = HEMO_BUILD_BINDING_POSITIONS) uniform samplerBuffer positions;
layout(binding = HEMO_BUILD_BINDING_CELL_START) uniform usamplerBuffer cellStart;
HEMO_SPH_PARAMS_UNIFORM(HEMO_BUILD_BINDING_PARAMS);
layout(std430, binding = HEMO_BUILD_BINDING_NCOUNT) writeonly buffer Counts { uint neighbourCount[]; };
layout(std430, binding = HEMO_BUILD_BINDING_NLIST) writeonly buffer List { uint neighbourList[]; };
layout(std430, binding = HEMO_BUILD_BINDING_STATUS) buffer Status { uint status[]; };
layout(std430, binding = HEMO_BUILD_BINDING_ACTIVE_ARGS) writeonly buffer ActiveArgs { uvec4 activeArgs; };
layout(push_constant) uniform Push {
  HemoGrid grid;
  uint first;  // the slots [first, n) get lists (with clusters, the fluid's are the clusters')
} pc;

// Distance in cell units from u to cell k along one axis; on a bounded axis the first and
// last cells reach to infinity, as particles outside the grid are clamped into them.
float hemo_cell_gap(int k, float u, uint dim, uint periodic) {
  float lo = float(k);
  float hi = float(k + 1);
  if (periodic == 0u) {
    lo = k <= 0 ? -3.0e38 : lo;
    hi = k >= int(dim) - 1 ? 3.0e38 : hi;
  }
  return max(0.0, max(lo - u, u - hi));
}

void main() {
  const uint i = pc.first + hemo_global_index();
  if (hemo_global_index() == 0u) {
    activeArgs = uvec4(0u, 1u, 1u, 0u);  // boundary_pressure.comp's active list, filled after this pass
  }
  if (i >= pc.grid.dimsN.w) {
    return;
  }
  const vec4 xi4 = texelFetch(positions, int(i));
  const bool fluidI = uint(xi4.w) == HEMO_KIND_FLUID;
  const vec3 xi = xi4.xyz;
  const float list2 = params.listRadius * params.listRadius;
  const uint capacity = params.neighbourCapacity;
  // The minimum image on the periodic axes only (specialization constant, common/sph_params.glsl),
  // as the passes over the list take it.
  const HemoPairParams pp = hemo_pair_params();
  const uvec3 dims = pc.grid.dimsN.xyz;
  const uint cellCount = dims.x * dims.y * dims.z;

  // The grid's cells are at least half the list radius R wide along y and z and narrower
  // along x (sph.cpp, gridFor), so every neighbour lies in the 5 x 5 rows (dz, dy in -2..2)
  // around the particle's cell, each within reachX cells in x. A row is skipped when its
  // nearest point is R or more away in (y, z), and its x-cells are trimmed to those within the
  // remaining reach sqrt(R^2 - gy^2 - gz^2).
  bool outside;
  const ivec3 c = hemo_cell_coords(xi, pc.grid, outside);
  // Position in cell units, in the same period as c on periodic axes.
  vec3 u = (xi - pc.grid.origin.xyz) * pc.grid.invCell.xyz;
  const vec3 dimsF = vec3(dims);
  u = mix(u, u - dimsF * floor(u / dimsF), notEqual(pc.grid.periodic.xyz, uvec3(0u)));
  const vec3 cellM = 1.0 / pc.grid.invCell.xyz;  // cell size per axis, m
  const int hiX = int(dims.x) - 1;
  // The x-cells within the list radius either way of the particle's
  const int reachX = int(ceil(params.listRadius * pc.grid.invCell.x));
  // Cells are trimmed against a slightly larger radius, so rounding never drops a cell that
  // holds a neighbour; the distance test below is exact.
  const float trim2 = list2 * 1.0001;
  // The non-empty ranges of slots to scan, in list order: [x, y) with y carrying
  // HEMO_LIST_BOUNDARY_BIT for the boundary part. At most 5 x 5 rows, two ranges each where a
  // periodic x axis wraps, in each of the two parts.
  uvec2 ranges[100];
  uint rangeCount = 0u;
  for (int dz = -2; dz <= 2; ++dz) {
    const int kz = c.z + dz;
    const float gz = hemo_cell_gap(kz, u.z, dims.z, pc.grid.periodic.z) * cellM.z;
    const int z = hemo_grid_step(c.z, dz, dims.z, pc.grid.periodic.z);
    if (z < 0 || gz * gz >= trim2) {
      continue;
    }
    // The plane's five rows (x fastest, so rows yLo .. yHi of plane z are one block of cells):
    // a part with no particle in the block is skipped in all of them. Boundary particles list
    // fluid only, and most sit far from it (a tank's walls); most fluid particles sit far from
    // any boundary particle. Two texel fetches per plane save two per row and part.
    int yLo = c.y - 2;
    int yHi = c.y + 2;
    if (pc.grid.periodic.y != 0u && (yLo < 0 || yHi >= int(dims.y))) {
      yLo = 0;  // the rows wrap: the whole plane
      yHi = int(dims.y) - 1;
    }
    yLo = clamp(yLo, 0, int(dims.y) - 1);
    yHi = clamp(yHi, 0, int(dims.y) - 1);
    const uint planeFirst = hemo_cell_linear(ivec3(0, yLo, z), dims);
    const uint planeLast = hemo_cell_linear(ivec3(hiX, yHi, z), dims);
    const uint tested = fluidI ? cellCount : 0u;  // fluid: the boundary part; boundary: the fluid part
    const bool occupied = texelFetch(cellStart, int(tested + planeFirst)).x != texelFetch(cellStart, int(tested + planeLast + 1u)).x;
    if (!fluidI && !occupied) {
      continue;
    }
    const uint parts = fluidI && occupied ? 2u : 1u;
    for (int dy = -2; dy <= 2; ++dy) {
      const int ky = c.y + dy;
      const float gy = hemo_cell_gap(ky, u.y, dims.y, pc.grid.periodic.y) * cellM.y;
      const float rest2 = trim2 - gy * gy - gz * gz;
      const int y = hemo_grid_step(c.y, dy, dims.y, pc.grid.periodic.y);
      if (y < 0 || rest2 <= 0.0) {
        continue;
      }
      const float reach = sqrt(rest2) * pc.grid.invCell.x;
      int lo = int(floor(u.x - reach));
      int hi = int(floor(u.x + reach));
      if (pc.grid.periodic.x == 0u) {  // the edge cells hold the particles clamped into them
        lo = clamp(lo, 0, hiX);
        hi = clamp(hi, 0, hiX);
      }
      lo = max(lo, c.x - reachX);
      hi = min(hi, min(c.x + reachX, lo + hiX));  // never a cell twice round a periodic x axis
      // The x-cells [lo, hi] as up to two contiguous ranges on the grid (the second, empty
      // unless a periodic x axis wraps, holds the cells past the seam).
      ivec2 xr[2];
      xr[0] = ivec2(max(lo, 0), min(hi, hiX));
      xr[1] = lo < 0 ? ivec2(lo + int(dims.x), hiX) : ivec2(0, hi - int(dims.x));
      const int segments = pc.grid.periodic.x != 0u ? 2 : 1;
      for (int s = 0; s < segments; ++s) {
        if (xr[s].x > xr[s].y) {
          continue;
        }
        const uint first = hemo_cell_linear(ivec3(xr[s].x, y, z), dims);
        const uint last = hemo_cell_linear(ivec3(xr[s].y, y, z), dims);
        for (uint part = 0u; part < parts; ++part) {
          // part 0: the fluid, plain slots; part 1: boundary and wall particles, marked
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
  // The candidates: every slot of the ranges in order, as one flat loop. A loop per range
  // ran, per SIMD group, each range as long as its longest lane's; this one runs as long as
  // the group's largest total (docs/benchmarks.md, "Session 22").
  uint count = 0u;
  uint next = 0u;  // the next range
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
    const vec3 d = hemo_min_image(xi - texelFetch(positions, int(j)).xyz, pp);
    // Every candidate is written to the next free slot, and the slot is kept (count
    // advances) only if the candidate is a neighbour: a store under a data-dependent
    // condition cost llvmpipe more than the candidate test itself (dam break: list
    // build 20 -> 14 ms, docs/benchmarks.md). Past the capacity the last slot is
    // overwritten; that overflow stops the run at the end of the batch (status).
    neighbourList[hemo_list_slot(i, min(count, capacity - 1u), pp)] = j | mark;
    if (j != i && dot(d, d) < list2) {
      ++count;
    }
    ++j;
  }
  neighbourCount[i] = min(count, capacity);
  if (count > capacity) {
    atomicAdd(status[HEMO_STATUS_NEIGHBOUR_OVERFLOW], 1u);
  }
  atomicMax(status[HEMO_STATUS_MAX_NEIGHBOURS], count);
}
