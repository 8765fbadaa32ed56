#version 450
// Blades cut the springs their edge sweeps through (interface/tool.h): per unbroken spring, the
// segment between its ends against the surface each cutting blade's edge swept since the
// last step, as two triangles; a spring that crosses it breaks for good. Each spring writes
// only its own flag, and the count is an integer atomic: the result does not depend on order.
#extension GL_GOOGLE_include_directive : require
#include "interface/sph.h"
#include "interface/tool.h"
#include "interface/wall.h"
#include "common/index.glsl"
#include "common/sph_params.glsl"
#include "common/clock.glsl"
#include "wall/spring.glsl"

layout(binding = HEMO_TOOLCUT_BINDING_POSITIONS) uniform samplerBuffer positionsT;
layout(binding = HEMO_TOOLCUT_BINDING_SLOT_OF_ID) uniform usamplerBuffer slotOfIdT;
layout(std430, binding = HEMO_TOOLCUT_BINDING_SPRINGS) buffer Springs { Spring springs[]; };
layout(std430, binding = HEMO_TOOLCUT_BINDING_COUNTERS) buffer Counters { uint counters[]; };
HEMO_SPH_PARAMS_UNIFORM(HEMO_TOOLCUT_BINDING_PARAMS);
layout(std140, binding = HEMO_TOOLCUT_BINDING_TOOLS) uniform Tools { vec4 toolData[HEMO_TOOL_DATA_VEC4S]; };
layout(std430, binding = HEMO_TOOLCUT_BINDING_CLOCK) readonly buffer Clock { ClockRecord clocks[2]; };
layout(push_constant) uniform Push {
  uint springCount;
  uint tools;
  uint clockIn;
} pc;

#include "common/tool_pose.glsl"

vec3 periodicImage(vec3 d) {
  return d - params.period.xyz * round(d * params.invPeriod.xyz);
}

// Whether the segment p + s d, s in [0, 1], meets the triangle (v0, v1, v2) (Moeller and
// Trumbore's test; a segment in the triangle's plane, or a triangle of no area, does not).
bool segmentMeetsTriangle(vec3 p, vec3 d, vec3 v0, vec3 v1, vec3 v2) {
  const vec3 e1 = v1 - v0;
  const vec3 e2 = v2 - v0;
  const vec3 pv = cross(d, e2);
  const float det = dot(e1, pv);
  if (det == 0.0) {
    return false;
  }
  const float inv = 1.0 / det;
  const vec3 tv = p - v0;
  const float u = dot(tv, pv) * inv;
  if (u < 0.0 || u > 1.0) {
    return false;
  }
  const vec3 qv = cross(tv, e1);
  const float v = dot(d, qv) * inv;
  if (v < 0.0 || u + v > 1.0) {
    return false;
  }
  const float s = dot(e2, qv) * inv;
  return s >= 0.0 && s <= 1.0;
}

void main() {
  const uint k = hemo_global_index();
  if (k >= pc.springCount || springs[k].broken != 0u) {
    return;
  }
  const ClockRecord clock = clocks[pc.clockIn];
  if (!(clock.lastDt > 0.0)) {
    return;  // no step yet: nothing swept
  }
  const float t1 = clock.time;
  const float t0 = t1 - clock.lastDt;
  const vec3 xa = texelFetch(positionsT, int(texelFetch(slotOfIdT, int(springs[k].a)).x)).xyz;
  const vec3 xb = texelFetch(positionsT, int(texelFetch(slotOfIdT, int(springs[k].b)).x)).xyz;
  for (uint tool = 0u; tool < pc.tools; ++tool) {
    const vec4 shape = hemo_tool_shape(tool);
    if (uint(shape.x) != HEMO_TOOL_KIND_BLADE) {
      continue;
    }
    const HemoToolPose before = hemo_tool_pose(tool, t0);
    if (!before.cutting) {
      continue;
    }
    const HemoToolPose after = hemo_tool_pose(tool, t1);
    const vec3 a0 = before.position, b0 = a0 + shape.z * before.axis;
    const vec3 a1 = after.position, b1 = a1 + shape.z * after.axis;
    const vec3 p = a0 + periodicImage(xa - a0);  // the spring's image next to the blade
    const vec3 d = periodicImage(xb - xa);
    if (segmentMeetsTriangle(p, d, a0, b0, b1) || segmentMeetsTriangle(p, d, a0, b1, a1)) {
      springs[k].broken = 1u;
      atomicAdd(counters[HEMO_WALL_COUNTER_BROKEN], 1u);
      return;
    }
  }
}
