#version 450
// Minimum and maximum of n floats in one dispatch. Each workgroup reduces its block of
// workgroupSize * HEMO_REDUCE_ITEMS values to a (min, max) partial and counts itself finished
// (an atomic counter); the workgroup that finishes last reduces all partials, writes the
// result and resets the counter for the next use. One dispatch instead of one per level saves
// a dispatch and a barrier per level, which llvmpipe charges ~50 us each (every step runs
// three reductions). The result does not depend on which workgroup is last: min and max are
// exact. Any NaN in the input makes the result (NaN, NaN), so a blown-up simulation cannot
// hide behind a min/max.
#extension GL_GOOGLE_include_directive : require
#extension GL_KHR_shader_subgroup_basic : require
#extension GL_KHR_shader_subgroup_arithmetic : require
#extension GL_KHR_shader_subgroup_vote : require
#include "interface/scan.h"
#include "common/index.glsl"

// The input is a texel slot (R32_SFLOAT): llvmpipe loads texels as one vector gather, storage
// values lane by lane (interface/sph.h, "texel slots").
layout(binding = HEMO_REDUCE_BINDING_VALUES) uniform samplerBuffer values;
// Written by every workgroup, read by the last: coherent, and published before the count.
layout(std430, binding = HEMO_REDUCE_BINDING_PARTIALS) coherent buffer Partials { vec2 partials[]; };
layout(std430, binding = HEMO_REDUCE_BINDING_COUNTER) coherent buffer Counter { uint finished; };
layout(std430, binding = HEMO_REDUCE_BINDING_RESULT) writeonly buffer Result { vec2 result; };
layout(push_constant) uniform Push { uint n; } pc;

shared vec2 s_subgroup[gl_WorkGroupSize.x];
shared bool s_nan[gl_WorkGroupSize.x];
shared bool s_last;


// The workgroup's (min, max) of every invocation's mm, or NaN if any invocation saw one;
// valid in invocation 0. Called in uniform control flow (it has a barrier).
vec2 hemo_workgroup_minmax(vec2 mm, bool nan) {
  const vec2 sub = vec2(subgroupMin(mm.x), subgroupMax(mm.y));
  const bool subNan = subgroupAny(nan);
  if (subgroupElect()) {
    s_subgroup[gl_SubgroupID] = sub;
    s_nan[gl_SubgroupID] = subNan;
  }
  barrier();
  vec2 r = s_subgroup[0];
  bool anyNan = s_nan[0];
  if (gl_LocalInvocationID.x == 0u) {
    for (uint s = 1u; s < gl_NumSubgroups; ++s) {
      r = vec2(min(r.x, s_subgroup[s].x), max(r.y, s_subgroup[s].y));
      anyNan = anyNan || s_nan[s];
    }
  }
  return anyNan ? vec2(uintBitsToFloat(0x7fc00000u)) : r;
}

void main() {
  const uint block = hemo_group_index();
  const uint blockSize = gl_WorkGroupSize.x * HEMO_REDUCE_ITEMS;
  const uint blocks = (pc.n + blockSize - 1u) / blockSize;
  const uint base = block * blockSize + gl_LocalInvocationID.x * HEMO_REDUCE_ITEMS;
  const float inf = uintBitsToFloat(0x7f800000u);
  vec2 mm = vec2(inf, -inf);
  bool nan = false;
  for (uint k = 0u; k < HEMO_REDUCE_ITEMS; ++k) {
    const uint idx = base + k;
    if (idx < pc.n) {
      const float v = texelFetch(values, int(idx)).x;
      nan = nan || isnan(v);
      mm = vec2(min(mm.x, v), max(mm.y, v));
    }
  }
  const vec2 partial = hemo_workgroup_minmax(mm, nan);
  if (gl_LocalInvocationID.x == 0u) {
    if (block < blocks) {
      partials[block] = partial;
    }
    memoryBarrierBuffer();  // the partial is visible before the count says so
    const uint groups = gl_NumWorkGroups.x * gl_NumWorkGroups.y * gl_NumWorkGroups.z;
    s_last = atomicAdd(finished, 1u) == groups - 1u;
  }
  barrier();
  if (!s_last) {
    return;  // the same for the whole workgroup
  }
  memoryBarrierBuffer();
  mm = vec2(inf, -inf);
  nan = false;
  for (uint p = gl_LocalInvocationID.x; p < blocks; p += gl_WorkGroupSize.x) {
    const vec2 v = partials[p];
    nan = nan || isnan(v.x) || isnan(v.y);
    mm = vec2(min(mm.x, v.x), max(mm.y, v.y));
  }
  // (The first round's shared values were all read before the barrier after s_last.)
  const vec2 total = hemo_workgroup_minmax(mm, nan);
  if (gl_LocalInvocationID.x == 0u) {
    result = total;
    finished = 0u;  // every other workgroup has counted itself: ready for the next use
  }
}
