#version 450
// Radix sort pass, step 3 of 3: each invocation walks its chunk in order and writes every
// pair to offsets[bucket * chunkCount + chunk] + (pairs of that bucket already written by this
// chunk). Chunks are ordered, so equal keys keep their input order: the sort is stable.
#extension GL_GOOGLE_include_directive : require
#include "interface/sort.h"
#include "common/index.glsl"

layout(binding = HEMO_SORT_BINDING_PAIRS_IN) uniform usamplerBuffer pairsIn;  // uvec2 texels
layout(binding = HEMO_SORT_BINDING_COUNTS) uniform usamplerBuffer offsets;
layout(std430, binding = HEMO_SORT_BINDING_PAIRS_OUT) writeonly buffer PairsOut { uvec2 pairsOut[]; };
layout(push_constant) uniform Push { uint n; uint shift; uint chunkSize; uint chunkCount; uint digitBits; } pc;

void main() {
  const uint chunk = hemo_global_index();
  if (chunk >= pc.chunkCount) {
    return;
  }
  const uint buckets = 1u << pc.digitBits;  // digitBits <= HEMO_RADIX_BITS
  const uint mask = buckets - 1u;
  uint next[HEMO_RADIX_BUCKETS];
  for (uint b = 0u; b < buckets; ++b) {
    next[b] = texelFetch(offsets, int(b * pc.chunkCount + chunk)).x;
  }
  const uint first = chunk * pc.chunkSize;
  const uint last = min(first + pc.chunkSize, pc.n);
  for (uint i = first; i < last; ++i) {
    const uvec2 p = texelFetch(pairsIn, int(i)).xy;
    const uint b = (p.x >> pc.shift) & mask;
    pairsOut[next[b]] = p;
    next[b] += 1u;
  }
}
