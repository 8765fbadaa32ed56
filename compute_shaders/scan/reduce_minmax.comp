#version 450
// Minimum and maximum of n floats, one (min, max) partial per workgroup; the host applies it
// again to the partials until one remains. Any NaN in the input makes the result (NaN, NaN),
// so a blown-up simulation cannot hide behind a min/max.
#extension GL_GOOGLE_include_directive : require
#extension GL_KHR_shader_subgroup_basic : require
#extension GL_KHR_shader_subgroup_arithmetic : require
#extension GL_KHR_shader_subgroup_vote : require
#include "interface/scan.h"
#include "common/index.glsl"

layout(std430, binding = HEMO_REDUCE_BINDING_VALUES) readonly buffer Values { float values[]; };
layout(std430, binding = HEMO_REDUCE_BINDING_PARTIALS_IN) readonly buffer PartialsIn { vec2 partialsIn[]; };
layout(std430, binding = HEMO_REDUCE_BINDING_PARTIALS_OUT) writeonly buffer PartialsOut { vec2 partialsOut[]; };
layout(push_constant) uniform Push { uint n; uint fromPartials; } pc;

shared vec2 s_subgroup[gl_WorkGroupSize.x];
shared bool s_nan[gl_WorkGroupSize.x];

void main() {
  const uint block = hemo_group_index();
  const uint base = (block * gl_WorkGroupSize.x + gl_LocalInvocationID.x) * HEMO_REDUCE_ITEMS;
  const float inf = uintBitsToFloat(0x7f800000u);
  vec2 mm = vec2(inf, -inf);
  bool nan = false;
  for (uint k = 0u; k < HEMO_REDUCE_ITEMS; ++k) {
    const uint idx = base + k;
    if (idx < pc.n) {
      const vec2 v = pc.fromPartials != 0u ? partialsIn[idx] : vec2(values[idx]);
      nan = nan || isnan(v.x) || isnan(v.y);
      mm = vec2(min(mm.x, v.x), max(mm.y, v.y));
    }
  }
  const vec2 sub = vec2(subgroupMin(mm.x), subgroupMax(mm.y));
  const bool subNan = subgroupAny(nan);
  if (subgroupElect()) {
    s_subgroup[gl_SubgroupID] = sub;
    s_nan[gl_SubgroupID] = subNan;
  }
  barrier();
  if (gl_LocalInvocationID.x == 0u) {
    vec2 r = s_subgroup[0];
    bool anyNan = s_nan[0];
    for (uint s = 1u; s < gl_NumSubgroups; ++s) {
      r = vec2(min(r.x, s_subgroup[s].x), max(r.y, s_subgroup[s].y));
      anyNan = anyNan || s_nan[s];
    }
    const uint blocks = (pc.n + gl_WorkGroupSize.x * HEMO_REDUCE_ITEMS - 1u) / (gl_WorkGroupSize.x * HEMO_REDUCE_ITEMS);
    if (block < blocks) {
      partialsOut[block] = anyNan ? vec2(uintBitsToFloat(0x7fc00000u)) : r;
    }
  }
}
