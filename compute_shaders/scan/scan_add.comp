#version 450
// Exclusive prefix sum, step 2 of 2: adds the scanned offset of each block to its elements.
#extension GL_GOOGLE_include_directive : require
#include "interface/scan.h"
#include "common/index.glsl"

layout(std430, binding = HEMO_SCAN_BINDING_DATA) buffer Data { uint data[]; };
layout(std430, binding = HEMO_SCAN_BINDING_SUMS) readonly buffer Sums { uint sums[]; };
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
  if (block == 0u || base >= n) {
    return;  // block 0 has offset 0; no barrier in this shader
  }
  const uint offset = sums[block];
  for (uint k = 0u; k < HEMO_SCAN_ITEMS; ++k) {
    const uint idx = base + k;
    if (idx < n) {
      data[idx] += offset;
    }
  }
}
