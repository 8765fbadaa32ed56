#version 450
// Neighbour grid, step 3 of the counting sort (interface/grid.h): cellStart[c] = local[c] +
// the offset of c's block, for every entry (empty cells carry the running offset, and the
// last entry is the particle count); and every particle's (key, slot) to its key's start
// plus its rank. Each entry and each target slot has exactly one writer. The counts go back
// to zero for the next build's hash (grid/cell_scan.comp has read them). Within a key the
// order is the ranks' (scheduling) order until grid/reorder.comp sorts it by slot.
// Invocation i writes the entries 4i .. 4i + 3 as one texel (grid/cell_scan.comp says why)
// and places particle i. In the texel that holds the last scanned entry, the entries past it
// keep their values: in a partial build they are part 1's, which that build leaves alone.
#extension GL_GOOGLE_include_directive : require
#include "interface/grid.h"
#include "interface/scan.h"
#include "common/index.glsl"

layout(binding = HEMO_SCATTER_BINDING_PAIRS) uniform usamplerBuffer pairs;  // (key, rank)
layout(binding = HEMO_SCATTER_BINDING_LOCAL) uniform usamplerBuffer local;  // four entries a texel
layout(binding = HEMO_SCATTER_BINDING_BLOCKS) uniform usamplerBuffer blocks;
// the same buffer as cellStart below, four entries a texel (each texel is read only by the
// invocation that writes it)
layout(binding = HEMO_SCATTER_BINDING_CELL_START_IN) uniform usamplerBuffer cellStartIn;
layout(std430, binding = HEMO_SCATTER_BINDING_CELL_START) writeonly buffer CellStart { uvec4 cellStart[]; };
layout(std430, binding = HEMO_SCATTER_BINDING_ORDER) writeonly buffer Order { uvec2 order[]; };
layout(std430, binding = HEMO_SCATTER_BINDING_KEY_COUNTS) writeonly buffer KeyCounts { uvec4 keyCounts[]; };
layout(push_constant) uniform Push {
  uint n;
  uint keys;       // cellStart entries (key count + 1)
  uint blockSize;  // keys per block of grid/cell_scan.comp (a multiple of 4)
} pc;

void main() {
  const uint i = hemo_global_index();
  const uint key = 4u * i;
  if (key < pc.keys) {
    // the four entries share a block
    const uvec4 start = texelFetch(local, int(i)) + texelFetch(blocks, int(key / pc.blockSize)).x;
    const bvec4 scanned = lessThan(uvec4(key) + uvec4(0u, 1u, 2u, 3u), uvec4(pc.keys));
    cellStart[i] = mix(texelFetch(cellStartIn, int(i)), start, scanned);
    keyCounts[i] = uvec4(0u);  // (past the scanned entries they are zero already)
  }
  if (i < pc.n) {
    const uvec2 kr = texelFetch(pairs, int(i)).xy;
    const uint start = texelFetch(local, int(kr.x >> 2u))[kr.x & 3u] + texelFetch(blocks, int(kr.x / pc.blockSize)).x;
    order[start + kr.y] = uvec2(kr.x, i);
  }
}
