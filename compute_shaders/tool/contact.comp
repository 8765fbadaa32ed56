#version 450
// The tools' contact with the fluid and the wall (interface/tool.h): each particle within the
// contact distance D of a tool's surface is pushed out along the surface normal, and the tool
// takes the opposite force (and its torque about the tool's position), summed per SIMD group
// for sph/dt_reduce.comp (no float atomics: the sums' order is fixed). A grasper's jaws grip
// the free wall points they squeeze (interface/tool.h, "Grasping").
#extension GL_GOOGLE_include_directive : require
#extension GL_KHR_shader_subgroup_basic : require
#extension GL_KHR_shader_subgroup_arithmetic : require
#extension GL_KHR_shader_subgroup_vote : require
#include "interface/sph.h"
#include "interface/tool.h"
#include "common/index.glsl"
#include "common/sph_params.glsl"
#include "common/clock.glsl"

layout(binding = HEMO_TOOLC_BINDING_POSITIONS) uniform samplerBuffer positionsT;
layout(binding = HEMO_TOOLC_BINDING_VELOCITIES) uniform samplerBuffer velocitiesT;
layout(binding = HEMO_TOOLC_BINDING_IDS) uniform usamplerBuffer idsT;
layout(binding = HEMO_TOOLC_BINDING_WALL_INFO) uniform samplerBuffer wallInfoT;
HEMO_SPH_PARAMS_UNIFORM(HEMO_TOOLC_BINDING_PARAMS);
layout(std140, binding = HEMO_TOOLC_BINDING_TOOLS) uniform Tools { vec4 toolData[HEMO_TOOL_DATA_VEC4S]; };
layout(std430, binding = HEMO_TOOLC_BINDING_CLOCK) readonly buffer Clock { ClockRecord clocks[2]; };
layout(std430, binding = HEMO_TOOLC_BINDING_ACCEL) buffer Accel { vec4 accel[]; };
layout(std430, binding = HEMO_TOOLC_BINDING_HELD) buffer Held { vec4 held[]; };
layout(std430, binding = HEMO_TOOLC_BINDING_PARTIALS) writeonly buffer Partials { vec4 partials[]; };
layout(std430, binding = HEMO_TOOLC_BINDING_PARTIAL_COUNT) writeonly buffer PartialCount { uint partialCount; };
layout(std430, binding = HEMO_TOOLC_BINDING_DT_PARTIALS) writeonly buffer DtPartials { vec2 dtPartials[]; };
layout(std430, binding = HEMO_TOOLC_BINDING_DT_COUNTS) writeonly buffer DtCounts { uint dtCounts[3]; };
layout(std430, binding = HEMO_TOOLC_BINDING_GRIPS) buffer Grips { vec4 grips[]; };
layout(push_constant) uniform Push {
  uint n;        // the moving slots [0, n)
  uint idCount;  // wall points (ids below it have a record in wallInfo)
  uint tools;
  uint held;     // 1: the wall takes substeps (add to its held record too)
  uint stride;   // partials per tool
  uint clockIn;  // the clock record that holds the time of this force evaluation
} pc;

#include "common/dt_fold.glsl"
#include "common/tool_pose.glsl"


// The push of one jaw or capsule on a particle at separation `arm` from the tool's tip
// (m/s^2): the points within `radius` of the rectangle from `base` spanned by `axis` (length
// `len`) and `lateral` (half-width `halfWidth` either side); half-width 0: a capsule.
// `gap` gets the distance to the surface.
vec3 slabPush(vec3 arm, vec3 base, vec3 axis, vec3 lateral, float len, float halfWidth, float radius, float reach,
              float psi, out float gap) {
  const vec3 rel = arm - base;
  const float along = clamp(dot(rel, axis), 0.0, len);
  const float across = clamp(dot(rel, lateral), -halfWidth, halfWidth);
  const vec3 off = rel - along * axis - across * lateral;  // from the nearest point of the rectangle
  const float dist = length(off);
  gap = dist - radius;  // to the surface; <= 0 inside
  if (!(gap < reach)) {
    return vec3(0.0);
  }
  vec3 normal;
  if (dist > 1.0e-6 * radius) {
    normal = off / dist;
  } else {  // on the rectangle itself: out along its normal (for a segment, one normal to it)
    const vec3 other = halfWidth > 0.0 ? lateral : (abs(axis.x) < 0.9 ? vec3(1.0, 0.0, 0.0) : vec3(0.0, 1.0, 0.0));
    normal = normalize(cross(axis, other));
  }
  const float q = max(gap / (2.0 * params.h), 1.0e-3);
  return (psi * (1.0 - q) * inversesqrt(q)) * normal;
}

