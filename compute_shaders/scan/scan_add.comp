#version 450
// Exclusive prefix sum, step 2 of 2: adds the scanned offset of each block to its elements.
#extension GL_GOOGLE_include_directive : require
#include "interface/scan.h"
#include "common/index.glsl"

layout(std430, binding = HEMO_SCAN_BINDING_DATA) buffer Data { uint data[]; };
layout(std430, binding = HEMO_SCAN_BINDING_SUMS) readonly buffer Sums { uint sums[]; };
layout(push_constant) uniform Push { uint n; } pc;

void main() {
  const uint block = hemo_group_index();
  const uint base = (block * gl_WorkGroupSize.x + gl_LocalInvocationID.x) * HEMO_SCAN_ITEMS;
  if (block == 0u || base >= pc.n) {
    return;  // block 0 has offset 0; no barrier in this shader
  }
  const uint offset = sums[block];
  for (uint k = 0u; k < HEMO_SCAN_ITEMS; ++k) {
    const uint idx = base + k;
    if (idx < pc.n) {
      data[idx] += offset;
    }
  }
}
