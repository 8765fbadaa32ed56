#version 450
// The time step's reduction, second level (common/dt_fold.glsl): one workgroup reduces the
// (min, max) partials of the force pass (from index 0) and, with a vessel wall, of the wall
// stage (from wallBase) to dtResult, which the integrator reads. A pass that did not run this
// step (push constant `passes`) adds nothing; with neither, the result is (+inf, -inf). Any
// NaN partial makes the result (NaN, NaN).
#extension GL_GOOGLE_include_directive : require
#include "interface/sph.h"
#include "common/index.glsl"

layout(binding = HEMO_DTREDUCE_BINDING_PARTIALS) uniform samplerBuffer partials;  // RG32F
layout(std430, binding = HEMO_DTREDUCE_BINDING_COUNTS) readonly buffer Counts { uint dtCounts[2]; };
layout(std430, binding = HEMO_DTREDUCE_BINDING_RESULT) writeonly buffer Result { vec2 dtResult; };
layout(push_constant) uniform Push {
  uint wallBase;  // the wall stage's first partial
  uint passes;    // bit 0: the force pass ran, bit 1: the wall stage ran
} pc;

shared vec2 s_range[gl_WorkGroupSize.x];
shared bool s_nan[gl_WorkGroupSize.x];

void main() {
  const uint lid = gl_LocalInvocationID.x;
  const float inf = uintBitsToFloat(0x7f800000u);
  vec2 r = vec2(inf, -inf);
  bool nan = false;
  for (uint pass = 0u; pass < 2u; ++pass) {
    if ((pc.passes & (1u << pass)) == 0u) {
      continue;
    }
    const uint base = pass == 0u ? 0u : pc.wallBase;
    const uint count = dtCounts[pass];
    for (uint p = lid; p < count; p += gl_WorkGroupSize.x) {
      const vec2 v = texelFetch(partials, int(base + p)).xy;
      nan = nan || any(isnan(v));
      r = vec2(min(r.x, v.x), max(r.y, v.y));
    }
  }
  s_range[lid] = r;
  s_nan[lid] = nan;
  barrier();
  if (lid == 0u) {
    vec2 total = s_range[0];
    bool anyNan = s_nan[0];
    for (uint s = 1u; s < gl_WorkGroupSize.x; ++s) {
      total = vec2(min(total.x, s_range[s].x), max(total.y, s_range[s].y));
      anyNan = anyNan || s_nan[s];
    }
    dtResult = anyNan ? vec2(uintBitsToFloat(0x7fc00000u)) : total;
  }
}
