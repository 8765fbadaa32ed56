#version 450
// Neighbour grid, step 3 of the counting sort (interface/grid.h): cellStart[c] = local[c] +
// the offset of c's block, for every entry (empty cells carry the running offset, and the
// last entry is the particle count); and every particle's (key, slot) to its key's start
// plus its rank. Each entry and each target slot has exactly one writer. The counts go back
// to zero for the next build's hash (grid/cell_scan.comp has read them). Within a key the
// order is the ranks' (scheduling) order until grid/reorder.comp sorts it by slot.
#extension GL_GOOGLE_include_directive : require
#include "interface/grid.h"
#include "interface/scan.h"
#include "common/index.glsl"

layout(binding = HEMO_SCATTER_BINDING_PAIRS) uniform usamplerBuffer pairs;  // (key, rank)
layout(binding = HEMO_SCATTER_BINDING_LOCAL) uniform usamplerBuffer local;
layout(binding = HEMO_SCATTER_BINDING_BLOCKS) uniform usamplerBuffer blocks;
layout(std430, binding = HEMO_SCATTER_BINDING_CELL_START) writeonly buffer CellStart { uint cellStart[]; };
layout(std430, binding = HEMO_SCATTER_BINDING_ORDER) writeonly buffer Order { uvec2 order[]; };
layout(std430, binding = HEMO_SCATTER_BINDING_KEY_COUNTS) writeonly buffer KeyCounts { uint keyCounts[]; };
layout(push_constant) uniform Push {
  uint n;
  uint keys;       // cellStart entries (key count + 1)
  uint blockSize;  // keys per block of grid/cell_scan.comp
} pc;

uint hemo_key_start(uint key) {
  return texelFetch(local, int(key)).x + texelFetch(blocks, int(key / pc.blockSize)).x;
}

void main() {
  const uint i = hemo_global_index();
  if (i < pc.keys) {
    cellStart[i] = hemo_key_start(i);
    keyCounts[i] = 0u;
  }
  if (i < pc.n) {
    const uvec2 kr = texelFetch(pairs, int(i)).xy;
    order[hemo_key_start(kr.x) + kr.y] = uvec2(kr.x, i);
  }
}
