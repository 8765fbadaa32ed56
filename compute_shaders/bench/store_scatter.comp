#version 450
// What a per-lane store costs (hemo-bench primitives, "store_scatter"): interface/bench.h.
// Every invocation stores one uint per iteration, always (variant 0 of constant 3) or only
// where a value derived from the data passes a test (1, as a list build keeps candidates),
// through a storage buffer or a storage texel buffer (constant 2).
#extension GL_GOOGLE_include_directive : require
#include "interface/bench.h"
#include "common/index.glsl"

layout(constant_id = 1) const uint kContiguous = 0u;
layout(constant_id = 2) const uint kTexel = 0u;
layout(constant_id = 3) const uint kMasked = 0u;

layout(std430, binding = HEMO_BENCH_STORE_BINDING_OUT) writeonly buffer Out { uint outv[]; };
layout(r32ui, binding = HEMO_BENCH_STORE_BINDING_IMAGE) uniform writeonly uimageBuffer image;
layout(push_constant) uniform Push {
  uint n;
  uint entries;
} pc;

void main() {
  const uint i = hemo_global_index();
  if (i >= pc.n) {
    return;
  }
  uint h = i * 2654435761u;
  uint count = 0u;
  for (uint k = 0u; k < pc.entries; ++k) {
    h = h * 1664525u + 1013904223u;
    const uint slot = kMasked != 0u ? count : k;
    const uint at = kContiguous != 0u ? i * pc.entries + slot : slot * pc.n + i;
    if (kTexel != 0u) {
      imageStore(image, int(at), uvec4(h));
    } else {
      outv[at] = h;
    }
    count += kMasked != 0u ? (h >> 31) : 1u;
  }
}
