#version 450
// The time step's reduction, second level (common/dt_fold.glsl): one workgroup reduces the
// (min, max) partials of the force pass (from index 0), with a vessel wall of the wall stage
// (from wallBase) and with tools of their contact pass (their own buffer, from index 0) to
// dtResult, which the integrator reads. A pass that did not run this
// step (push constant `passes`) adds nothing; with neither, the result is (+inf, -inf). Any
// NaN partial makes the result (NaN, NaN).
// With tools it also sums each tool's force and torque partials (tool/contact.comp) in a fixed
// order (each lane a strided run, then lane 0 over the lanes) into the step's tool log, with
// the tool's pose: the single-workgroup pass the step has anyway, so tools add one dispatch
// (the contact pass) per force evaluation.
#extension GL_GOOGLE_include_directive : require
#include "interface/sph.h"
#include "interface/tool.h"
#include "common/index.glsl"
#include "common/clock.glsl"

layout(binding = HEMO_DTREDUCE_BINDING_PARTIALS) uniform samplerBuffer partials;  // RG32F
layout(std430, binding = HEMO_DTREDUCE_BINDING_COUNTS) readonly buffer Counts { uint dtCounts[3]; };
layout(std430, binding = HEMO_DTREDUCE_BINDING_RESULT) writeonly buffer Result { vec2 dtResult; };
layout(binding = HEMO_DTREDUCE_BINDING_TOOL_PARTIALS) uniform samplerBuffer toolPartials;  // RG32F
layout(std140, binding = HEMO_DTREDUCE_BINDING_TOOLS) uniform Tools { vec4 toolData[HEMO_TOOL_DATA_VEC4S]; };
layout(std430, binding = HEMO_DTREDUCE_BINDING_CLOCK) readonly buffer Clock { ClockRecord clocks[2]; };
layout(std430, binding = HEMO_DTREDUCE_BINDING_TOOL_FORCES) readonly buffer ToolForces { vec4 toolForces[]; };
layout(std430, binding = HEMO_DTREDUCE_BINDING_TOOL_FORCE_COUNT) readonly buffer ToolForceCount { uint toolForceCount; };
layout(std430, binding = HEMO_DTREDUCE_BINDING_TOOL_LOG) writeonly buffer ToolLog { vec4 toolLog[]; };
layout(push_constant) uniform Push {
  uint wallBase;  // the wall stage's first partial
  uint passes;    // bit 0: the force pass ran, bit 1: the wall stage ran, bit 2: the tools' contact
  uint tools;     // tools whose force partials to sum (0: none)
  uint toolStride;  // partials per tool
  uint clockIn;   // the clock record of this force evaluation
  uint logIndex;  // the step's index in the batch (the tool log's row)
} pc;

#include "common/tool_pose.glsl"

shared vec2 s_range[gl_WorkGroupSize.x];
shared bool s_nan[gl_WorkGroupSize.x];
shared vec4 s_force[gl_WorkGroupSize.x];
shared vec4 s_torque[gl_WorkGroupSize.x];

void main() {
  const uint lid = gl_LocalInvocationID.x;
  const float inf = uintBitsToFloat(0x7f800000u);
  vec2 r = vec2(inf, -inf);
  bool nan = false;
  for (uint pass = 0u; pass < 3u; ++pass) {
    if ((pc.passes & (1u << pass)) == 0u) {
      continue;
    }
    const uint base = pass == 0u ? 0u : pc.wallBase;
    const uint count = dtCounts[pass];
    for (uint p = lid; p < count; p += gl_WorkGroupSize.x) {
      const vec2 v = pass == 2u ? texelFetch(toolPartials, int(p)).xy : texelFetch(partials, int(base + p)).xy;
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
  const uint count = pc.tools > 0u ? toolForceCount : 0u;
  for (uint k = 0u; k < pc.tools; ++k) {
    vec4 f = vec4(0.0), m = vec4(0.0);
    for (uint p = lid; p < count; p += gl_WorkGroupSize.x) {
      const uint at = (k * pc.toolStride + p) * 2u;
      f += toolForces[at];
      m += toolForces[at + 1u];
    }
    barrier();  // (the previous tool's sums are read)
    s_force[lid] = f;
    s_torque[lid] = m;
    barrier();
    if (lid == 0u) {
      vec4 force = vec4(0.0), torque = vec4(0.0);
      for (uint l = 0u; l < gl_WorkGroupSize.x; ++l) {
        force += s_force[l];
        torque += s_torque[l];
      }
      const float t = clocks[pc.clockIn].time;
      const HemoToolPose pose = hemo_tool_pose(k, t);
      const uint at = (pc.logIndex * pc.tools + k) * HEMO_TOOL_LOG_VEC4S;
      toolLog[at] = vec4(force.xyz, t);
      toolLog[at + 1u] = vec4(torque.xyz, 0.0);
      toolLog[at + 2u] = vec4(pose.position, pose.speed);
      toolLog[at + 3u] = pose.orientation;
    }
  }
}
