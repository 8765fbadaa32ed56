#version 450
// Neighbour grid, step 2 of the counting sort (interface/grid.h): the exclusive scan of the
// per-key counts, in one dispatch. Each workgroup scans its block of keys (offsets within the
// block to `local`) and stores the block's total; the last workgroup to finish turns the
// totals into block offsets (a sequential pass: a grid has a few blocks per thousand
// particles). cellStart = local + the block's offset, written by grid/scatter.comp, which
// reads both and sets the counts back to zero for the next build's hash. The counts are read
// as texels (one vector gather on llvmpipe, where a storage buffer is read lane by lane).
#extension GL_GOOGLE_include_directive : require
#extension GL_KHR_shader_subgroup_basic : require
#extension GL_KHR_shader_subgroup_arithmetic : require
#include "interface/grid.h"
#include "interface/scan.h"
#include "common/index.glsl"
#include "common/workgroup_scan.glsl"

layout(binding = HEMO_CELL_SCAN_BINDING_KEY_COUNTS) uniform usamplerBuffer keyCounts;
layout(std430, binding = HEMO_CELL_SCAN_BINDING_LOCAL) writeonly buffer Local { uint local[]; };
// Written by every workgroup, read by the last: coherent, and published before the count.
layout(std430, binding = HEMO_CELL_SCAN_BINDING_BLOCKS) coherent buffer Blocks { uint blocks[]; };
layout(std430, binding = HEMO_CELL_SCAN_BINDING_FINISHED) coherent buffer Finished { uint finished; };
layout(push_constant) uniform Push { uint keys; } pc;  // entries to scan (key count + 1)

shared bool s_last;

void main() {
  const uint block = hemo_group_index();
  const uint blockSize = gl_WorkGroupSize.x * HEMO_SCAN_ITEMS;
  const uint blockCount = (pc.keys + blockSize - 1u) / blockSize;
  const uint base = block * blockSize + gl_LocalInvocationID.x * HEMO_SCAN_ITEMS;
  uint items[HEMO_SCAN_ITEMS];
  uint total = 0u;
  for (uint k = 0u; k < HEMO_SCAN_ITEMS; ++k) {
    const uint idx = base + k;
    items[k] = idx < pc.keys ? texelFetch(keyCounts, int(idx)).x : 0u;
    total += items[k];
  }
  uint blockTotal;
  uint running = hemo_workgroup_exclusive_scan(total, blockTotal);
  for (uint k = 0u; k < HEMO_SCAN_ITEMS; ++k) {
    const uint idx = base + k;
    if (idx < pc.keys) {
      local[idx] = running;
    }
    running += items[k];
  }
  if (gl_LocalInvocationID.x == 0u) {
    if (block < blockCount) {
      blocks[block] = blockTotal;
    }
    memoryBarrierBuffer();  // the total is visible before the count says so
    const uint groups = gl_NumWorkGroups.x * gl_NumWorkGroups.y * gl_NumWorkGroups.z;
    s_last = atomicAdd(finished, 1u) == groups - 1u;
  }
  barrier();
  if (!s_last || gl_LocalInvocationID.x != 0u) {
    return;
  }
  memoryBarrierBuffer();
  uint offset = 0u;
  for (uint b = 0u; b < blockCount; ++b) {
    const uint t = blocks[b];
    blocks[b] = offset;
    offset += t;
  }
  finished = 0u;  // every other workgroup has counted itself: ready for the next build
}
