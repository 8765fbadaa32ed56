#version 450
// The fixed cost of a dispatch (hemo-bench primitives, "dispatch"): a shader that only reads,
// so that dispatches of it in a row need no barrier between them (see interface/bench.h).
#extension GL_GOOGLE_include_directive : require
#include "interface/bench.h"
#include "common/index.glsl"

layout(std430, binding = HEMO_BENCH_PROBE_BINDING_IN) readonly buffer In { uint values[]; };
layout(push_constant) uniform Push { uint n; } pc;

shared uint s_sum;

void main() {
  const uint i = hemo_global_index();
  // A read the compiler cannot drop, into workgroup memory nobody else sees.
  if (i < pc.n && values[i] == 0xffffffffu) {
    s_sum = i;
  }
}
