#version 450
// bench/pair_gather_texel.comp's contiguous pair loop with each invocation owning a cluster of
// kCluster particles (slots i kCluster ...): every list entry is fetched once and evaluated
// against all of them, so a fetch serves kCluster pairs (interface/bench.h).
#extension GL_GOOGLE_include_directive : require
#include "interface/bench.h"
#include "common/index.glsl"

layout(constant_id = 1) const uint kLoads = 1u;
layout(constant_id = 2) const uint kCluster = 1u;
// 0: a few flops per pair; 1: the density pass's (a Wendland W); 2: the force pass's (grad W,
// a viscous quotient, two vec3 sums)
layout(constant_id = 3) const uint kBody = 0u;

layout(binding = HEMO_BENCH_BINDING_LIST) uniform usamplerBuffer list;
layout(binding = HEMO_BENCH_BINDING_A) uniform samplerBuffer a;
layout(binding = HEMO_BENCH_BINDING_B) uniform samplerBuffer b;
layout(binding = HEMO_BENCH_BINDING_C) uniform samplerBuffer c;
layout(binding = HEMO_BENCH_BINDING_D) uniform samplerBuffer d;
layout(std430, binding = HEMO_BENCH_BINDING_OUT) writeonly buffer Out { vec4 outv[]; };
layout(push_constant) uniform Push {
  uint n;        // clusters
  uint entries;  // list entries per cluster
} pc;

void main() {
  const uint i = hemo_global_index();
  if (i >= pc.n) {
    return;
  }
  vec4 self[8];
  vec4 sum[8];
  vec3 sum2[8];
  for (uint m = 0u; m < kCluster; ++m) {
    self[m] = vec4(float(i * kCluster + m) * 1e-3, 0.5, 0.25, 1.0);
    sum[m] = vec4(0.0);
    sum2[m] = vec3(0.0);
  }
  for (uint k = 0u; k < pc.entries; ++k) {
    const int j = int(texelFetch(list, int(i * pc.entries + k)).x);
    vec4 x = kLoads >= 1u ? texelFetch(a, j) : vec4(float(j) * 1e-3, 0.0, 0.0, 1.0);
    if (kLoads >= 2u) x += texelFetch(b, j);
    if (kLoads >= 3u) x += texelFetch(c, j);
    if (kLoads >= 4u) x += texelFetch(d, j);
    for (uint m = 0u; m < kCluster; ++m) {
      const vec3 r = self[m].xyz - x.xyz;
      if (kBody == 0u) {
        const float r2 = dot(r, r) + 1e-6;
        sum[m] += vec4(r * (x.w * inversesqrt(r2)), r2);
      } else if (kBody == 1u) {
        const float q = sqrt(dot(r, r)) * 2.0;
        const float t = max(1.0 - 0.5 * q, 0.0);
        const float t2 = t * t;
        sum[m].x += x.w * t2 * t2 * (2.0 * q + 1.0);
      } else {
        const float r2 = dot(r, r);
        const float t = max(1.0 - sqrt(r2), 0.0);
        const vec3 gradW = r * (-3.0 * t * t * t);
        sum[m].xyz -= (x.w * self[m].w + x.x) * gradW;
        sum2[m] += (x.w * dot(r, gradW) / (r2 + 1e-4)) * (self[m].xyz - x.yzw);
      }
    }
  }
  vec4 total = vec4(0.0);
  for (uint m = 0u; m < kCluster; ++m) total += sum[m] + vec4(sum2[m], 0.0);
  outv[i] = total;
}