// The acceleration tool k gives a particle at x (m/s^2), and the particle's separation from
// the tool's tip (for the torque). A grasper's two jaws each push as a rounded plate;
// `squeezed` says whether the point lies within the contact distance of both.
vec3 contactAccel(uint k, HemoToolPose pose, vec3 x, out vec3 arm, out bool squeezed) {
  const vec4 shape = hemo_tool_shape(k);  // (kind, radius, length, D)
  const vec4 contact = hemo_tool_contact(k);  // (Psi, first key, keys, jaw half-width)
  const vec3 d = x - pose.position;
  arm = d - params.period.xyz * round(d * params.invPeriod.xyz);  // minimum image (period 0: none)
  float gap, other;
  squeezed = false;
  if (uint(shape.x) != HEMO_TOOL_KIND_GRASPER) {
    return slabPush(arm, vec3(0.0), pose.axis, pose.side, shape.z, 0.0, shape.y, shape.w, contact.x, gap);
  }
  const vec3 lateral = cross(pose.axis, pose.side);
  const vec3 side = (0.5 * pose.opening + shape.y) * pose.side;
  const vec3 push = slabPush(arm, side, pose.axis, lateral, shape.z, contact.w, shape.y, shape.w, contact.x, gap) +
                    slabPush(arm, -side, pose.axis, lateral, shape.z, contact.w, shape.y, shape.w, contact.x, other);
  squeezed = gap < shape.w && other < shape.w;
  return push;
}

// The grip's pull on a point of mass `mass` at separation `arm` from the tip, moving at v,
// held at `anchor` (along the axis, across the jaws) by grasper k (interface/tool.h).
vec3 gripAccel(uint k, HemoToolPose pose, vec3 arm, vec3 v, vec2 anchor, float mass) {
  const float omega = sqrt(hemo_tool_grip(k).x / mass);
  const vec3 lateral = cross(pose.axis, pose.side);
  const vec3 slip = pose.velocity + cross(pose.spin, arm) - v;  // the jaw's material point against the point
  const float along = omega * omega * (anchor.x - dot(arm, pose.axis)) + 2.0 * omega * dot(slip, pose.axis);
  const float across = omega * omega * (anchor.y - dot(arm, lateral)) + 2.0 * omega * dot(slip, lateral);
  return along * pose.axis + across * lateral;
}

