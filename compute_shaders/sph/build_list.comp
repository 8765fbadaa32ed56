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
#extension GL_KHR_shader_subgroup_basic : require
#extension GL_KHR_shader_subgroup_arithmetic : require
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
  uint first;  // the slots [first, end) get lists (with clusters, the fluid's are the clusters'),
  uint end;    // all in one page of the list
} pc;

#include "common/list_ranges.glsl"

void main() {
  const uint i = pc.first + hemo_global_index();
  if (hemo_global_index() == 0u) {
    activeArgs = uvec4(0u, 1u, 1u, 0u);  // boundary_pressure.comp's active list, filled after this pass
  }
  if (i >= pc.end) {
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
  // The rows around the particle's cell (common/list_ranges.glsl), with the particle's
  // position in cell units, in the same period as its cell on periodic axes.
  bool outside;
  const ivec3 c = hemo_cell_coords(xi, pc.grid, outside);
  vec3 u = (xi - pc.grid.origin.xyz) * pc.grid.invCell.xyz;
  const vec3 dimsF = vec3(pc.grid.dimsN.xyz);
  u = mix(u, u - dimsF * floor(u / dimsF), notEqual(pc.grid.periodic.xyz, uvec3(0u)));
  // (a parked slot lists nothing: interface/sph.h, HEMO_KIND_PARKED)
  const uint rangeCount =
      uint(xi4.w) == HEMO_KIND_PARKED ? 0u : hemo_list_ranges(pc.grid, c, u, u, fluidI, params.listRadius);
  // The candidates: every slot of the ranges in order, as one flat loop. A loop per range
  // ran, per SIMD group, each range as long as its longest lane's; this one runs as long as
  // the group's largest total.
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
      const uvec2 r = gRanges[next];
      ++next;
      j = r.x;
      jEnd = r.y & ~HEMO_LIST_BOUNDARY_BIT;
      mark = r.y & HEMO_LIST_BOUNDARY_BIT;
    }
    const vec3 d = hemo_min_image(xi - texelFetch(positions, int(j)).xyz, pp);
    // Every candidate is written to the next free slot, and the slot is kept (count
    // advances) only if the candidate is a neighbour: a store under a data-dependent
    // condition cost llvmpipe more than the candidate test itself (dam break: list
    // build 20 -> 14 ms, docs/benchmarks.md). A full list takes no more writes: a
    // further neighbour overflows it, which stops the run at the end of the batch (status),
    // and any other candidate must not take the last neighbour's slot.
    if (count < capacity) {
      neighbourList[hemo_list_slot(i, count, pp)] = j | mark;
    }
    if (j != i && dot(d, d) < list2) {
      ++count;
    }
    ++j;
  }
  neighbourCount[i] = min(count, capacity);
  if (count > capacity) {
    atomicAdd(status[HEMO_STATUS_NEIGHBOUR_OVERFLOW], 1u);
  }
  // One atomic per SIMD group on the shared word rather than one per invocation (on lavapipe
  // the build measured the same either way).
  const uint groupMost = subgroupMax(count);
  if (subgroupElect()) {
    atomicMax(status[HEMO_STATUS_MAX_NEIGHBOURS], groupMost);
  }
}
