#version 450
// Exclusive prefix sum, step 1 of 2: each workgroup scans its own block of
// workgroupSize * HEMO_SCAN_ITEMS elements in place and writes the block total to sums[block].
// The host scans `sums` the same way (recursively) and then runs scan_add.comp.
// Within a workgroup: each invocation sums its items sequentially, and
// common/workgroup_scan.glsl combines the invocations.
#extension GL_GOOGLE_include_directive : require
#extension GL_KHR_shader_subgroup_basic : require
#extension GL_KHR_shader_subgroup_arithmetic : require
#include "interface/scan.h"
#include "common/index.glsl"
#include "common/workgroup_scan.glsl"

layout(std430, binding = HEMO_SCAN_BINDING_DATA) buffer Data { uint data[]; };
layout(std430, binding = HEMO_SCAN_BINDING_SUMS) writeonly buffer Sums { uint sums[]; };
layout(std430, binding = HEMO_SCAN_BINDING_LENGTH) readonly buffer Lengths { uint lengths[]; };
layout(push_constant) uniform Push {
  uint n;
  uint lengthIndex;
  uint lengthPlus;
  uint level;
} pc;

// The number of elements this dispatch scans: push n, or the GPU length carried down `level`
// levels of blocks (never more than n, the capacity this dispatch was sized for).
uint hemo_scan_length() {
  if (pc.lengthIndex == HEMO_SCAN_NO_LENGTH) {
    return pc.n;
  }
  const uint block = gl_WorkGroupSize.x * HEMO_SCAN_ITEMS;
  uint len = lengths[pc.lengthIndex] + pc.lengthPlus;
  for (uint k = 0u; k < pc.level; ++k) {
    len = (len + block - 1u) / block;
  }
  return min(len, pc.n);
}

void main() {
  const uint n = hemo_scan_length();
  const uint block = hemo_group_index();
  const uint base = (block * gl_WorkGroupSize.x + gl_LocalInvocationID.x) * HEMO_SCAN_ITEMS;

  uint items[HEMO_SCAN_ITEMS];
  uint total = 0u;
  for (uint k = 0u; k < HEMO_SCAN_ITEMS; ++k) {
    const uint idx = base + k;
    items[k] = idx < n ? data[idx] : 0u;
    total += items[k];
  }

  uint blockTotal;
  uint running = hemo_workgroup_exclusive_scan(total, blockTotal);
  for (uint k = 0u; k < HEMO_SCAN_ITEMS; ++k) {
    const uint idx = base + k;
    if (idx < n) {
      data[idx] = running;
    }
    running += items[k];
  }
  const uint blocks = (n + gl_WorkGroupSize.x * HEMO_SCAN_ITEMS - 1u) / (gl_WorkGroupSize.x * HEMO_SCAN_ITEMS);
  if (gl_LocalInvocationID.x == 0u && block < blocks) {
    sums[block] = blockTotal;
  }
}
