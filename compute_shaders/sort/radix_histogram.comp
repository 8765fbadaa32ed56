#version 450
// Radix sort pass, step 1 of 3: each invocation counts the digits of its chunk of pairs.
// Step 2 is an exclusive scan of the bucket-major counts; step 3 is radix_scatter.comp.
#extension GL_GOOGLE_include_directive : require
#include "interface/sort.h"
#include "common/index.glsl"

layout(binding = HEMO_SORT_BINDING_PAIRS_IN) uniform usamplerBuffer pairsIn;  // uvec2 texels
layout(std430, binding = HEMO_SORT_BINDING_COUNTS) writeonly buffer Counts { uint counts[]; };
layout(push_constant) uniform Push { uint n; uint shift; uint chunkSize; uint chunkCount; uint digitBits; } pc;

void main() {
  const uint chunk = hemo_global_index();
  if (chunk >= pc.chunkCount) {
    return;
  }
  const uint buckets = 1u << pc.digitBits;  // digitBits <= HEMO_RADIX_BITS
  const uint mask = buckets - 1u;
  uint histogram[HEMO_RADIX_BUCKETS];
  for (uint b = 0u; b < buckets; ++b) {
    histogram[b] = 0u;
  }
  const uint first = chunk * pc.chunkSize;
  const uint last = min(first + pc.chunkSize, pc.n);
  for (uint i = first; i < last; ++i) {
    histogram[(texelFetch(pairsIn, int(i)).x >> pc.shift) & mask] += 1u;
  }
  for (uint b = 0u; b < buckets; ++b) {
    counts[b * pc.chunkCount + chunk] = histogram[b];
  }
}
