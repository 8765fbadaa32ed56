#version 450
// Neighbour grid, step 1: the cell of every particle as a (cell, slot) pair for the sort.
// Particles outside the grid are clamped into the border cells and counted (on periodic
// axes they wrap instead); a particle with a non-finite coordinate goes to cell 0 and is
// counted separately so the caller can stop.
#extension GL_GOOGLE_include_directive : require
#include "interface/grid.h"
#include "common/index.glsl"
#include "common/grid.glsl"

layout(binding = HEMO_HASH_BINDING_POSITIONS) uniform samplerBuffer positions;  // a texel slot
layout(std430, binding = HEMO_HASH_BINDING_PAIRS) writeonly buffer Pairs { uvec2 pairs[]; };
layout(std430, binding = HEMO_HASH_BINDING_COUNTERS) buffer Counters { uint counters[]; };
layout(push_constant) uniform Push { HemoGrid grid; } pc;

void main() {
  const uint i = hemo_global_index();
  if (i >= pc.grid.dimsN.w) {
    return;
  }
  const vec3 p = texelFetch(positions, int(i)).xyz;
  uint cell = 0u;
  if (any(isnan(p)) || any(isinf(p))) {
    atomicAdd(counters[HEMO_COUNTER_NONFINITE], 1u);
  } else {
    bool outside;
    const ivec3 c = hemo_cell_coords(p, pc.grid, outside);
    cell = hemo_cell_linear(c, pc.grid.dimsN.xyz);
    if (outside) {
      atomicAdd(counters[HEMO_COUNTER_OUTSIDE], 1u);
    }
  }
  pairs[i] = uvec2(cell, i);
}
