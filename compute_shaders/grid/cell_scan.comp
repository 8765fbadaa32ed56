#version 450
// Neighbour grid, step 2 of the counting sort (interface/grid.h): the exclusive scan of the
// per-key counts, in one dispatch. Each workgroup scans its block of keys (offsets within the
// block to `local`) and stores the block's total; the last workgroup to finish turns the
// totals into block offsets (a sequential pass: a grid has a few blocks per thousand
// particles). cellStart = local + the block's offset, written by grid/scatter.comp, which
// reads both and sets the counts back to zero for the next build's hash.
// An invocation's HEMO_SCAN_ITEMS keys are read and written four at a time, as uvec4 texels
// and stores: llvmpipe loops over the lanes for each load (as a texel, one vector gather) and
// each store, and a grid has several keys per particle (the dam break: 6.7), so the scan's
// cost was in those loops. The buffers hold whole texels.
#extension GL_GOOGLE_include_directive : require
#extension GL_KHR_shader_subgroup_basic : require
#extension GL_KHR_shader_subgroup_arithmetic : require
#include "interface/grid.h"
#include "interface/scan.h"
#include "common/index.glsl"
#include "common/workgroup_scan.glsl"

#if (HEMO_SCAN_ITEMS % 4) != 0
#error "the scan reads its items four at a time"
#endif

layout(binding = HEMO_CELL_SCAN_BINDING_KEY_COUNTS) uniform usamplerBuffer keyCounts;  // four keys a texel
layout(std430, binding = HEMO_CELL_SCAN_BINDING_LOCAL) writeonly buffer Local { uvec4 local[]; };
// Written by every workgroup, read by the last: coherent, and published before the count.
layout(std430, binding = HEMO_CELL_SCAN_BINDING_BLOCKS) coherent buffer Blocks { uint blocks[]; };
layout(std430, binding = HEMO_CELL_SCAN_BINDING_FINISHED) coherent buffer Finished { uint finished; };
layout(push_constant) uniform Push { uint keys; } pc;  // entries to scan (key count + 1)

shared bool s_last;

const uint kTexels = HEMO_SCAN_ITEMS / 4u;

void main() {
  const uint block = hemo_group_index();
  const uint blockSize = gl_WorkGroupSize.x * HEMO_SCAN_ITEMS;
  const uint blockCount = (pc.keys + blockSize - 1u) / blockSize;
  const uint base = block * blockSize + gl_LocalInvocationID.x * HEMO_SCAN_ITEMS;  // a multiple of 4
  uvec4 items[kTexels];
  uint total = 0u;
  for (uint t = 0u; t < kTexels; ++t) {
    const uint key = base + 4u * t;
    const uvec4 c = key < pc.keys ? texelFetch(keyCounts, int(key >> 2u)) : uvec4(0u);
    // the entries past the scanned ones count nothing (in a partial build they are part 1's)
    items[t] = mix(uvec4(0u), c, lessThan(uvec4(key) + uvec4(0u, 1u, 2u, 3u), uvec4(pc.keys)));
    total += items[t].x + items[t].y + items[t].z + items[t].w;
  }
  uint blockTotal;
  uint running = hemo_workgroup_exclusive_scan(total, blockTotal);
  for (uint t = 0u; t < kTexels; ++t) {
    const uint key = base + 4u * t;
    const uvec4 c = items[t];
    if (key < pc.keys) {
      local[key >> 2u] = uvec4(running, running + c.x, running + c.x + c.y, running + c.x + c.y + c.z);
    }
    running += c.x + c.y + c.z + c.w;
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
