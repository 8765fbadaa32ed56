#version 450
// What a parameter read costs (hemo-bench primitives, "param_read"): see interface/bench.h.
// Every invocation runs the same loop and reads, per iteration, one vec4 whose index depends
// only on the loop counter, so the address is the same across the whole dispatch, as for a
// scene parameter. Variant (constant 1): 0 none (the loop's arithmetic alone), 1 from a
// storage buffer, 2 from a uniform buffer, 3 from push constants.
#extension GL_GOOGLE_include_directive : require
#include "interface/bench.h"
#include "common/index.glsl"

layout(constant_id = 1) const uint kVariant = 0u;

layout(std430, binding = HEMO_BENCH_PARAM_BINDING_STORAGE) readonly buffer Storage { vec4 sp[HEMO_BENCH_PARAM_VEC4S]; };
layout(std140, binding = HEMO_BENCH_PARAM_BINDING_UNIFORM) uniform Uniform { vec4 up[HEMO_BENCH_PARAM_VEC4S]; };
layout(std430, binding = HEMO_BENCH_PARAM_BINDING_OUT) writeonly buffer Out { vec4 outv[]; };
layout(push_constant) uniform Push {
  vec4 pp[HEMO_BENCH_PARAM_VEC4S - 1];
  uint n;
  uint reads;
} pc;

void main() {
  const uint i = hemo_global_index();
  if (i >= pc.n) {
    return;
  }
  vec4 sum = vec4(float(i) * 1e-3, 0.5, 0.25, 1.0);
  for (uint k = 0u; k < pc.reads; ++k) {
    const uint slot = k % uint(HEMO_BENCH_PARAM_VEC4S - 1);
    vec4 p = vec4(float(k) * 1e-3, 0.5, 0.25, 1.0);
    if (kVariant == 1u) p = sp[slot];
    if (kVariant == 2u) p = up[slot];
    if (kVariant == 3u) p = pc.pp[slot];
    sum = sum * p.x + p.yzwx;
  }
  outv[i] = sum;
}
