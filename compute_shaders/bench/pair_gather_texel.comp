#version 450
// bench/pair_gather.comp with the list and the per-neighbour data read as uniform texel
// buffers (texelFetch) instead of storage buffers: what the same pair loop costs when the
// device gathers through its texel path (interface/bench.h).
#extension GL_GOOGLE_include_directive : require
#include "interface/bench.h"
#include "common/index.glsl"

layout(constant_id = 1) const uint kLoads = 1u;
layout(constant_id = 2) const uint kContiguous = 0u;  // 1: entries of a particle adjacent
layout(constant_id = 3) const uint kVariant = 0u;

layout(binding = HEMO_BENCH_BINDING_LIST) uniform usamplerBuffer list;
layout(binding = HEMO_BENCH_BINDING_A) uniform samplerBuffer a;
layout(binding = HEMO_BENCH_BINDING_B) uniform samplerBuffer b;
layout(binding = HEMO_BENCH_BINDING_C) uniform samplerBuffer c;
layout(binding = HEMO_BENCH_BINDING_D) uniform samplerBuffer d;
layout(std430, binding = HEMO_BENCH_BINDING_OUT) writeonly buffer Out { vec4 outv[]; };
layout(push_constant) uniform Push {
  uint n;
  uint entries;
} pc;

void main() {
  const uint i = hemo_global_index();
  if (i >= pc.n) {
    return;
  }
  const vec4 self = vec4(float(i) * 1e-3, 0.5, 0.25, 1.0);
  vec4 sum = vec4(0.0);
  for (uint k = 0u; k < pc.entries; ++k) {
    const int j = kVariant == 1u ? int(texelFetch(list, int(gl_WorkGroupID.x * pc.entries + k)).x) : int(texelFetch(list, int(kContiguous != 0u ? i * pc.entries + k : k * pc.n + i)).x);
    vec4 x = kLoads >= 1u ? texelFetch(a, j) : vec4(float(j) * 1e-3, 0.0, 0.0, 1.0);
    if (kLoads >= 2u) x += texelFetch(b, j);
    if (kLoads >= 3u) x += texelFetch(c, j);
    if (kLoads >= 4u) x += texelFetch(d, j);
    const vec3 r = self.xyz - x.xyz;
    const float r2 = dot(r, r) + 1e-6;
    sum += vec4(r * (x.w * inversesqrt(r2)), r2);
  }
  outv[i] = sum;
}
