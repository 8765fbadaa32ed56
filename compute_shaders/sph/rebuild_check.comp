#version 450
// The neighbour list's rebuild test, after the integrator, in one dispatch: the (min, max)
// of every slot's x displacement since the list build and the largest reach
// (sph/integrate.comp), then the decision for the next step's gated grid and list build,
// written straight into the gate's indirect arguments (common/gate.glsl): rebuild when the
// largest reach exceeds half the skin (push.threshold), or is NaN.
// Each workgroup reduces its block to a partial and counts itself finished; the last one
// reduces the partials (the result does not depend on which one that is: min and max are
// exact). The result also keeps the middle of the step before's range (w), from which the
// integrator extrapolates its reference. When the gate opens, the result's displacement
// range is set to (0, 0) with w = 0: the next step rebuilds, and displacements start again
// from the new build, so the next integrator measures the reach from c = 0. Any NaN makes
// the whole result NaN.
// Folding the three steps of the old test (a reduction, the reach pass, a second reduction)
// and the gate's own arming pass into this one saves llvmpipe three dispatches and their
// barriers every step (docs/benchmarks.md, "Session 17").
#extension GL_GOOGLE_include_directive : require
#extension GL_KHR_shader_subgroup_basic : require
#extension GL_KHR_shader_subgroup_arithmetic : require
#extension GL_KHR_shader_subgroup_vote : require
#include "interface/sph.h"
#include "interface/scan.h"
#include "common/index.glsl"

layout(binding = HEMO_CHECK_BINDING_DRIFT_X) uniform samplerBuffer driftX;
layout(binding = HEMO_CHECK_BINDING_REACH) uniform samplerBuffer reach;
// Written by every workgroup, read by the last: coherent, and published before the count.
layout(std430, binding = HEMO_CHECK_BINDING_PARTIALS) coherent buffer Partials { vec4 partials[]; };
layout(std430, binding = HEMO_CHECK_BINDING_COUNTER) coherent buffer Counter { uint finished; };
layout(std430, binding = HEMO_CHECK_BINDING_RESULT) buffer Result { vec4 result; };
layout(std430, binding = HEMO_CHECK_BINDING_GATE_ARMED) readonly buffer GateArmed { uvec4 gateArmed[]; };
layout(std430, binding = HEMO_CHECK_BINDING_GATE_ARGS) writeonly buffer GateArgs { uvec4 gateArgs[]; };
layout(std430, binding = HEMO_CHECK_BINDING_GATE_OPENED) buffer GateOpened { uint gateOpened; };
layout(push_constant) uniform Push {
  uint n;
  float threshold;
  uint gateSlots;
  uint staticSlots;  // 1: the slots past n hold rigid boundary particles (not integrated)
} pc;

#include "common/gate.glsl"

shared vec3 s_subgroup[gl_WorkGroupSize.x];
shared bool s_nan[gl_WorkGroupSize.x];
shared bool s_last;

// (min d.x, max d.x, max reach) of the workgroup, NaN if any invocation saw one; valid in
// invocation 0. Called in uniform control flow (it has a barrier).
vec3 hemo_workgroup_check(vec3 m, bool nan) {
  const vec3 sub = vec3(subgroupMin(m.x), subgroupMax(m.y), subgroupMax(m.z));
  const bool subNan = subgroupAny(nan);
  if (subgroupElect()) {
    s_subgroup[gl_SubgroupID] = sub;
    s_nan[gl_SubgroupID] = subNan;
  }
  barrier();
  vec3 r = s_subgroup[0];
  bool anyNan = s_nan[0];
  if (gl_LocalInvocationID.x == 0u) {
    for (uint s = 1u; s < gl_NumSubgroups; ++s) {
      r = vec3(min(r.x, s_subgroup[s].x), max(r.y, s_subgroup[s].y), max(r.z, s_subgroup[s].z));
      anyNan = anyNan || s_nan[s];
    }
  }
  return anyNan ? vec3(uintBitsToFloat(0x7fc00000u)) : r;
}

void main() {
  const uint block = hemo_group_index();
  const uint blockSize = gl_WorkGroupSize.x * HEMO_REDUCE_ITEMS;
  const uint blocks = (pc.n + blockSize - 1u) / blockSize;
  const uint base = block * blockSize + gl_LocalInvocationID.x * HEMO_REDUCE_ITEMS;
  const float inf = uintBitsToFloat(0x7f800000u);
  vec3 m = vec3(inf, -inf, -inf);
  bool nan = false;
  for (uint k = 0u; k < HEMO_REDUCE_ITEMS; ++k) {
    const uint idx = base + k;
    if (idx < pc.n) {
      const float dx = texelFetch(driftX, int(idx)).x;
      const float r = texelFetch(reach, int(idx)).x;
      nan = nan || isnan(dx) || isnan(r);
      m = vec3(min(m.x, dx), max(m.y, dx), max(m.z, r));
    }
  }
  const vec3 partial = hemo_workgroup_check(m, nan);
  if (gl_LocalInvocationID.x == 0u) {
    if (block < blocks) {
      partials[block] = vec4(partial, 0.0);
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
  m = vec3(inf, -inf, -inf);
  nan = false;
  for (uint p = gl_LocalInvocationID.x; p < blocks; p += gl_WorkGroupSize.x) {
    const vec3 v = partials[p].xyz;
    nan = nan || any(isnan(v));
    m = vec3(min(m.x, v.x), max(m.y, v.y), max(m.z, v.z));
  }
  // (The first round's shared values were all read before the barrier after s_last.)
  vec3 total = hemo_workgroup_check(m, nan);
  if (gl_LocalInvocationID.x == 0u) {
    if (pc.staticSlots != 0u && !isnan(total.z)) {
      // Slots the integrator left out (SphSolver::movingSlots): rigid boundary particles,
      // displacement 0, so their reach is |c| with the integrator's own reference c.
      float c = (result.x + result.y) - result.w;
      if (!(abs(c) < 1.0e30)) {
        c = 0.0;
      }
      total = vec3(min(total.x, 0.0), max(total.y, 0.0), max(total.z, abs(c)));
    }
    const bool open = hemo_gate_open(total.z, pc.threshold);
    const float lastMiddle = 0.5 * (result.x + result.y);  // the step before's, for the extrapolation
    result = open ? vec4(0.0, 0.0, total.z, 0.0) : vec4(total.xy, total.z, lastMiddle);
    hemo_gate_arm(open, pc.gateSlots);
    finished = 0u;  // every other workgroup has counted itself: ready for the next use
  }
}
