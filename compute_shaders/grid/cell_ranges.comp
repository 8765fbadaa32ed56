#version 450
// Neighbour grid, step 3 (after the sort): cellStart from the sorted cell keys, without
// atomics. Invocation i (0 <= i <= n) writes cellStart[c] = i for every cell c in
// (key[i-1], key[i]], taking key[-1] = -1 and key[n] = cellCount. Every entry of
// cellStart[0 .. cellCount] is written exactly once; empty cells get the running offset.
#extension GL_GOOGLE_include_directive : require
#include "interface/grid.h"
#include "common/index.glsl"

layout(binding = HEMO_RANGES_BINDING_PAIRS) uniform usamplerBuffer pairs;  // (cell, slot), a texel slot
layout(std430, binding = HEMO_RANGES_BINDING_CELL_START) writeonly buffer CellStart { uint cellStart[]; };
layout(push_constant) uniform Push { uint n; uint cellCount; } pc;

void main() {
  const uint i = hemo_global_index();
  if (i > pc.n) {
    return;
  }
  const uint first = i == 0u ? 0u : texelFetch(pairs, int(i) - 1).x + 1u;
  const uint last = i == pc.n ? pc.cellCount : texelFetch(pairs, int(i)).x;
  for (uint c = first; c <= last; ++c) {
    cellStart[c] = i;
  }
}
