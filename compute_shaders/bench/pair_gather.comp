#version 450
// The cost of an SPH pair loop's memory accesses on a device (hemo-bench primitives,
// "pair_gather"): see interface/bench.h. With loads = 0 only the list index is read, so the
// rows for 0..4 separate the list read, each per-neighbour vec4 gather and the arithmetic.
// Variants (constant 3): 0 every gather a vec4; 1 "narrow": the second gather reads one
// float and the third a vec2 (what a gather's width costs); 2 "uniform index": every
// invocation of a workgroup reads the same entries (whether the device broadcasts a load whose
// index is the same across the workgroup).
#extension GL_GOOGLE_include_directive : require
#include "interface/bench.h"
#include "common/index.glsl"

layout(constant_id = 1) const uint kLoads = 1u;
layout(constant_id = 2) const uint kContiguous = 0u;  // 1: entries of a particle adjacent
layout(constant_id = 3) const uint kVariant = 0u;

layout(std430, binding = HEMO_BENCH_BINDING_LIST) readonly buffer List { uint list[]; };
layout(std430, binding = HEMO_BENCH_BINDING_A) readonly buffer A { vec4 a[]; };
layout(std430, binding = HEMO_BENCH_BINDING_B) readonly buffer B { vec4 b[]; };
layout(std430, binding = HEMO_BENCH_BINDING_C) readonly buffer C { vec4 c[]; };
layout(std430, binding = HEMO_BENCH_BINDING_D) readonly buffer D { vec4 d[]; };
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
    const uint j = kVariant == 2u ? list[gl_WorkGroupID.x * pc.entries + k]
                                  : list[kContiguous != 0u ? i * pc.entries + k : k * pc.n + i];
    // Without loads the neighbour's "position" comes from its index, so the loop still
    // depends on j.
    vec4 x = kLoads >= 1u ? a[j] : vec4(float(j) * 1e-3, 0.0, 0.0, 1.0);
    if (kLoads >= 2u) x += kVariant == 1u ? vec4(b[j].x) : b[j];
    if (kLoads >= 3u) x += kVariant == 1u ? vec4(c[j].xy, 0.0, 0.0) : c[j];
    if (kLoads >= 4u) x += d[j];
    const vec3 r = self.xyz - x.xyz;
    const float r2 = dot(r, r) + 1e-6;
    sum += vec4(r * (x.w * inversesqrt(r2)), r2);
  }
  outv[i] = sum;
}