void main() {
  const uint slot = hemo_global_index();
  // The tools' poses at this force evaluation's time: every invocation evaluates them (a few
  // uniform reads), where they are needed (an array of them costs CPU devices private memory
  // per workgroup).
  const float t = clocks[pc.clockIn].time;
  float mass = 0.0;
  bool wall = false;
  uint id = ~0u;
  vec3 x = vec3(0.0);
  if (slot < pc.n) {
    const uint kind = uint(texelFetch(velocitiesT, int(slot)).w);
    const vec4 xm = texelFetch(positionsT, int(slot));
    x = xm.xyz;
    if (kind == HEMO_KIND_FLUID) {
      mass = xm.w;
    } else if (kind == HEMO_KIND_WALL) {
      wall = true;
      id = texelFetch(idsT, int(slot)).x;
      mass = xm.w;
      if (id < pc.idCount) {
        const vec4 info = texelFetch(wallInfoT, int(id));
        mass = info.y != 0.0 ? 0.0 : info.x;  // anchored points do not move
      } else {
        id = ~0u;
      }
    }
  }
  // a free wall point of the network may be gripped: its record, and the grasper that squeezes it
  const bool grippable = id != ~0u && mass > 0.0;
  const vec4 record = grippable ? grips[id] : vec4(0.0);
  const uint holder = uint(record.w);  // tool + 1, 0: none
  uint gripper = 0u;                 // tool + 1 that grips it now
  vec3 total = vec3(0.0);
  uint touched = 0u;
  for (uint k = 0u; k < pc.tools; ++k) {
    vec3 arm;
    bool squeezed = false;
    const vec3 push = mass > 0.0 ? contactAccel(k, hemo_tool_pose(k, t), x, arm, squeezed) : vec3(0.0);
    if (push != vec3(0.0)) {
      touched |= 1u << k;
      total += push;
    }
    // the grasper that holds it keeps it while it squeezes it, else the first that squeezes it
    if (grippable && squeezed && hemo_tool_grip(k).x > 0.0 && (gripper == 0u || k + 1u == holder)) {
      gripper = k + 1u;
    }
  }
  vec3 grip = vec3(0.0);
  float limit = 0.0;
  bool valid = false;
  if (grippable) {
    vec2 anchor = record.xy;
    if (gripper != 0u) {
      const uint k = gripper - 1u;
      const HemoToolPose pose = hemo_tool_pose(k, t);
      vec3 d = x - pose.position;
      d -= params.period.xyz * round(d * params.invPeriod.xyz);
      if (gripper != holder) {  // gripped now: where it is
        anchor = vec2(dot(d, pose.axis), dot(d, cross(pose.axis, pose.side)));
      }
      grip = gripAccel(k, pose, d, texelFetch(velocitiesT, int(slot)).xyz, anchor, mass);
      touched |= 1u << k;
      total += grip;
      limit = hemo_tool_grip(k).y * sqrt(mass / hemo_tool_grip(k).x);
      valid = true;
    }
    if (gripper != holder) {
      grips[id] = gripper != 0u ? vec4(anchor, 0.0, float(gripper)) : vec4(0.0);
    }
  }
  if (touched != 0u) {
    const vec4 before = accel[slot];
    const vec3 after = before.xyz + total;
    accel[slot] = vec4(after, before.w);
    if (pc.held != 0u && wall) {
      held[slot].xyz += total;
    }
    const float force = params.cflForce * sqrt(params.h / max(length(after), 1.0e-30));
    limit = valid ? min(limit, force) : force;
    valid = true;
  }
  if (slot == 0u) {  // the tools' own limit: a surface moves at most D / 4 per step
    for (uint k = 0u; k < pc.tools; ++k) {
      const float speed = hemo_tool_pose(k, t).speed;
      if (speed > 0.0) {
        const float own = 0.25 * hemo_tool_shape(k).w / speed;
        limit = valid ? min(limit, own) : own;
        valid = true;
      }
    }
  }
  // every invocation, in uniform control flow: subgroup operations
  hemo_dt_partial(limit, valid, 0u, 2u, 0u, true);
  const uint partial = hemo_group_index() * gl_NumSubgroups + gl_SubgroupID;
  for (uint k = 0u; k < pc.tools; ++k) {
    vec4 force = vec4(0.0), torque = vec4(0.0);
    if (subgroupAny((touched & (1u << k)) != 0u)) {
      // (computed again: an array of the pushes indexed by tool costs CPU devices more)
      vec3 arm = vec3(0.0);
      bool squeezed;
      vec3 push = (touched & (1u << k)) != 0u ? contactAccel(k, hemo_tool_pose(k, t), x, arm, squeezed) : vec3(0.0);
      if (k + 1u == gripper) {
        push += grip;
      }
      const vec3 onTool = -mass * push;
      force = vec4(subgroupAdd(onTool), 0.0);
      torque = vec4(subgroupAdd(cross(arm, onTool)), 0.0);
    }
    if (subgroupElect()) {
      const uint at = (k * pc.stride + partial) * 2u;
      partials[at] = force;
      partials[at + 1u] = torque;
    }
  }
  if (slot == 0u) {
    partialCount = gl_NumWorkGroups.x * gl_NumWorkGroups.y * gl_NumSubgroups;
  }
}
